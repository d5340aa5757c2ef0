/* Heap-allocation counter for test_rhs_allocations.
 *
 * malloc, calloc and realloc are defined here, in the test executable, and
 * forward to glibc's allocator (__libc_malloc, ...), so every allocation of the
 * process goes through them: the library's own code (airlaunch_lib is static)
 * and the shared libraries it calls, libgfortran included (a matmul result or
 * an array pack made inside libgfortran calls malloc there, which a
 * -Wl,--wrap=malloc of our objects alone would not see).  free stays glibc's:
 * the blocks come from the same allocator.  glibc only. */
#include <stddef.h>
#include <stdint.h>

void *__libc_malloc(size_t size);
void *__libc_calloc(size_t n, size_t size);
void *__libc_realloc(void *p, size_t size);

static int64_t allocations = 0;

void *malloc(size_t size)
{
    __atomic_fetch_add(&allocations, 1, __ATOMIC_RELAXED);
    return __libc_malloc(size);
}

void *calloc(size_t n, size_t size)
{
    __atomic_fetch_add(&allocations, 1, __ATOMIC_RELAXED);
    return __libc_calloc(n, size);
}

void *realloc(void *p, size_t size)
{
    __atomic_fetch_add(&allocations, 1, __ATOMIC_RELAXED);
    return __libc_realloc(p, size);
}

/* Number of malloc, calloc and realloc calls so far (Fortran: bind(C)). */
int64_t airlaunch_test_heap_allocations(void)
{
    return __atomic_load_n(&allocations, __ATOMIC_RELAXED);
}

/* Used as a preloaded library (LD_PRELOAD, tests/python/test_heap_per_step.py):
 * at exit, the count is written to the file named by AIRLAUNCH_HEAP_REPORT.
 * open/write and a stack buffer: the report itself allocates nothing. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

__attribute__((destructor)) static void airlaunch_heap_report(void)
{
    const char *path = getenv("AIRLAUNCH_HEAP_REPORT");
    char text[32];
    int fd, n;
    if (path == NULL || path[0] == '\0') return;
    n = snprintf(text, sizeof text, "%lld\n", (long long)airlaunch_test_heap_allocations());
    fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) return;
    if (write(fd, text, (size_t)n) != n) { /* nothing to do: the test will find no number */ }
    close(fd);
}
