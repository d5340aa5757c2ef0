/* Unbuffered POSIX writes for the sweep's own files (journal rows, the journal's
 * fingerprint, the case namelists), bound to Fortran in airlaunch_sweep_files.
 *
 * gfortran's buffered I/O does not report a full disk: measured on a 16 KiB
 * tmpfs, write, flush(iostat=) and close(iostat=) all returned 0 while the
 * bytes were lost.  Here every byte count that write(2) returns is checked
 * (a short write is continued; -1 is an error), and so is close(2), so a lost
 * byte is an error at once, with the C library's text for errno.
 *
 * Each function returns 0 on success (airlaunch_file_open: the descriptor) and
 * -1 on failure, with a NUL-terminated message in msg[0 .. msglen-1].
 * airlaunch_remove_case_files lists a directory (which Fortran cannot) for
 * --restart. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/types.h>
#include <unistd.h>

static void set_message(char *msg, int msglen, const char *what, int err) {
  const char *text = strerror(err);
  size_t n = 0;
  if (msglen <= 0) return;
  for (const char *p = what; *p != '\0' && n + 1 < (size_t)msglen; ++p) msg[n++] = *p;
  for (const char *p = ": "; *p != '\0' && n + 1 < (size_t)msglen; ++p) msg[n++] = *p;
  for (const char *p = text; *p != '\0' && n + 1 < (size_t)msglen; ++p) msg[n++] = *p;
  msg[n] = '\0';
}

/* Open `path` for writing: appending (O_APPEND: every write goes to the end)
 * or replacing its content (O_TRUNC); created with mode 0644 if missing. */
int airlaunch_file_open(const char *path, int append, char *msg, int msglen) {
  int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (append ? O_APPEND : O_TRUNC);
  int fd;
  do {
    fd = open(path, flags, 0644);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) set_message(msg, msglen, "open", errno);
  return fd < 0 ? -1 : fd;
}

/* Write all n bytes of data, or fail. */
int airlaunch_file_write(int fd, const char *data, long n, char *msg, int msglen) {
  long done = 0;
  while (done < n) {
    ssize_t k = write(fd, data + done, (size_t)(n - done));
    if (k < 0) {
      if (errno == EINTR) continue;
      set_message(msg, msglen, "write", errno);
      return -1;
    }
    if (k == 0) {   /* no progress on a regular file: treat as a full device */
      set_message(msg, msglen, "write", ENOSPC);
      return -1;
    }
    done += (long)k;
  }
  return 0;
}

/* Make a new empty file from `templ`, a path ending in XXXXXX followed by
 * `suffix_len` characters (mkstemps: a unique name, created O_EXCL with mode
 * 0600, so a name in a shared /tmp cannot be a planted symlink); the
 * X's are replaced in place. */
int airlaunch_temp_file(char *templ, int suffix_len, char *msg, int msglen) {
  int fd = mkstemps(templ, suffix_len);
  if (fd < 0) {
    set_message(msg, msglen, "mkstemps", errno);
    return -1;
  }
  close(fd);
  return 0;
}

/* Close fd; its result is checked (NFS reports write errors here). */
int airlaunch_file_close(int fd, char *msg, int msglen) {
  if (close(fd) != 0) {   /* no retry on EINTR: on Linux the descriptor is gone */
    set_message(msg, msglen, "close", errno);
    return -1;
  }
  return 0;
}

/* Remove every case_<digits>.nc and case_<digits>.nc.part of directory `dir`
 * (the kept trajectories of any earlier sweep, whatever its case count).
 * Returns the number of files that could not be removed (0: all gone), -1 if
 * the directory exists but cannot be read; a missing directory is 0. */
static int is_case_file(const char *name) {
  const char *p = name;
  if (strncmp(p, "case_", 5) != 0) return 0;
  p += 5;
  if (*p < '0' || *p > '9') return 0;
  while (*p >= '0' && *p <= '9') ++p;
  return strcmp(p, ".nc") == 0 || strcmp(p, ".nc.part") == 0;
}

int airlaunch_remove_case_files(const char *dir) {
  DIR *d = opendir(dir);
  struct dirent *e;
  int failed = 0;
  size_t n = strlen(dir);
  if (d == NULL) return errno == ENOENT ? 0 : -1;
  while ((e = readdir(d)) != NULL) {
    if (!is_case_file(e->d_name)) continue;
    size_t m = n + 1 + strlen(e->d_name) + 1;
    char *path = malloc(m);
    if (path == NULL) { ++failed; continue; }
    memcpy(path, dir, n);
    path[n] = '/';
    memcpy(path + n + 1, e->d_name, strlen(e->d_name) + 1);
    if (unlink(path) != 0 && errno != ENOENT) ++failed;
    free(path);
  }
  closedir(d);
  return failed;
}

/* Take an exclusive advisory lock (flock) on `path`, created if missing, and
 * keep it for the life of the process (the descriptor stays open).  Returns
 * the descriptor, -2 if another process holds the lock, -1 on another failure
 * (with the reason in msg).  Two airlaunch-sweep runs on one output directory
 * would interleave their journals: the second is refused. */
int airlaunch_lock_file(const char *path, char *msg, int msglen) {
  int fd;
  do {
    fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) {
    set_message(msg, msglen, "open", errno);
    return -1;
  }
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    int err = errno;
    close(fd);
    if (err == EWOULDBLOCK) return -2;
    set_message(msg, msglen, "flock", err);
    return -1;
  }
  return fd;
}
