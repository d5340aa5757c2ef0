# Writes the code-version module at BUILD time (not only at configure time), so
# that every output file names the commit it was built from:
#   cmake -DSOURCE_DIR=... -DINPUT=... -DOUTPUT=... -DPROJECT_VERSION=... -P airlaunch_version.cmake
# configure_file leaves OUTPUT untouched when the text is unchanged, so an
# unchanged tree recompiles nothing.
execute_process(COMMAND git describe --always --dirty --tags
  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE AIRLAUNCH_GIT
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT AIRLAUNCH_GIT)
  set(AIRLAUNCH_GIT "unknown")
endif()
configure_file(${INPUT} ${OUTPUT} @ONLY)
