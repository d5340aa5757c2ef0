# Writes the code-version module at BUILD time (not only at configure time), so
# that every output file names the commit it was built from:
#   cmake -DSOURCE_DIR=... -DINPUT=... -DOUTPUT=... -DPROJECT_VERSION=... [-DBUILD_SETTINGS=...]
#         -P airlaunch_version.cmake
# configure_file leaves OUTPUT untouched when the text is unchanged, so an
# unchanged tree recompiles nothing.
execute_process(COMMAND git describe --always --dirty --tags
  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE AIRLAUNCH_GIT
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT AIRLAUNCH_GIT)
  set(AIRLAUNCH_GIT "unknown")
endif()
# The digest of what the programs compute with, for the sweep's journal (a
# resume mixes rows only of the same code): every file under src/ and cmake/
# and CMakeLists.txt (relative path and SHA-256), and the build's settings
# (BUILD_SETTINGS: build type, compilers, flags, SUNDIALS).  Unlike the git
# description it does not change when a file outside the code is edited (an
# input, a criteria file, the docs: "-dirty") or when the same code is committed.
file(GLOB_RECURSE _airlaunch_code RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/src/* ${SOURCE_DIR}/cmake/*)
list(APPEND _airlaunch_code CMakeLists.txt)
list(SORT _airlaunch_code)
set(_airlaunch_digest_text "${BUILD_SETTINGS}\n${AIRLAUNCH_SUNDIALS}\n")
foreach(_f IN LISTS _airlaunch_code)
  file(SHA256 ${SOURCE_DIR}/${_f} _h)
  string(APPEND _airlaunch_digest_text "${_f} ${_h}\n")
endforeach()
string(SHA256 AIRLAUNCH_CODE_DIGEST "${_airlaunch_digest_text}")
string(SUBSTRING ${AIRLAUNCH_CODE_DIGEST} 0 16 AIRLAUNCH_CODE_DIGEST)
configure_file(${INPUT} ${OUTPUT} @ONLY)
