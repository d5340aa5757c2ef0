!> One BLAS thread for the whole program: see airlaunch_blas_threads.c (OpenBLAS's
!> idle workers spin on the other cores; every LAPACK call here is small).
!> Called first thing by the programs in src/app.
module airlaunch_blas_threads
  implicit none
  private
  public :: use_one_blas_thread

  interface
    !> Stop OpenBLAS's worker threads unless OPENBLAS_NUM_THREADS is set; no-op
    !> with another BLAS.
    subroutine use_one_blas_thread() bind(C, name="airlaunch_one_blas_thread")
      implicit none
    end subroutine use_one_blas_thread
  end interface
end module airlaunch_blas_threads
