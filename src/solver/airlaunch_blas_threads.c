/* One BLAS thread for the whole program (called first thing by the programs in
 * src/app).  Every LAPACK call of airlaunch is on a small matrix (3x3 inertia,
 * Kane and CFA systems, the line's narrow band), where threads never pay; but
 * OpenBLAS starts a worker per core when it is loaded, and the workers spin
 * (sched_yield) while they wait for work: measured, the paper scenario kept 1.7
 * CPUs busy for a one-CPU computation, and under `mpirun -n <cores>` the
 * spinning workers compete with the other ranks.  OpenBLAS's own entry points
 * are weak symbols here: with another BLAS nothing happens.  An explicit
 * OPENBLAS_NUM_THREADS in the environment is the user's choice and is left alone. */
#include <stdlib.h>

extern void openblas_set_num_threads(int) __attribute__((weak));
extern void blas_thread_shutdown_(void) __attribute__((weak));

void airlaunch_one_blas_thread(void) {
  const char *user = getenv("OPENBLAS_NUM_THREADS");
  if (user != NULL && user[0] != '\0') return;
  if (openblas_set_num_threads) openblas_set_num_threads(1);
  /* the workers already started: stop them (OpenBLAS restarts them only for a
     threaded call, and with one thread it makes none) */
  if (blas_thread_shutdown_) blas_thread_shutdown_();
}
