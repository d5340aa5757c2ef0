!> Constraint force algorithm (CFA) of Zheng & Zhang 2018, §3.3 Steps 1-4, with
!> Coulomb friction on the slide component.
!>
!> The caller has probed the dynamics: with the cut-joint wrench R_H = 0 the
!> constraint rows give beta (Step 1); with each unit component the rows change by
!> the columns of alpha (Step 2: column = c(e_i) - c(0), the accelerations being
!> affine in R_H).  Step 3: R_H = -alpha^{-1} beta, by an LU solve (solve_general),
!> never an explicit inverse.  Step 4 (the other cut joints) does not arise: the
!> rocket-aircraft joint is the only cut joint; the chain joints are inside Kane's
!> equations.
!>
!> Components 2.. are always constrained.  Component 1 (the slide) is
!>   slide_locked  - constrained too (Case 0, or the no-slip edge);
!>   slide_free    - frictionless: lambda_1 = 0;
!>   slide_coulomb - Coulomb friction |lambda_1| <= mu |N|, N = (lambda_2, lambda_3)
!>                   the resultant of the normal and lateral reactions, with the
!>                   Karnopp stick band: if |slide rate| < v_stick, first try to stick
!>                   (row 1 constrained, its bias holding the velocity damping so the
!>                   slide rate decays to zero); keep it if |lambda_1| <= mu |N|, else
!>                   slip with the friction against the impending motion,
!>                   lambda_1 = sign(lambda_1,stick) mu |N|.  Outside the band
!>                   lambda_1 = -sign(slide rate) mu |N|.  The model is continuous when
!>                   a rocket starting at rest breaks away (the usual case: friction is
!>                   then kinetic from the first instant, as in the analytic solution)
!>                   and when sticking ends.  |N| makes the problem nonlinear: the
!>                   direction n = N/|N| is iterated (fixed point, at most `max_iter`),
!>                   each iterate a linear solve with lambda_1 = sigma mu n.N.  No
!>                   convergence means no consistent contact force (Painleve paradox:
!>                   mu too large for the contact geometry) and is an error.
module airlaunch_cfa
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_linalg, only: solve_general
  implicit none
  private
  public :: cfa_workspace, cfa_solve, slide_locked, slide_free, slide_coulomb

  integer, parameter :: slide_locked = 0   !< component 1 constrained
  integer, parameter :: slide_free = 1     !< component 1 zero
  integer, parameter :: slide_coulomb = 2  !< component 1 Coulomb friction

  !> Maximum fixed-point iterations on the normal-force direction.
  integer, parameter :: max_iter = 50

  !> A square system of one size, preallocated.
  type :: square_system
    real(dp), allocatable :: a(:, :), b(:, :)
  end type square_system

  !> Work arrays of every size up to 6 (no allocation while solving).
  type :: cfa_workspace
    type(square_system) :: sys(6)
  contains
    procedure :: init => workspace_init
  end type cfa_workspace

