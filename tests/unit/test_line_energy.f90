!> Validation 4 (issue 3): energy.  With damping and air off, a line (N = 10,
!> 2 m, 0.1 kg, EA = 1e4 N) fixed at one end and carrying a 1 kg point mass at
!> the other is released from rest at 40 deg (pre-stretched by the static
!> tension) and swings under gravity for 20 s (about 7 periods).  The tension
!> stays positive, the axial and transverse modes of the line, excited by the
!> release, are undamped.  Kinetic + elastic + gravitational energy of the
!> semi-discrete system is an exact invariant; the integrator must keep it to
!> its tolerance:
!>  - the largest drift over 20 s, relative to the energy scale M g L, must be
!>    below rtol (at rtol = 1e-7 and 1e-9; CVODE controls the local error, so
!>    the energy error is a small multiple of rtol times the energy scale per
!>    unit of time unless the error cancels, which it largely does here);
!>  - it must fall with the tolerance: 100-fold tighter, at least 10-fold smaller.
!> Both mass matrices (lumped, and mixed with its kinetic energy 1/2 v^T M v: a
!> wrong energy or a wrong M a = f would show as a drift that does not fall
!> with the tolerance).
program test_line_energy
  use airlaunch_kinds, only: dp, g0, deg2rad
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_line_scene
  use testing
  implicit none
  real(dp), parameter :: length = 2.0_dp, mass = 1.0_dp, ea = 1.0e4_dp, rho = 0.05_dp
  real(dp) :: drift_loose, drift_tight, scale
  character(len=6), parameter :: masses(2) = ["lumped", "mixed "]
  integer :: im

  scale = mass*g0*length
  do im = 1, 2
    call section("energy conservation, CVODE BDF band, " // trim(masses(im)) // " mass, 20 s, energy scale " // &
      "M g L = " // str(scale) // " J")
    drift_loose = drift(1.0e-7_dp, masses(im))
    drift_tight = drift(1.0e-9_dp, masses(im))
    call check(drift_loose < 1.0e-7_dp*scale, "rtol 1e-7: max |E - E0| = " // str(drift_loose) // &
      " J < rtol M g L = " // str(1.0e-7_dp*scale) // " J")
    call check(drift_tight < 1.0e-9_dp*scale, "rtol 1e-9: max |E - E0| = " // str(drift_tight) // &
      " J < rtol M g L = " // str(1.0e-9_dp*scale) // " J")
    call check(drift_tight < 0.1_dp*drift_loose, "drift falls with the tolerance: " // str(drift_loose) // &
      " J (rtol 1e-7) -> " // str(drift_tight) // " J (rtol 1e-9)")
  end do
  call finish()

contains

  !> Largest |E(t) - E(0)| over the run at relative tolerance rtol.
  real(dp) function drift(rtol, mass_matrix) result(d)
    real(dp), intent(in) :: rtol
    character(len=*), intent(in) :: mass_matrix
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(error_type), allocatable :: error
    real(dp) :: e0, tmin, th
    integer :: i
    th = 40.0_dp*deg2rad
    cfg%line = line_params(length=length, n_seg=10, ea=ea, mass_per_length=rho, damping=0.0_dp, &
      gravity=.true., air=.false., mass=mass_matrix)
    cfg%end_a = line_end(kind=end_fixed, position=[0.0_dp, 0.0_dp, 0.0_dp])
    cfg%end_b = line_end(kind=end_point_mass, mass=mass, &
      position=length*(1 + mass*g0*cos(th)/ea)*[sin(th), -cos(th), 0.0_dp])
    cfg%integration%rtol = rtol
    cfg%integration%atol = 1.0e-2_dp*rtol
    cfg%integration%max_order = 5   ! tight tolerance: the steps resolve the line's oscillations
    cfg%t_end = 20.0_dp
    cfg%output_interval = 0.01_dp
    cfg%record_nodes = .false.
    call scene%init(cfg, error)
    call scene%run(error)
    call check(.not. allocated(error), "run, rtol = " // str(rtol))
    if (allocated(error)) print '(a)', error%message
    e0 = sum(scene%energy(:, 1))
    d = 0
    tmin = huge(1.0_dp)
    do i = 1, scene%n_out
      d = max(d, abs(sum(scene%energy(:, i)) - e0))
      tmin = min(tmin, minval(scene%end_tension(:, i)))
    end do
    print '(a, es8.1, a, es10.3, a, i0, a, f7.3, a, es10.3, a)', "  rtol ", rtol, ": max |E - E0| = ", d, &
      " J; steps ", scene%stats%steps, ", wall ", scene%wall_time, " s; smallest end tension ", tmin, " N"
    call scene%free()
  end function drift
end program test_line_energy
