/* The runtime numerical environment (airlaunch_runtime_env.f90): what the
 * process computes with beyond the build (code_digest names that), read when
 * asked, never during an integration.
 *
 * The same build gives different bits on different machines because its
 * libraries choose their code by the processor at run time: OpenBLAS picks a
 * kernel (OPENBLAS_CORETYPE overrides it), glibc's libm picks FMA variants of
 * exp, log, pow, sin, cos when FMA and AVX2 are usable (GLIBC_TUNABLES
 * glibc.cpu.hwcaps masks them), libgfortran's MATMUL picks an AVX-512, AVX2,
 * AVX or FMA3 kernel by vendor and features (no switch).  docs/output.md,
 * "Runtime numerical environment", and docs/validation.md, "Reproducing a
 * result across machines", say what each changes.
 *
 * OpenBLAS's entry points and LAPACK's ilaver are weak symbols: with another
 * BLAS (the reference one, -DBLA_VENDOR=Generic) they are absent and the
 * answer is "unknown"; the build never depends on them. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif
#if defined(__x86_64__) && defined(__has_include)
#if __has_include(<sys/platform/x86.h>)
#include <sys/platform/x86.h>
#define AIRLAUNCH_GLIBC_X86 1
#endif
#endif

extern char *openblas_get_corename(void) __attribute__((weak));
extern char *openblas_get_config(void) __attribute__((weak));
extern void ilaver_(int *major, int *minor, int *patch) __attribute__((weak));
/* the BLAS and LAPACK routines whose library is named (the LU of the Kane,
   CFA and line systems calls both) */
extern void dgemm_(void) __attribute__((weak));
extern void dgetrf_(void) __attribute__((weak));
/* sundials_version.h (SUNDIALS >= 3; declared here: the project does not put
   SUNDIALS's C headers on the include path) */
int SUNDIALSGetVersion(char *version, int len);

static void copy_out(const char *text, char *buf, int len) {
  if (len <= 0) return;
  snprintf(buf, (size_t)len, "%s", text != NULL ? text : "");
}

/* The file of the shared object that holds `address` (symbolic links
   resolved: /usr/lib/x86_64-linux-gnu/libopenblas.so.0 is a chain of Debian's
   alternatives); "unknown" for none. */
static void object_of(void (*address)(void), char *buf, int len) {
  Dl_info info;
  char real[PATH_MAX];
  if (address == NULL || dladdr((void *)address, &info) == 0 || info.dli_fname == NULL ||
      info.dli_fname[0] == '\0') {
    copy_out("unknown", buf, len);
    return;
  }
  copy_out(realpath(info.dli_fname, real) != NULL ? real : info.dli_fname, buf, len);
}

/* OpenBLAS's query `name` ("openblas_get_corename", "openblas_get_config")
   if OpenBLAS computes the BLAS: looked up in the library that provides
   dgemm_ and the libraries it depends on (Debian's openblas-pthread/libblas.so.3,
   which a -DBLA_VENDOR=Generic build links through the alternatives, is an
   interface to libopenblas.so.0's kernels); NULL for another BLAS, also when
   OpenBLAS is loaded but an LD_PRELOADed reference BLAS provides dgemm_.  A
   BLAS linked into the program (no library to open): the weak symbol, if
   OpenBLAS's is linked in with it. */
typedef char *(*openblas_query)(void);
static openblas_query openblas_entry(const char *name) {
  Dl_info blas;
  void *handle;
  openblas_query entry = NULL;
  if (dgemm_ == NULL || dladdr((void *)dgemm_, &blas) == 0 || blas.dli_fname == NULL) return NULL;
  handle = dlopen(blas.dli_fname, RTLD_LAZY | RTLD_NOLOAD);
  if (handle != NULL) {
    *(void **)&entry = dlsym(handle, name);
    dlclose(handle);
    return entry;
  }
  if (openblas_get_corename == NULL || openblas_get_config == NULL) return NULL;
  {
    Dl_info ob;
    if (dladdr((void *)openblas_get_corename, &ob) == 0 || ob.dli_fbase != blas.dli_fbase) return NULL;
  }
  return strcmp(name, "openblas_get_corename") == 0 ? openblas_get_corename : openblas_get_config;
}

static void env_blas_library(char *buf, int len) { object_of(dgemm_, buf, len); }

static void env_lapack_library(char *buf, int len) { object_of(dgetrf_, buf, len); }

static void env_blas_core(char *buf, int len) {
  openblas_query entry = openblas_entry("openblas_get_corename");
  copy_out(entry != NULL ? entry() : "unknown", buf, len);
}

