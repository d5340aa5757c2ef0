!> Small helpers to format numbers into messages.
module airlaunch_strings
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: str, lower, fixed, escaped

  !> Format a number as a compact string.
  interface str
    module procedure str_real, str_int, str_logical
  end interface str

contains

  !> Real as shortest readable text (general format, trimmed).
  pure function str_real(x) result(s)
    real(dp), intent(in) :: x   !< value
    character(len=:), allocatable :: s
    character(len=32) :: buf
    if (x /= x) then
      s = "NaN"
      return
    end if
    if (x == 0.0_dp .or. (abs(x) >= 1.0e-3_dp .and. abs(x) < 1.0e7_dp)) then
      write(buf, '(f0.9)') x
      s = trim(adjustl(buf))
      ! strip trailing zeros of the fixed-point rendering (1.500000000 -> 1.5)
      do while (len(s) > 1 .and. s(len(s):len(s)) == '0')
        s = s(:len(s)-1)
      end do
      if (s(len(s):len(s)) == '.') s = s // '0'
      if (s(1:1) == '.') s = '0' // s
      if (s(1:2) == '-.') s = '-0' // s(2:)
    else if (abs(x) < 1.0e-99_dp .or. abs(x) >= 1.0e100_dp) then
      ! three exponent digits: es16.8 would drop the E (1.00000000+300)
      write(buf, '(es17.8e3)') x
      s = trim(adjustl(buf))
    else
      write(buf, '(es16.8)') x
      s = trim(adjustl(buf))
    end if
  end function str_real

  !> Real with d digits after the point, a leading zero kept (0.878, -0.5).
  function fixed(x, d) result(s)
    real(dp), intent(in) :: x   !< value
    integer, intent(in) :: d    !< digits after the point
    character(len=:), allocatable :: s
    character(len=40) :: buf, fmt
    write(fmt, '("(f0.",i0,")")') d
    write(buf, fmt) x
    s = trim(adjustl(buf))
    if (s(1:1) == '.') s = '0' // s
    if (len(s) > 1) then
      if (s(1:2) == '-.') s = '-0' // s(2:)
    end if
  end function fixed

  !> Integer as text.
  pure function str_int(i) result(s)
    integer, intent(in) :: i   !< value
    character(len=:), allocatable :: s
    character(len=24) :: buf
    write(buf, '(i0)') i
    s = trim(buf)
  end function str_int

  !> Logical as Fortran namelist text.
  pure function str_logical(l) result(s)
    logical, intent(in) :: l   !< value
    character(len=:), allocatable :: s
    if (l) then
      s = ".true."
    else
      s = ".false."
    end if
  end function str_logical

  !> Lower-case copy of a string (ASCII).
  pure function lower(s) result(t)
    character(len=*), intent(in) :: s   !< text
    character(len=len(s)) :: t
    integer :: i, c
    t = s
    do i = 1, len(s)
      c = iachar(s(i:i))
      if (c >= iachar('A') .and. c <= iachar('Z')) t(i:i) = achar(c + 32)
    end do
  end function lower

  !> The text on one line: each ASCII control character written as \n, \t,
  !> \r or \xHH, so a message naming it stays one line.
  pure function escaped(s) result(t)
    character(len=*), intent(in) :: s   !< text
    character(len=:), allocatable :: t
    character(len=*), parameter :: hex = "0123456789abcdef"
    integer :: i, c
    t = ""
    do i = 1, len(s)
      c = iachar(s(i:i))
      select case (c)
      case (10)
        t = t // "\n"
      case (9)
        t = t // "\t"
      case (13)
        t = t // "\r"
      case (0:8, 11:12, 14:31, 127)
        t = t // "\x" // hex(c/16+1:c/16+1) // hex(mod(c, 16)+1:mod(c, 16)+1)
      case default
        t = t // s(i:i)
      end select
    end do
  end function escaped
end module airlaunch_strings
