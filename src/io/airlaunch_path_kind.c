/* What a path names, for the output file's checks before a run
 * (airlaunch_run_config: require_output_directory), which Fortran's inquire
 * cannot tell: a regular file, a directory, or something else (a device, a
 * FIFO, a socket), and whether two paths name the same file; the free space
 * of its file system; and an exclusive lock on a file, so that two runs never
 * write one output at once. */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <sys/types.h>
#include <unistd.h>

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

/* Free bytes for an unprivileged user on the file system that holds `path`
 * (a file or a directory), or -1 if it cannot be told. */
double airlaunch_free_bytes(const char *path) {
  struct statvfs vfs;
  if (statvfs(path, &vfs) != 0) return -1.0;
  return (double)vfs.f_bavail * (double)vfs.f_frsize;
}

/* The process's file size limit (ulimit -f, RLIMIT_FSIZE's soft limit) in
 * bytes, or -1 if there is none. */
double airlaunch_file_size_limit(void) {
  struct rlimit lim;
  if (getrlimit(RLIMIT_FSIZE, &lim) != 0 || lim.rlim_cur == RLIM_INFINITY) return -1.0;
  return (double)lim.rlim_cur;
}

/* An exclusive lock on the file `path` (created if missing), held through the
 * returned descriptor until airlaunch_release_output_lock: an open-file-description
 * lock (F_OFD_SETLK; a process-owned F_SETLK where that is not supported),
 * which the process's death releases.  Returns the descriptor, -1 if another
 * open file holds the lock, -2 if the lock cannot be had (no such file can be
 * made, or the file system has no locks).  A file replaced between its open
 * and its lock (another process released and removed it) is locked anew. */
int airlaunch_lock_output(const char *path) {
  for (int tries = 0; tries < 5; ++tries) {
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) return -2;
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
#ifdef F_OFD_SETLK
    int rc = fcntl(fd, F_OFD_SETLK, &fl);
    if (rc != 0 && errno == EINVAL) rc = fcntl(fd, F_SETLK, &fl);
#else
    int rc = fcntl(fd, F_SETLK, &fl);
#endif
    if (rc != 0) {
      int busy = errno == EAGAIN || errno == EACCES;
      close(fd);
      return busy ? -1 : -2;
    }
    struct stat held, now;
    if (fstat(fd, &held) == 0 && stat(path, &now) == 0 && held.st_dev == now.st_dev && held.st_ino == now.st_ino)
      return fd;
    close(fd);
  }
  return -2;
}

/* Remove the lock file `path` and release its lock (fd from airlaunch_lock_output). */
void airlaunch_release_output_lock(const char *path, int fd) {
  if (fd < 0) return;
  unlink(path);
  close(fd);
}

/* Past the process's file size limit (ulimit -f) a write fails with EFBIG
 * instead of killing the process with SIGXFSZ: the writer then reports it
 * like any failed write. */
void airlaunch_ignore_file_size_signal(void) { signal(SIGXFSZ, SIG_IGN); }
