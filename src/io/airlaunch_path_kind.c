/* What a path names, for the output file's checks before a run
 * (airlaunch_run_config: require_output_directory), which Fortran's inquire
 * cannot tell: a regular file, a directory, or something else (a device, a
 * FIFO, a socket), and whether two paths name the same file. */
#include <sys/stat.h>
#include <sys/types.h>

/* 0: nothing there (or not reachable), 1: a regular file, 2: a directory,
 * 3: anything else; symbolic links are followed. */
int airlaunch_path_kind(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) return 0;
  if (S_ISREG(st.st_mode)) return 1;
  if (S_ISDIR(st.st_mode)) return 2;
  return 3;
}

/* 1 if both paths exist and name the same file (device and inode), else 0. */
int airlaunch_same_file(const char *a, const char *b) {
  struct stat sa, sb;
  if (stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}