static void env_blas_config(char *buf, int len) {
  openblas_query entry = openblas_entry("openblas_get_config");
  copy_out(entry != NULL ? entry() : "unknown", buf, len);
}

static void env_lapack_version(char *buf, int len) {
  int major = 0, minor = 0, patch = 0;
  char text[64];
  if (ilaver_ == NULL) {
    copy_out("unknown", buf, len);
    return;
  }
  ilaver_(&major, &minor, &patch);
  snprintf(text, sizeof text, "%d.%d.%d", major, minor, patch);
  copy_out(text, buf, len);
}

static void env_sundials_version(char *buf, int len) {
  char text[64];
  if (SUNDIALSGetVersion(text, (int)sizeof text) != 0) {
    copy_out("unknown", buf, len);
    return;
  }
  copy_out(text, buf, len);
}

/* The first "model name" of /proc/cpuinfo (x86 and some ARM kernels write
   it); "unknown" without it.  Read to that line only. */
static void env_cpu_model(char *buf, int len) {
  FILE *f = fopen("/proc/cpuinfo", "r");
  char line[512];
  copy_out("unknown", buf, len);
  if (f == NULL) return;
  while (fgets(line, sizeof line, f) != NULL) {
    char *colon;
    size_t n;
    if (strncmp(line, "model name", 10) != 0) continue;
    colon = strchr(line, ':');
    if (colon == NULL) continue;
    colon++;
    while (*colon == ' ' || *colon == '\t') colon++;
    n = strlen(colon);
    while (n > 0 && (colon[n - 1] == '\n' || colon[n - 1] == ' ')) colon[--n] = '\0';
    if (n > 0) copy_out(colon, buf, len);
    break;
  }
  fclose(f);
}

/* The processor's vendor and the features by which libgfortran's MATMUL (and
   OpenBLAS, unless forced) choose their code: "AMD avx512f avx2 fma avx
   sse4_2"; "unknown" off x86-64. */
static void env_cpu_features(char *buf, int len) {
#if defined(__x86_64__) && defined(__GNUC__)
  char text[160];
  __builtin_cpu_init();
  snprintf(text, sizeof text, "%s%s%s%s%s%s%s",
           __builtin_cpu_is("intel") ? "Intel" : (__builtin_cpu_is("amd") ? "AMD" : "other"),
           __builtin_cpu_supports("avx512f") ? " avx512f" : "",
           __builtin_cpu_supports("avx2") ? " avx2" : "",
           __builtin_cpu_supports("fma") ? " fma" : "",
           __builtin_cpu_supports("fma4") ? " fma4" : "",
           __builtin_cpu_supports("avx") ? " avx" : "",
           __builtin_cpu_supports("sse4.2") ? " sse4_2" : "");
  copy_out(text, buf, len);
#else
  copy_out("unknown", buf, len);
#endif
}

/* The C library and the x86 features it reports usable, by which glibc's
   libm selects the variants of its functions (FMA ones with FMA and AVX2;
   FMA4, AVX or SSE2 ones otherwise): "glibc 2.36 (usable: fma avx2 avx)".
   GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA removes the first two (and
   changes the paper scenario's bits: docs/validation.md). */
static void env_libm(char *buf, int len) {
  char text[160];
#if defined(__GLIBC__)
  snprintf(text, sizeof text, "glibc %s", gnu_get_libc_version());
#else
  snprintf(text, sizeof text, "unknown C library");
#endif
#if defined(AIRLAUNCH_GLIBC_X86)
  {
    size_t n = strlen(text);
    snprintf(text + n, sizeof text - n, " (usable:%s%s%s%s)",
             CPU_FEATURE_ACTIVE(FMA) ? " fma" : "", CPU_FEATURE_ACTIVE(AVX2) ? " avx2" : "",
             CPU_FEATURE_ACTIVE(FMA4) ? " fma4" : "", CPU_FEATURE_ACTIVE(AVX) ? " avx" : "");
  }
#endif
  copy_out(text, buf, len);
}

/* The one entry point of the Fortran side (airlaunch_runtime_env's
   query_runtime_env): value `which` of its env_names, 1 cpu_model ...
   9 sundials_version, into buf(1:len), NUL-ended ("unknown" for another). */
void airlaunch_env_query(int which, char *buf, int len) {
  typedef void (*query)(char *, int);
  static const query queries[] = {env_cpu_model,      env_cpu_features,   env_blas_library,
                                  env_blas_core,      env_blas_config,    env_lapack_library,
                                  env_lapack_version, env_libm,           env_sundials_version};
  if (which < 1 || which > (int)(sizeof queries / sizeof queries[0])) {
    copy_out("unknown", buf, len);
    return;
  }
  queries[which - 1](buf, len);
}
