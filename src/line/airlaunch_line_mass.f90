!> The line's mass matrix over its state nodes (airlaunch_line_model, header:
!> "Mass matrix"): M a = f for the accelerations a of the nodes first..last,
!> given the node forces f and the accelerations of the kinematic ends.
!>
!> Per Cartesian component M is the same symmetric tridiagonal matrix (the
!> segment matrices rho l0 [[1/2 - beta, beta], [beta, 1/2 - beta]] assembled,
!> point-mass ends added to their node's diagonal), so it is factored once
!> (LAPACK dpttrf, L D L^T of a symmetric positive definite tridiagonal matrix:
!> diagonally dominant for beta < 1/4) and each right-hand side solves the three
!> components at once (dpttrs, nrhs = 3).  A kinematic end k (fixed,
!> prescribed, body) is not a state: its row is dropped and its column moves
!> to the right-hand side, f_j - M(j, k) a_k for its neighbour j.
!> With beta = 0 (lumped) M is the diagonal and nothing is factored.
module airlaunch_line_mass
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  implicit none
  private
  public :: line_mass_matrix

  !> M over the state nodes first..last of a line of N segments.
  type :: line_mass_matrix
    integer :: first = 0                     !< first state node
    integer :: last = -1                     !< last state node
    real(dp) :: coupling = 0.0_dp            !< M(k, k +- 1) = beta rho l0 [kg] (0: lumped)
    real(dp), allocatable :: diagonal(:)     !< M(k, k), k = 0..N [kg] (point-mass ends included)
    real(dp), allocatable :: built(:)        !< M(k, k) as built, without `set_extra`'s masses [kg]
    real(dp), allocatable :: inv_diagonal(:) !< 1/M(k, k) [1/kg]
    real(dp), allocatable :: d(:), e(:)      !< dpttrf's factors of M over first..last
    real(dp), allocatable :: work(:, :)      !< right-hand sides (nodes, 3)
  contains
    procedure :: build => mass_build
    procedure :: is_lumped => mass_is_lumped
    procedure :: accelerations => mass_accelerations
    procedure :: scaled_coupling => mass_scaled_coupling
    procedure :: set_extra => mass_set_extra
  end type line_mass_matrix

  interface
    subroutine dpttrf(n, d, e, info)
      import :: dp
      implicit none
      integer, intent(in) :: n
      real(dp), intent(inout) :: d(*), e(*)
      integer, intent(out) :: info
    end subroutine dpttrf
    subroutine dpttrs(n, nrhs, d, e, b, ldb, info)
      import :: dp
      implicit none
      integer, intent(in) :: n, nrhs, ldb
      real(dp), intent(in) :: d(*), e(*)
      real(dp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dpttrs
  end interface

contains

  !> Assemble and factor M for the state nodes first..last: `node_mass` the
  !> lumped node masses (0:N) with the point-mass ends added, `segment_mass`
  !> rho l0, `beta` the coupling fraction.
  subroutine mass_build(self, node_mass, segment_mass, beta, first, last, error)
    class(line_mass_matrix), intent(inout) :: self         !< the matrix (re-initialised)
    real(dp), intent(in) :: node_mass(0:)                  !< lumped node masses, ends' bodies included [kg]
    real(dp), intent(in) :: segment_mass                   !< rho l0 [kg]
    real(dp), intent(in) :: beta                           !< coupling fraction (0: lumped)
    integer, intent(in) :: first, last                     !< state nodes
    type(error_type), allocatable, intent(inout) :: error  !< set if M is not positive definite
    integer :: m, info
    self%first = first
    self%last = last
    self%coupling = beta*segment_mass
    if (allocated(self%diagonal)) deallocate(self%diagonal, self%built, self%inv_diagonal, self%d, self%e, self%work)
    m = max(0, last - first + 1)
    allocate(self%diagonal(0:size(node_mass) - 1), self%built(0:size(node_mass) - 1), self%inv_diagonal(0:size(node_mass) - 1), self%d(m), &
      self%e(max(m - 1, 1)), self%work(max(m, 1), 3))
    ! each segment moves beta rho l0 from each end's diagonal to the coupling
    self%diagonal = node_mass - 2.0_dp*self%coupling
    self%diagonal(0) = self%diagonal(0) + self%coupling
    self%diagonal(ubound(node_mass, 1)) = self%diagonal(ubound(node_mass, 1)) + self%coupling
    self%built = self%diagonal
    self%inv_diagonal = 1.0_dp/self%diagonal
    call factor(self, info)
    if (info /= 0) call fatal_error(error, "line: the mixed mass matrix is not positive definite (LAPACK " // &
      "dpttrf info = " // str(info) // ")")
  end subroutine mass_build

  !> Node k's diagonal entry becomes its built one plus `extra` [kg] (a
  !> canopy's apparent mass, which changes with time), refactored if mixed.
  !> Adding mass keeps M positive definite.  No allocation.
  subroutine mass_set_extra(self, k, extra)
    class(line_mass_matrix), intent(inout) :: self   !< the matrix
    integer, intent(in) :: k                         !< node
    real(dp), intent(in) :: extra                    !< added mass, >= 0 [kg]
    integer :: info
    if (self%diagonal(k) == self%built(k) + extra) return
    self%diagonal(k) = self%built(k) + extra
    self%inv_diagonal(k) = 1.0_dp/self%diagonal(k)
    if (k >= self%first .and. k <= self%last) call factor(self, info)
  end subroutine mass_set_extra

  !> L D L^T of M over the state nodes (LAPACK dpttrf); nothing for the lumped
  !> matrix.  info from dpttrf (0: factored).
  subroutine factor(self, info)
    type(line_mass_matrix), intent(inout) :: self   !< the matrix
    integer, intent(out) :: info                    !< dpttrf's
    integer :: k, m
    info = 0
    m = max(0, self%last - self%first + 1)
    if (self%is_lumped() .or. m == 0) return
    do k = self%first, self%last
      self%d(k - self%first + 1) = self%diagonal(k)
    end do
    self%e = self%coupling
    call dpttrf(m, self%d, self%e, info)
  end subroutine factor

  !> True for the diagonal (lumped) matrix.
  pure logical function mass_is_lumped(self)
    class(line_mass_matrix), intent(in) :: self   !< the matrix
    mass_is_lumped = self%coupling == 0.0_dp
  end function mass_is_lumped

  !> Accelerations a(:, first..last) from M a = f, with the kinematic ends'
  !> accelerations a_start (node first - 1) and a_end (node last + 1) where
  !> those are ends of the line.  No allocation.
  subroutine mass_accelerations(self, f, a_start, a_end, a)
    class(line_mass_matrix), intent(inout) :: self   !< the matrix
    real(dp), intent(in) :: f(:, 0:)                 !< node forces (3, 0:N) [N]
    real(dp), intent(in) :: a_start(3), a_end(3)     !< kinematic end accelerations [m/s^2]
    real(dp), intent(inout) :: a(:, 0:)              !< accelerations (3, 0:N), first..last set [m/s^2]
    integer :: k, m, info
    if (self%is_lumped()) then
      do k = self%first, self%last
        a(:, k) = f(:, k)*self%inv_diagonal(k)
      end do
      return
    end if
    m = self%last - self%first + 1
    if (m < 1) return   ! one segment between two kinematic ends: no state node
    do k = self%first, self%last
      self%work(k - self%first + 1, :) = f(:, k)
    end do
    if (self%first > 0) self%work(1, :) = self%work(1, :) - self%coupling*a_start
    if (self%last < ubound(f, 2)) self%work(m, :) = self%work(m, :) - self%coupling*a_end
    call dpttrs(m, 3, self%d, self%e, self%work, size(self%work, 1), info)
    do k = self%first, self%last
      a(:, k) = self%work(k - self%first + 1, :)
    end do
  end subroutine mass_accelerations

  !> M(k, k + d)/M(k, k) for d = -1, 1 between state nodes (0 towards a kinematic
  !> end): the off-diagonal of M with its rows scaled by their diagonals, as the
  !> velocity-reduced Newton solve uses it.
  pure real(dp) function mass_scaled_coupling(self, k, d) result(c)
    class(line_mass_matrix), intent(in) :: self   !< the matrix
    integer, intent(in) :: k, d                   !< node, neighbour offset (-1 or 1)
    c = 0.0_dp
    if (k + d < self%first .or. k + d > self%last) return
    c = self%coupling/self%diagonal(k)
  end function mass_scaled_coupling
end module airlaunch_line_mass