contains

  !> Allocate the work arrays.
  subroutine workspace_init(self)
    class(cfa_workspace), intent(inout) :: self   !< workspace
    integer :: m
    do m = 1, 6
      if (allocated(self%sys(m)%a)) deallocate(self%sys(m)%a, self%sys(m)%b)
      allocate(self%sys(m)%a(m, m), self%sys(m)%b(m, 1))
    end do
  end subroutine workspace_init

  !> Solve the CFA for the constraint-wrench amplitudes lambda (Step 3).
  subroutine cfa_solve(ws, alpha, beta, n, mode, mu, slide_rate, stick_velocity, lambda, stick, error)
    class(cfa_workspace), intent(inout) :: ws             !< work arrays
    real(dp), intent(in) :: alpha(:, :)                   !< (>=n, >=n) row response to unit components
    real(dp), intent(in) :: beta(:)                       !< (>=n) rows with R_H = 0
    integer, intent(in) :: n                              !< number of components (>= 3 with friction)
    integer, intent(in) :: mode                           !< slide_locked | slide_free | slide_coulomb
    real(dp), intent(in) :: mu                            !< friction coefficient
    real(dp), intent(in) :: slide_rate                    !< relative sliding velocity [m/s]
    real(dp), intent(in) :: stick_velocity                !< Karnopp band half-width [m/s]
    real(dp), intent(out) :: lambda(:)                    !< (>=n) amplitudes
    logical, intent(out) :: stick                         !< the slide sticks
    type(error_type), allocatable, intent(inout) :: error !< set if unsolvable
    real(dp) :: sigma, nn(2), nhat(2), nnew(2), nmag
    integer :: it
    lambda = 0.0_dp
    stick = .false.
    if (n == 0) return
    if (mode == slide_locked .or. (mode == slide_coulomb .and. abs(slide_rate) < stick_velocity)) then
      call solve_all(ws, alpha, beta, n, lambda, error)
      if (allocated(error) .or. mode == slide_locked) then
        stick = .not. allocated(error)
        return
      end if
      if (abs(lambda(1)) <= mu*hypot(lambda(2), lambda(3))) then
        stick = .true.
        return
      end if
      sigma = sign(1.0_dp, lambda(1))
    else
      sigma = -sign(1.0_dp, slide_rate)
    end if
    ! frictionless solution (slide_free, or the start of the friction iteration)
    call solve_reduced(ws, alpha, beta, n, 0.0_dp, [0.0_dp, 0.0_dp], lambda, error)
    if (allocated(error) .or. mode == slide_free .or. mu == 0.0_dp) return
    nn = lambda(2:3)
    nmag = norm2(nn)
    if (nmag == 0.0_dp) return
    nhat = nn/nmag
    do it = 1, max_iter
      call solve_reduced(ws, alpha, beta, n, sigma*mu, nhat, lambda, error)
      if (allocated(error)) return
      nn = lambda(2:3)
      nmag = norm2(nn)
      if (nmag == 0.0_dp) then
        lambda(1) = 0.0_dp
        return
      end if
      nnew = nn/nmag
      if (norm2(nnew - nhat) <= 1.0e-12_dp) then
        lambda(1) = sigma*mu*nmag
        return
      end if
      nhat = nnew
    end do
    call fatal_error(error, "CFA: no consistent contact force with Coulomb friction mu = " // str(mu) // &
      " (the normal force keeps reversing: Painleve paradox, friction too large for this contact)")
  end subroutine cfa_solve

  !> All n components constrained: alpha lambda = -beta.
  subroutine solve_all(ws, alpha, beta, n, lambda, error)
    class(cfa_workspace), intent(inout) :: ws
    real(dp), intent(in) :: alpha(:, :), beta(:)
    integer, intent(in) :: n
    real(dp), intent(inout) :: lambda(:)
    type(error_type), allocatable, intent(inout) :: error
    ws%sys(n)%a = alpha(1:n, 1:n)
    ws%sys(n)%b(:, 1) = -beta(1:n)
    call solve_general(ws%sys(n)%a, ws%sys(n)%b, error, "CFA matrix alpha (Eqs. (43), (68))", &
      estimate_condition=.false.)
    if (allocated(error)) return
    lambda(1:n) = ws%sys(n)%b(:, 1)
  end subroutine solve_all

  !> Components 2..n constrained, lambda_1 = k * (nhat . lambda(2:3)).
  subroutine solve_reduced(ws, alpha, beta, n, k, nhat, lambda, error)
    class(cfa_workspace), intent(inout) :: ws
    real(dp), intent(in) :: alpha(:, :), beta(:)
    integer, intent(in) :: n
    real(dp), intent(in) :: k, nhat(2)
    real(dp), intent(inout) :: lambda(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: m
    m = n - 1
    ws%sys(m)%a = alpha(2:n, 2:n)
    ws%sys(m)%a(:, 1) = ws%sys(m)%a(:, 1) + k*nhat(1)*alpha(2:n, 1)
    ws%sys(m)%a(:, 2) = ws%sys(m)%a(:, 2) + k*nhat(2)*alpha(2:n, 1)
    ws%sys(m)%b(:, 1) = -beta(2:n)
    call solve_general(ws%sys(m)%a, ws%sys(m)%b, error, "CFA matrix alpha (Eqs. (43), (68))", &
      estimate_condition=.false.)
    if (allocated(error)) return
    lambda(2:n) = ws%sys(m)%b(:, 1)
    lambda(1) = k*dot_product(nhat, lambda(2:3))
  end subroutine solve_reduced
end module airlaunch_cfa
