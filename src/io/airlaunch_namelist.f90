!> Namelist input with validation that names file, group, variable, value and
!> what is allowed, in one line.
!>
!> The Fortran runtime reads the values (`read(unit, nml=...)`); before that,
!> `nml_file%load` scans the text itself so that unknown groups and misspelled
!> variables are reported by name (the runtime's own messages do not name
!> them), and `diagnose` finds which value of a group failed to read.
!> Group readers (one per scene concept, e.g. src/scene/airlaunch_drop_scene.f90)
!> follow the pattern: set defaults; `call f%check_group(...)`; `call
!> f%position(group, unit, present)`; `read(unit, nml=...)`; on failure `call
!> f%diagnose(...)`; then range checks with `require_*`.
module airlaunch_namelist
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str, lower
  use airlaunch_path, only: path_kind, kind_other
  implicit none
  private
  public :: nml_file, nml_var, nml_assignment, unset_real, unset_int
  public :: require_positive, require_nonnegative, require_range, require_choice, require_set
  public :: require_int_range, edit_distance

  !> Sentinel of a required real/integer value that the file did not set.
  real(dp), parameter :: unset_real = -huge(1.0_dp)
  integer, parameter :: unset_int = -huge(1)

  !> One `name = value` assignment found in the file.
  type :: nml_assignment
    character(len=:), allocatable :: group   !< lower-case group name
    character(len=:), allocatable :: name    !< lower-case variable name (without index)
    character(len=:), allocatable :: index   !< lower-case index without blanks, "(2)", or ""
    character(len=:), allocatable :: value   !< value text as written
    integer :: line = 0                      !< line of the file
    integer :: group_number = 0              !< which group of the file (1, 2, ...) holds it
    !> where it is written: line and column of the name's first character and of
    !> the value's last (its trailing comma included)
    integer :: first_line = 0, first_col = 0, last_line = 0, last_col = 0
  end type nml_assignment

  !> Expected name and type of a variable, for diagnosis: kind is one of
  !> "real", "integer", "logical", "string", "real_list", "real3" (a vector of
  !> exactly three reals when assigned whole: `v = 1.0, 2.0, 3.0` or `v = 3*0.0`;
  !> elements one by one, `v(2) = 1.0`, stay allowed), "real_array" (an array
  !> of reals whose length its reader checks, assigned whole or by elements
  !> in any order: a list's values, not a scalar's, without a list's order rule).
  type :: nml_var
    character(len=32) :: name = ""
    character(len=16) :: kind = "real"
    !> "string": the most characters the reader's variable holds (0: not
    !> checked); longer values are an error, not cut off.  "real_array": the
    !> most elements an assignment by index may set (0: not checked; "real3":
    !> 3 always)
    integer :: length = 0
  end type nml_var

  !> Most values of a list variable ("real_list", "integer_list") a reader holds.
  integer, parameter, public :: max_list_items = 4096
  !> Largest file read as a namelist [bytes] (the paper scenario: 5.6 kB)
  integer, parameter :: max_file_size = 16*1024*1024
  !> value_class: what the values of a real list read as
  integer, parameter :: normal_values = 0, subnormal = 1, not_finite = 2
  !> element_span: an index it cannot read (not a number, not k:m)
  integer, parameter :: unknown_element = -huge(1)

  !> A scanned namelist file.
  type :: nml_file
    character(len=:), allocatable :: path
    type(nml_assignment), allocatable :: items(:)
    character(len=32), allocatable :: groups(:)   !< groups present (lower case)
    integer, allocatable :: group_lines(:)
    !> The file's last line has no newline: gfortran's namelist read then meets
    !> the end of the file at the last group's '/' (iostat = -1, "End of
    !> file", values read); `position` gives the runtime a terminated copy.
    logical :: unterminated = .false.
    integer :: nlines = 0   !< lines of the file
  contains
    procedure :: load => nml_load
    procedure :: check_groups => nml_check_groups
    procedure :: check_group => nml_check_group
    procedure :: has_group => nml_has_group
    procedure :: is_set => nml_is_set
    procedure :: position => nml_position
    procedure :: open_text => nml_open_text
    procedure :: diagnose => nml_diagnose
    procedure :: where => nml_where
  end type nml_file

contains

  !> Read and scan `path`.  A missing or unreadable file, an unterminated
  !> group or an unterminated string is an error.
  subroutine nml_load(self, path, error)
    class(nml_file), intent(inout) :: self
    character(len=*), intent(in) :: path                  !< file to read
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: unit, ios, lineno, k, nchar, pos, lt
    character(len=:), allocatable :: buf, text
    integer, allocatable :: line_of(:), col_of(:)
    logical :: exists, is_dir
    integer(i8) :: nbytes
    character(len=*), parameter :: no_group = ": no namelist group in the file (a group starts with &name " // &
      "and ends with /, e.g. &run ... /)"

    self%path = path
    if (allocated(self%items)) deallocate(self%items)
    if (allocated(self%groups)) deallocate(self%groups)
    if (allocated(self%group_lines)) deallocate(self%group_lines)
    allocate(self%items(0), self%groups(0), self%group_lines(0))
    inquire(file=path, exist=exists)
    if (.not. exists) then
      call fatal_error(error, path // ": file does not exist (give the path of a namelist scenario file)")
      return
    end if
    inquire(file=path // "/.", exist=is_dir)
    if (is_dir) then
      call fatal_error(error, path // ": is a directory (give the path of a namelist scenario file)")
      return
    end if
    ! a device or pipe that reading would never end (/dev/zero) or wait on (a FIFO)
    if (path_kind(path) == kind_other) then
      call fatal_error(error, path // ": not a regular file (a device, FIFO or socket: give the path of a " // &
        "namelist file)")
      return
    end if
    inquire(file=path, size=nbytes)
    if (nbytes == 0) then
      call fatal_error(error, path // no_group)
      return
    end if
    if (nbytes > max_file_size) then
      call fatal_error(error, path // ": the file has " // str(real(nbytes, dp)) // " bytes; a namelist file " // &
        "of at most " // str(max_file_size) // " is read")
      return
    end if
    open(newunit=unit, file=path, status="old", action="read", iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, path // ": cannot open the file for reading")
      return
    end if
    ! The whole file as one string (comments removed, each line followed by one
    ! blank), with the line and column of each character: a first pass sizes it,
    ! a second fills it (growing them line by line was quadratic in the file's
    ! length; with the buffered assignments below, reading the paper scenario
    ! went from 12.4 M to 2.8 M instructions)
    nchar = 0
    do
      call read_line(unit, buf, ios)
      if (ios /= 0) exit
      nchar = nchar + stripped_length(buf) + 1
    end do
    rewind(unit)
    allocate(character(len=nchar) :: text)
    allocate(line_of(nchar), col_of(nchar))
    lineno = 0
    pos = 0
    do
      call read_line(unit, buf, ios)
      if (ios /= 0 .or. pos >= nchar) exit
      lineno = lineno + 1
      ! a UTF-8 byte-order mark (some Windows editors write one) reads as blanks
      if (lineno == 1 .and. buf(1:3) == char(239) // char(187) // char(191)) buf(1:3) = "   "
      lt = stripped_length(buf)
      ! tabs scan as blanks, other control characters as '?' (messages stay one line)
      do k = 1, lt
        if (iachar(buf(k:k)) == 9) then
          buf(k:k) = " "
        else if (iachar(buf(k:k)) < 32 .or. iachar(buf(k:k)) == 127) then
          buf(k:k) = "?"
        end if
      end do
      text(pos+1:pos+lt+1) = buf(1:lt) // " "
      line_of(pos+1:pos+lt+1) = lineno
      col_of(pos+1:pos+lt+1) = [(k, k = 1, lt + 1)]
      pos = pos + lt + 1
    end do
    close(unit)
    self%nlines = lineno
    self%unterminated = .not. ends_with_newline(path)
    if (self%unterminated) call check_terminated_copy(self, error)
    if (allocated(error)) return
    call scan_text(self, text(1:pos), line_of(1:pos), col_of(1:pos), error)
    if (.not. allocated(error) .and. size(self%groups) == 0) call fatal_error(error, path // no_group)
  end subroutine nml_load

  !> A file whose last line has no newline is read through a terminated copy
  !> in a scratch file (nml_open_text), which gfortran puts in $TMPDIR (or
  !> /tmp) and which loses its lines without an error when that is full: the
  !> groups would then read as empty.  Make the copy once here and count its
  !> lines back, so that a full temporary directory is one clear error.
  subroutine check_terminated_copy(self, error)
    class(nml_file), intent(in) :: self
    type(error_type), allocatable, intent(inout) :: error !< set if the copy is short
    integer :: unit, lines, ios
    character(len=:), allocatable :: line
    call self%open_text(unit, error)
    if (allocated(error)) return
    lines = 0
    do
      call read_line(unit, line, ios)
      if (ios /= 0) exit
      lines = lines + 1
    end do
    close(unit)
    if (lines >= self%nlines) return
    call fatal_error(error, self%path // ": its last line has no newline, and its copy with one could not be " // &
      "written in the temporary directory ($TMPDIR, else /tmp; " // str(lines) // " of " // str(self%nlines) // &
      " lines): is it full? (or end the file with a newline)")
  end subroutine check_terminated_copy

  !> One whole line of any length (ios 0; nonzero at the end of the file).
  subroutine read_line(unit, line, ios)
    integer, intent(in) :: unit                          !< formatted sequential unit
    character(len=:), allocatable, intent(out) :: line   !< the line without its end
    integer, intent(out) :: ios                          !< 0, or the end of the file
    character(len=4096) :: chunk
    integer :: n
    line = ""
    do
      read(unit, '(a)', advance="no", iostat=ios, size=n) chunk
      line = line // chunk(1:n)
      if (ios /= 0) exit
    end do
    if (is_iostat_eor(ios)) ios = 0
  end subroutine read_line

  !> The file is empty or its last byte is a line feed.
  logical function ends_with_newline(path) result(ok)
    character(len=*), intent(in) :: path  !< an existing, readable file
    integer :: unit, ios
    integer(i8) :: nbytes
    character(len=1) :: last
    ok = .true.
    open(newunit=unit, file=path, access="stream", form="unformatted", status="old", action="read", iostat=ios)
    if (ios /= 0) return
    inquire(unit=unit, size=nbytes)
    if (nbytes > 0) then
      read(unit, pos=nbytes, iostat=ios) last
      if (ios == 0) ok = last == achar(10)
    end if
    close(unit)
  end function ends_with_newline

  !> Length of a line without its comment and trailing blanks.
  pure integer function stripped_length(line) result(n)
    character(len=*), intent(in) :: line
    integer :: lt
    lt = len_trim(line)
    n = len_trim(strip_comment(line(1:lt)))
  end function stripped_length

  !> Scan the comment-free text into groups and assignments.
  subroutine scan_text(self, text, line_of, col_of, error)
    type(nml_file), intent(inout) :: self
    character(len=*), intent(in) :: text
    integer, intent(in) :: line_of(:), col_of(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: i, n, j, k, vstart, gline, n_items
    character(len=:), allocatable :: group, name, idx
    logical :: in_group
    character :: quote
    type(nml_assignment) :: item
    type(nml_assignment), allocatable :: items(:)

    ! the assignments found, in a buffer that doubles when full (appending to
    ! self%items one by one copied every earlier assignment each time)
    allocate(items(16))
    n_items = 0
    call scan()
    self%items = items(1:n_items)
  contains
    !> The groups and assignments of the text, in order.
    subroutine scan()
      n = len(text)
      i = 1
      in_group = .false.
      vstart = 0
      gline = 0
      do while (i <= n)
        if (.not. in_group) then
          if (text(i:i) == "&" .or. text(i:i) == "$") then
            j = i + 1
            do while (j <= n)
              if (.not. is_name_char(text(j:j))) exit
              j = j + 1
            end do
            group = lower(text(i+1:j-1))
            if (group == "end") then
              i = j
              cycle
            end if
            in_group = .true.
            gline = line_of(i)
            self%groups = [character(len=32) :: self%groups, group]
            self%group_lines = [self%group_lines, gline]
            vstart = 0
            i = j
            cycle
          else if (text(i:i) /= " ") then
            call fatal_error(error, self%path // ":" // str(line_of(i)) // ": text outside a namelist group: '" &
              // trim(text(i:min(n, i+20))) // "' (groups start with &name and end with /)")
            return
          end if
          i = i + 1
        else
          select case (text(i:i))
          case ("'", '"')
            quote = text(i:i)
            j = index(text(i+1:), quote)
            ! a string ends on its own line (a missing closing quote would
            ! otherwise be found lines later, at the next quote)
            if (j > 0) then
              if (line_of(i + j) /= line_of(i)) j = 0
            end if
            if (j == 0) then
              call fatal_error(error, self%path // ":" // str(line_of(i)) // ": &" // group // &
                ": unterminated string " // trim(text(i:min(n, i+39, line_end(i)))) // " (a quoted value must " // &
                "end with its " // quote // " on the same line)")
              return
            end if
            i = i + j + 1
          case ("/")
            ! `output = /tmp/run.nc`: an unquoted path, whose / would end the group
            if (vstart > 0 .and. i < n) then
              if (len_trim(text(vstart:i-1)) == 0 .and. text(i+1:i+1) /= " ") then
                j = i
                do while (j < n)
                  if (text(j+1:j+1) == " " .or. text(j+1:j+1) == ",") exit
                  j = j + 1
                end do
                call fatal_error(error, self%path // ":" // str(line_of(i)) // ": &" // group // ": '" // &
                  item%name // item%index // "' = " // text(i:j) // " is not allowed: a string must be quoted ('" // &
                  text(i:j) // "'); an unquoted / ends the group")
                return
              end if
            end if
            if (vstart > 0) call close_item(i - 1)
            in_group = .false.
            vstart = 0
            i = i + 1
          case ("&")
            if (lower(text(i:min(n, i+3))) == "&end") then
              if (vstart > 0) call close_item(i - 1)
              in_group = .false.
              vstart = 0
              i = i + 4
            else
              call fatal_error(error, self%path // ":" // str(line_of(i)) // ": group &" // group // &
                " is not closed with / before the next group")
              return
            end if
          case default
            if (is_name_start(text(i:i)) .and. (i == 1 .or. is_sep(text(max(1, i-1):max(1, i-1))))) then
              ! a name followed (after an optional index and blanks) by '=' starts an assignment
              j = i
              do while (j <= n)
                if (.not. (is_name_char(text(j:j)) .or. text(j:j) == "%")) exit
                j = j + 1
              end do
              k = j
              idx = ""
              if (k <= n) then
                if (text(k:k) == "(") then
                  k = index(text(k:), ")") + k
                  idx = lower(without_blanks(text(j:k-1)))
                end if
              end if
              do while (k <= n)
                if (text(k:k) /= " ") exit
                k = k + 1
              end do
              if (k <= n) then
                if (text(k:k) == "=") then
                  if (vstart > 0) call close_item(i - 1)
                  name = lower(text(i:j-1))
                  item%group = group
                  item%name = name
                  item%index = idx
                  item%line = line_of(i)
                  item%group_number = size(self%groups)
                  item%first_line = line_of(i)
                  item%first_col = col_of(i)
                  item%last_line = line_of(k)
                  item%last_col = col_of(k)
                  vstart = k + 1
                  i = k + 1
                  cycle
                end if
              end if
              i = j
            else
              i = i + 1
            end if
          end select
        end if
      end do
      if (in_group) then
        call fatal_error(error, self%path // ":" // str(gline) // ": group &" // group // &
          " is not closed (end it with /)")
      end if
    end subroutine scan

    !> The last character of the line that holds character i.
    pure integer function line_end(i) result(e)
      integer, intent(in) :: i
      e = i
      do while (e < n)
        if (line_of(e + 1) /= line_of(i)) exit
        e = e + 1
      end do
    end function line_end

    subroutine close_item(last)
      integer, intent(in) :: last
      character(len=:), allocatable :: v
      integer :: p
      p = len_trim(text(vstart:last))
      if (p > 0) then
        item%last_line = line_of(vstart + p - 1)
        item%last_col = col_of(vstart + p - 1)
      end if
      v = trim(adjustl(text(vstart:last)))
      if (len(v) > 0) then
        if (v(len(v):len(v)) == ",") v = trim(v(:len(v)-1))
      end if
      item%value = v
      if (n_items == size(items)) call grow()
      n_items = n_items + 1
      items(n_items) = item
      vstart = 0
    end subroutine close_item

    subroutine grow()
      type(nml_assignment), allocatable :: bigger(:)
      allocate(bigger(2*size(items)))
      bigger(1:n_items) = items(1:n_items)
      call move_alloc(bigger, items)
    end subroutine grow
  end subroutine scan_text

  !> Every group in the file must be one of `allowed`.
  subroutine nml_check_groups(self, allowed, error)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: allowed(:)            !< known group names
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: i, j
    do i = 1, size(self%groups)
      if (.not. any([(lower(trim(allowed(j))) == trim(self%groups(i)), j = 1, size(allowed))])) then
        call fatal_error(error, self%path // ":" // str(self%group_lines(i)) // ": unknown group &" // &
          trim(self%groups(i)) // " (allowed: " // join(allowed) // ")" // other_kind_hint(self%groups(i)))
        return
      end if
      do j = 1, i - 1
        if (self%groups(j) == self%groups(i)) then
          call fatal_error(error, self%path // ":" // str(self%group_lines(i)) // ": group &" // &
            trim(self%groups(i)) // " appears twice (allowed once)")
          return
        end if
      end do
    end do
  end subroutine nml_check_groups

  !> For a scenario's unknown group that belongs to the package's other input
  !> files, what that file is and where it goes ("" otherwise).
  pure function other_kind_hint(group) result(hint)
    character(len=*), intent(in) :: group   !< the group's name, lower case
    character(len=:), allocatable :: hint
    select case (trim(group))
    case ("sweep", "input", "fixed")
      hint = ": this is a sweep definition, run by scripts/sweep (docs/sweep.md)"
    case ("criteria")
      hint = ": this is a criteria file, named by a sweep's &sweep criteria (docs/sweep.md)"
    case default
      hint = ""
    end select
  end function other_kind_hint

  !> Every variable written in `group` must be one of `vars`.
  subroutine nml_check_group(self, group, vars, error)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: group                 !< group name
    type(nml_var), intent(in) :: vars(:)                  !< its variables
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: i, j
    logical :: known, is_list, twice
    character(len=:), allocatable :: first
    do i = 1, size(self%items)
      if (self%items(i)%group /= lower(group)) cycle
      known = .false.
      do j = 1, size(vars)
        if (lower(trim(vars(j)%name)) == self%items(i)%name) known = .true.
      end do
      if (.not. known) then
        call fatal_error(error, self%where(self%items(i)) // "unknown variable '" // &
          self%items(i)%name // "' = " // self%items(i)%value // closest(self%items(i)%name, vars) // &
          " (allowed: " // join(vars%name) // ")")
        return
      end if
      ! The value's form against its variable (check_form below)
      is_list = .false.
      do j = 1, size(vars)
        if (lower(trim(vars(j)%name)) /= self%items(i)%name) cycle
        call check_form(self%items(i), vars(j))
        if (allocated(error)) return
        is_list = vars(j)%kind == "real_list" .or. vars(j)%kind == "integer_list"
      end do
      ! Fortran's namelist read keeps the last of two assignments without a word:
      ! a value written twice is an error, not a silent choice — also an
      ! element a whole vector or a range assigns too (`b_position = 1, 2, 3`
      ! and `b_position(2) = 5`, in either order; lists: check_list_order).
      do j = 1, i - 1
        associate(a => self%items(j), b => self%items(i))
          twice = .false.
          if (a%group_number == b%group_number .and. a%name == b%name) then
            twice = a%index == b%index
            if (.not. twice .and. .not. is_list) twice = spans_overlap(a, b)
          end if
          if (twice) then
            if (a%index == b%index) then
              first = a%value
            else
              first = a%name // a%index // " = " // a%value
            end if
            call fatal_error(error, self%where(b) // "'" // b%name // b%index // "' = " // b%value // &
              " is assigned a second time (first at line " // str(a%line) // ": " // first // &
              "); a namelist would keep the last value silently, so give it once")
            return
          end if
        end associate
      end do
      if (is_list) call check_list_order(i)
      if (allocated(error)) return
    end do
  contains
    !> The assignments of a list variable in one group fill it in order, without
    !> gaps: the whole list first (`values = a, b`), then elements one value
    !> each, `values(3) = c`, the next index each time.  Fortran's read would
    !> leave a gap unset (and the readers count the leading set values only),
    !> refuse `values(3) = a, b`; the table step (f90nml) would drop values:
    !> both steps refuse all of these alike (check_namelist_text in
    !> postproc/sweep/definition.py).
    subroutine check_list_order(i)
      integer, intent(in) :: i   !< the assignment to check
      integer :: j, next, k, ios
      logical :: ok
      next = 1
      do j = 1, i - 1
        if (self%items(j)%group_number == self%items(i)%group_number .and. &
          self%items(j)%name == self%items(i)%name) next = next + count_values(self%items(j)%value)
      end do
      associate(b => self%items(i))
        if (len(b%index) == 0) then
          ok = next == 1
        else
          k = 0
          ios = 1
          if (len(b%index) > 2 .and. len(b%index) <= 12) then
            if (verify(b%index(2:len(b%index)-1), "+-0123456789") == 0) &
              read(b%index(2:len(b%index)-1), *, iostat=ios) k
          end if
          if (ios == 0 .and. (k < 1 .or. k > max_list_items)) then
            call fatal_error(error, self%where(b) // "'" // b%name // b%index // "' = " // b%value // &
              " is not allowed (" // b%name // " holds at most " // str(max_list_items) // &
              " values: indices 1 to " // str(max_list_items) // ")")
            return
          end if
          ok = ios == 0 .and. k == next .and. count_values(b%value) == 1
        end if
        if (.not. ok) call fatal_error(error, self%where(b) // "'" // b%name // b%index // "' = " // b%value // &
          " is not allowed: the elements of " // b%name // " are given one value each, in order and without " // &
          "gaps (" // b%name // "(" // str(next) // ") is next), or as the whole list first (" // b%name // &
          " = a, b, ...)")
      end associate
    end subroutine check_list_order

    !> - reals: NaN and Inf read as real numbers; no input is meant to be either;
    !> - numbers: every value looks like one (gfortran reads a lone "-" as 0);
    !> - strings: quoted (gfortran would take `name = 0` as the text "0"), and no
    !>   longer than the reader's variable (it would cut them off silently);
    !> - lists: no longer than the reader's array ("Cannot match namelist object
    !>   name" otherwise);
    !> - a whole 3-vector: three values (Fortran's read would keep the old value
    !>   of a missing component, or stop at an extra one);
    !> - no null value (`t_end = ,`, `1.0,,2.0`, `2*`): Fortran's read keeps the
    !>   variable's default for it, silently.
    subroutine check_form(item, var)
      type(nml_assignment), intent(in) :: item
      type(nml_var), intent(in) :: var
      integer :: n, lo, hi
      character(len=:), allocatable :: v
      v = item%value
      if (len_trim(v) == 0) then
        call fatal_error(error, self%where(item) // "'" // item%name // item%index // "' has no value (a " // &
          "namelist read would keep its default silently): give a value, or leave the variable out")
        return
      else if (has_null_value(v)) then
        call fatal_error(error, self%where(item) // "'" // item%name // item%index // "' = " // v // &
          " is not allowed: it has a null value (nothing between separators, or a repeat count without a " // &
          "value), which a namelist read skips, keeping the default silently; give every value")
        return
      end if
      select case (var%kind)
      case ("real", "real_list", "real3", "real_array")
        select case (value_class(v))
        case (not_finite)
          call fatal_error(error, self%where(item) // "'" // item%name // item%index // "' = " // v // &
            " is not allowed (not a finite number)")
          return
        case (subnormal)
          ! e.g. a stop time 1e-310 after t = 0: CVODE's first step is subnormal,
          ! 1/h overflows and CVode does not return
          call fatal_error(error, self%where(item) // "'" // item%name // item%index // "' = " // v // &
            " is not allowed (a subnormal number, 0 < |x| < 2.2e-308: too small to compute with; give 0 or " // &
            "a normal number)")
          return
        end select
      end select
      select case (var%kind)
      case ("real", "real_list", "real3", "real_array", "integer", "integer_list")
        if (.not. all_numbers(v)) then
          call fatal_error(error, self%where(item) // "variable '" // item%name // "' = " // v // " is not " // &
            trim(merge("an integer   ", "a real number", index(var%kind, "integer") == 1)))
          return
        end if
      end select
      select case (var%kind)
      case ("string")
        ! a leading repeat count (`4*'direct'`) is allowed
        n = verify(v, "0123456789")
        if (n > 1) then
          if (v(n:n) == "*") v = v(n+1:)
        end if
        if (len(v) == 0) return
        if (v(1:1) /= "'" .and. v(1:1) /= '"') then
          call fatal_error(error, self%where(item) // "variable '" // item%name // "' = " // item%value // &
            " is not a quoted string")
        else if (var%length > 0 .and. longest_quoted(v) > var%length) then
          call fatal_error(error, self%where(item) // "'" // item%name // "' is " // str(longest_quoted(v)) // &
            " characters long; at most " // str(var%length) // " are allowed")
        end if
      case ("real_list", "integer_list")
        n = count_values(v)
        if (len(item%index) == 0 .and. n > max_list_items) call fatal_error(error, self%where(item) // "'" // &
          item%name // "' has " // str(n) // " values; at most " // str(max_list_items) // " are allowed")
      case ("real3")
        n = count_values(v)
        if (len(item%index) == 0 .and. n /= 3) call fatal_error(error, self%where(item) // "'" // item%name // &
          "' = " // v // " has " // str(n) // " values; a vector of 3 (x, y, z) is expected")
      end select
      if (allocated(error)) return
      ! an element the array does not have (`wind(4)`, `c_dn_table(0)`): the
      ! read fails with the runtime's "Index 1 out of range", which names
      ! neither the value nor the bounds
      n = 0
      if (var%kind == "real3") n = 3
      if (var%kind == "real_array") n = var%length
      if (n > 0 .and. len(item%index) > 0) then
        ! one element takes one value (the read stops at the second with
        ! "Cannot match namelist object name"); a section k:m takes several
        if (index(item%index, ":") == 0 .and. count_values(item%value) > 1) then
          call fatal_error(error, self%where(item) // "'" // item%name // item%index // "' = " // item%value // &
            " is not allowed (one element takes one value: give " // item%name // "(k:m) = ... for several, " // &
            "or the whole " // item%name // " = ...)")
          return
        end if
        call element_span(item, lo, hi)
        if (lo /= unknown_element .and. (lo < 1 .or. hi > n)) call fatal_error(error, self%where(item) // "'" // &
          item%name // item%index // "' = " // item%value // " is not allowed (" // item%name // " holds at most " // &
          str(n) // " values: indices 1 to " // str(n) // ")")
      end if
    end subroutine check_form

    !> The longest quoted string of a value ('a', "b", 3*'c' ...: a list gives
    !> each item's length; a doubled quote inside counts as one character).
    pure integer function longest_quoted(v) result(longest)
      character(len=*), intent(in) :: v
      character :: q
      integer :: i, n
      longest = 0
      q = " "
      n = 0
      i = 1
      do while (i <= len(v))
        if (q == " ") then
          if (v(i:i) == "'" .or. v(i:i) == '"') then
            q = v(i:i)
            n = 0
          end if
        else if (v(i:i) == q) then
          if (i < len(v)) then
            if (v(i+1:i+1) == q) then   ! a doubled quote: one character
              n = n + 1
              i = i + 2
              cycle
            end if
          end if
          longest = max(longest, n)
          q = " "
        else
          n = n + 1
        end if
        i = i + 1
      end do
      if (q /= " ") longest = max(longest, n)
    end function longest_quoted
  end subroutine nml_check_group

  !> "file:line: &group: " prefix of a message about an assignment.
  function nml_where(self, item) result(s)
    class(nml_file), intent(in) :: self
    type(nml_assignment), intent(in) :: item
    character(len=:), allocatable :: s
    s = self%path // ":" // str(item%line) // ": &" // item%group // ": "
  end function nml_where

  !> True if the file has the group.
  logical function nml_has_group(self, group)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: group   !< group name
    nml_has_group = any(self%groups == lower(group))
  end function nml_has_group

  !> True if the file assigns `name` in `group`.
  logical function nml_is_set(self, group, name)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: group, name   !< group and variable
    integer :: i
    nml_is_set = .false.
    do i = 1, size(self%items)
      if (self%items(i)%group == lower(group) .and. self%items(i)%name == lower(name)) nml_is_set = .true.
    end do
  end function nml_is_set

  !> Open the file on a new unit for `read(unit, nml=...)` of `group`;
  !> `present` is false (and the unit closed) if the file lacks the group, or
  !> if it cannot be opened again (`error` set).
  subroutine nml_position(self, group, unit, present, error)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: group   !< group name
    integer, intent(out) :: unit            !< unit to read from (closed by the caller)
    logical, intent(out) :: present         !< the group is in the file
    type(error_type), allocatable, intent(inout) :: error  !< set if the file cannot be opened
    present = self%has_group(group)
    unit = -1
    if (.not. present) return
    call self%open_text(unit, error)
    present = .not. allocated(error)
  end subroutine nml_position

  !> Open the file at its start on a new unit for `read(unit, nml=...)` of its
  !> groups in turn (closed by the caller): the file itself, or, if its last
  !> line has no newline, the same lines each terminated in a scratch file.
  !> If that fails (the file removed since it was loaded, no temporary
  !> directory to write in) `error` says so and no unit is left open.
  subroutine nml_open_text(self, unit, error)
    class(nml_file), intent(in) :: self
    integer, intent(out) :: unit            !< unit to read from
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    integer :: src, ios, ios_close
    character(len=:), allocatable :: line
    character(len=256) :: msg
    msg = "a read failed"
    open(newunit=unit, file=self%path, status="old", action="read", iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call fatal_error(error, self%path // ": could not be opened again to read its groups (" // trim(msg) // ")")
      return
    end if
    if (.not. self%unterminated) return
    src = unit
    open(newunit=unit, status="scratch", action="readwrite", form="formatted", iostat=ios, iomsg=msg)
    if (ios == 0) then
      do
        call read_line(src, line, ios)
        if (ios /= 0) exit
        write(unit, '(a)', iostat=ios, iomsg=msg) line
        if (ios /= 0) exit
      end do
      ! the end of the file: every line copied; otherwise a read or a write failed
      if (is_iostat_end(ios)) rewind(unit, iostat=ios, iomsg=msg)
      if (ios /= 0) close(unit, iostat=ios_close)
    end if
    close(src, iostat=ios_close)
    if (ios /= 0) call fatal_error(error, self%path // ": its last line has no newline, and its copy with one " // &
      "could not be written in the temporary directory ($TMPDIR, else /tmp: " // trim(msg) // &
      "; or end the file with a newline)")
  end subroutine nml_open_text

  !> After a failed namelist read of `group`: find the value that does not
  !> parse as its variable's type and report it; otherwise report the
  !> runtime's message.
  subroutine nml_diagnose(self, group, vars, iomsg, error)
    class(nml_file), intent(in) :: self
    character(len=*), intent(in) :: group                 !< group name
    type(nml_var), intent(in) :: vars(:)                  !< its variables
    character(len=*), intent(in) :: iomsg                 !< message of the failed read
    type(error_type), allocatable, intent(inout) :: error !< set
    integer :: i, j, ios
    real(dp) :: r, rl(1000)
    integer :: k
    logical :: l
    character(len=:), allocatable :: v, expected
    do i = 1, size(self%items)
      if (self%items(i)%group /= lower(group)) cycle
      v = self%items(i)%value
      do j = 1, size(vars)
        if (lower(trim(vars(j)%name)) /= self%items(i)%name) cycle
        select case (vars(j)%kind)
        case ("real")
          read(v, *, iostat=ios) r
          if (ios == 0) ios = merge(0, 1, is_number(v))
          expected = "a real number"
        case ("integer")
          read(v, *, iostat=ios) k
          if (ios == 0) ios = merge(0, 1, is_number(v) .and. verify(trim(v), "+-0123456789") == 0)
          if (is_number(v) .and. verify(trim(v), "+-0123456789") /= 0) then
            expected = "an integer (a whole number: no decimal point or exponent)"
          else
            expected = "an integer in [" // str(-huge(1)) // ", " // str(huge(1)) // "]"
          end if
        case ("logical")
          read(v, *, iostat=ios) l
          expected = ".true. or .false."
        case ("string")
          ios = 0
          if (len(v) > 0) then
            if (v(1:1) /= "'" .and. v(1:1) /= '"') ios = 1
          end if
          expected = "a quoted string"
        case ("real_list", "real3", "real_array")
          rl = 0
          read(v, *, iostat=ios) rl(1:min(max(count_values(v), 1), size(rl)))
          expected = "a list of real numbers"
        case default
          ios = 0
          expected = ""
        end select
        if (ios /= 0 .or. len(v) == 0) then
          call fatal_error(error, self%where(self%items(i)) // "variable '" // self%items(i)%name // &
            "' = " // v // " is not " // expected)
          return
        end if
      end do
    end do
    call fatal_error(error, self%path // ": &" // lower(group) // ": cannot read the group: " // trim(iomsg))
  end subroutine nml_diagnose

  ! ---------------------------------------------------------------------
  ! Range checks: one line naming file, group, variable, value, allowed.
  ! ---------------------------------------------------------------------

  !> x > 0 required.
  subroutine require_positive(f, group, name, x, unit, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, unit
    real(dp), intent(in) :: x
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call require_set(f, group, name, x, unit, error)
    if (allocated(error)) return
    if (.not. (x > 0.0_dp)) call fatal_error(error, f%path // ": &" // group // ": " // name // &
      " = " // str(x) // " is not allowed (must be > 0" // with_unit(unit) // ")")
  end subroutine require_positive

  !> x >= 0 required.
  subroutine require_nonnegative(f, group, name, x, unit, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, unit
    real(dp), intent(in) :: x
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call require_set(f, group, name, x, unit, error)
    if (allocated(error)) return
    if (.not. (x >= 0.0_dp)) call fatal_error(error, f%path // ": &" // group // ": " // name // &
      " = " // str(x) // " is not allowed (must be >= 0" // with_unit(unit) // ")")
  end subroutine require_nonnegative

  !> " UNIT", or nothing for a quantity without a unit.
  pure function with_unit(unit) result(s)
    character(len=*), intent(in) :: unit
    character(len=:), allocatable :: s
    s = ""
    if (len_trim(unit) > 0) s = " " // trim(unit)
  end function with_unit

  !> lo <= x <= hi required.
  subroutine require_range(f, group, name, x, lo, hi, unit, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, unit
    real(dp), intent(in) :: x, lo, hi
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call require_set(f, group, name, x, unit, error)
    if (allocated(error)) return
    if (.not. (x >= lo .and. x <= hi)) call fatal_error(error, f%path // ": &" // group // ": " // &
      name // " = " // str(x) // " is not allowed (must be in [" // str(lo) // ", " // str(hi) // &
      "]" // with_unit(unit) // ")")
  end subroutine require_range

  !> lo <= i <= hi required.
  subroutine require_int_range(f, group, name, i, lo, hi, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name
    integer, intent(in) :: i, lo, hi
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    if (i == unset_int) then
      call fatal_error(error, f%path // ": &" // group // ": missing required value " // name // &
        " (an integer in [" // str(lo) // ", " // str(hi) // "])")
    else if (i < lo .or. i > hi) then
      call fatal_error(error, f%path // ": &" // group // ": " // name // " = " // str(i) // &
        " is not allowed (must be an integer in [" // str(lo) // ", " // str(hi) // "])")
    end if
  end subroutine require_int_range

  !> s must be one of `choices`.
  subroutine require_choice(f, group, name, s, choices, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, s
    character(len=*), intent(in) :: choices(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: j
    if (allocated(error)) return
    if (.not. any([(trim(choices(j)) == trim(s), j = 1, size(choices))])) then
      call fatal_error(error, f%path // ": &" // group // ": " // name // " = '" // trim(s) // &
        "' is not allowed (one of: " // join(choices) // ")")
    end if
  end subroutine require_choice

  !> A required value must have been set in the file.
  subroutine require_set(f, group, name, x, unit, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, unit
    real(dp), intent(in) :: x
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    if (x /= unset_real) return
    if (len_trim(unit) > 0) then
      call fatal_error(error, f%path // ": &" // group // ": missing required value " // name // " (" // &
        trim(unit) // ")")
    else
      call fatal_error(error, f%path // ": &" // group // ": missing required value " // name)
    end if
  end subroutine require_set

  ! ---------------------------------------------------------------------
  ! Text helpers
  ! ---------------------------------------------------------------------

  !> Line without its '!' comment (quotes respected).
  pure function strip_comment(line) result(s)
    character(len=*), intent(in) :: line
    character(len=len(line)) :: s
    integer :: i
    character :: quote
    s = line
    quote = " "
    do i = 1, len(line)
      if (quote /= " ") then
        if (line(i:i) == quote) quote = " "
      else if (line(i:i) == "'" .or. line(i:i) == '"') then
        quote = line(i:i)
      else if (line(i:i) == "!") then
        s = line(:i-1)
        return
      end if
    end do
  end function strip_comment

  pure function without_blanks(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    integer :: i
    t = ""
    do i = 1, len(s)
      if (s(i:i) /= " ") t = t // s(i:i)
    end do
  end function without_blanks

  pure logical function is_name_start(c)
    character, intent(in) :: c
    is_name_start = (c >= "a" .and. c <= "z") .or. (c >= "A" .and. c <= "Z")
  end function is_name_start

  pure logical function is_name_char(c)
    character, intent(in) :: c
    is_name_char = is_name_start(c) .or. (c >= "0" .and. c <= "9") .or. c == "_"
  end function is_name_char

  pure logical function is_sep(c)
    character, intent(in) :: c
    is_sep = c == " " .or. c == "," .or. c == "&"
  end function is_sep

  !> The value looks like a number (not a logical or a string read as one).
  pure logical function is_number(v)
    character(len=*), intent(in) :: v
    is_number = len_trim(v) > 0 .and. verify(trim(v), "+-.0123456789eEdD") == 0 .and. &
      scan(v, "0123456789") > 0
  end function is_number


  !> True if the value text v (the scanner has dropped one separator after the
  !> last value) has a null value: no value at all, a comma with no value
  !> before it (`, 1.0`, `1.0,,2.0`, a trailing `1.0,` after the dropped one),
  !> or a repeat count without a value (`2*`).  Quotes are respected.
  pure logical function has_null_value(v) result(null)
    character(len=*), intent(in) :: v
    integer :: i
    logical :: in_quote, seen_value
    character :: q
    null = .true.
    in_quote = .false.
    seen_value = .false.   ! a value since the last comma
    q = " "
    do i = 1, len(v)
      if (in_quote) then
        if (v(i:i) == q) in_quote = .false.
        cycle
      end if
      select case (v(i:i))
      case ("'", '"')
        in_quote = .true.
        q = v(i:i)
        seen_value = .true.
      case (",")
        if (.not. seen_value) return
        seen_value = .false.
      case (" ")
      case ("*")
        if (i == len(v)) return
        if (v(i+1:i+1) == "," .or. v(i+1:i+1) == " ") return
      case default
        seen_value = .true.
      end select
    end do
    null = .not. seen_value
  end function has_null_value

  !> Bounds first:last of the next item of the list v at or after position pos
  !> (blanks and commas separate items); first = 0 when there is none.
  pure subroutine next_item(v, pos, first, last)
    character(len=*), intent(in) :: v
    integer, intent(in) :: pos
    integer, intent(out) :: first, last
    first = pos
    do while (first <= len(v))
      if (v(first:first) /= "," .and. v(first:first) /= " ") exit
      first = first + 1
    end do
    if (first > len(v)) then
      first = 0
      last = 0
      return
    end if
    last = first
    do while (last < len(v))
      if (v(last+1:last+1) == "," .or. v(last+1:last+1) == " ") exit
      last = last + 1
    end do
  end subroutine next_item

  !> Number of values of a list, repeat counts included ("3*0.0" and "2*" are 3
  !> and 2 values).
  !> The elements two assignments of one vector set overlap: the whole vector
  !> sets 1..(its values), `x(k) = ...` k onwards, `x(k:m)` k..m (an index of
  !> another form: no overlap known; the exact comparison applies).
  logical function spans_overlap(a, b)
    type(nml_assignment), intent(in) :: a, b   !< two assignments of one variable
    integer :: lo(2), hi(2)
    call element_span(a, lo(1), hi(1))
    call element_span(b, lo(2), hi(2))
    spans_overlap = all(lo >= 1) .and. max(lo(1), lo(2)) <= min(hi(1), hi(2))
  end function spans_overlap

  !> The elements [lo, hi] an assignment sets (lo = unknown_element: an index of
  !> another form; a negative index is read as itself).
  subroutine element_span(item, lo, hi)
    type(nml_assignment), intent(in) :: item   !< an assignment (index normalised: no blanks)
    integer, intent(out) :: lo, hi
    integer :: colon, ios1, ios2, n
    character(len=:), allocatable :: inner
    n = max(1, count_values(item%value))
    lo = unknown_element
    hi = -1
    if (len(item%index) == 0) then
      lo = 1
      hi = n
      return
    end if
    if (len(item%index) < 3 .or. len(item%index) > 24) return
    inner = item%index(2:len(item%index)-1)
    if (verify(inner, "+-0123456789:") /= 0) return
    colon = index(inner, ":")
    if (colon == 0) then
      read(inner, *, iostat=ios1) lo
      if (ios1 /= 0) lo = unknown_element
      hi = lo + n - 1
    else if (colon > 1 .and. colon < len(inner)) then
      read(inner(1:colon-1), *, iostat=ios1) lo
      read(inner(colon+1:), *, iostat=ios2) hi
      if (ios1 /= 0 .or. ios2 /= 0) lo = unknown_element
    end if
  end subroutine element_span

  integer function count_values(v) result(n)
    character(len=*), intent(in) :: v
    integer :: first, last, star, k, ios
    n = 0
    call next_item(v, 1, first, last)
    do while (first > 0)
      star = index(v(first:last), "*")
      k = 1
      if (star > 1) then
        read(v(first:first+star-2), *, iostat=ios) k
        if (ios /= 0 .or. k < 1) k = 1
      end if
      n = n + k
      call next_item(v, last + 1, first, last)
    end do
  end function count_values

  !> Every value of a list has the form of a number (repeat counts `k*v` and
  !> null values `k*` allowed; called after `value_class`, so no NaN or Inf).
  logical function all_numbers(v) result(ok)
    character(len=*), intent(in) :: v
    integer :: first, last, star
    character(len=:), allocatable :: x
    ok = .true.
    call next_item(v, 1, first, last)
    do while (first > 0)
      star = index(v(first:last), "*")
      x = v(first+star:last)
      if (len(x) > 0) ok = ok .and. is_number(x)
      call next_item(v, last + 1, first, last)
    end do
  end function all_numbers

  !> What the values of a list (repeat counts allowed) read as: one NaN or
  !> infinite (not_finite) before one subnormal, 0 < |x| < tiny (subnormal),
  !> else normal_values; values that do not read as numbers are left to
  !> `diagnose`.
  integer function value_class(v) result(worst)
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    character(len=*), intent(in) :: v
    integer :: first, last, star, ios
    real(dp) :: x
    worst = normal_values
    call next_item(v, 1, first, last)
    do while (first > 0)
      star = index(v(first:last), "*")
      if (first + star <= last) then
        read(v(first+star:last), *, iostat=ios) x
        if (ios == 0) then
          if (.not. ieee_is_finite(x)) then
            worst = not_finite
            return
          end if
          if (x /= 0.0_dp .and. abs(x) < tiny(x)) worst = subnormal
        end if
      end if
      call next_item(v, last + 1, first, last)
    end do
  end function value_class

  !> Comma-separated list of names.
  pure function join(names) result(s)
    character(len=*), intent(in) :: names(:)
    character(len=:), allocatable :: s
    integer :: i
    s = ""
    do i = 1, size(names)
      if (i > 1) s = s // ", "
      s = s // lower(trim(names(i)))
    end do
  end function join

  !> " (did you mean 'x'?)" for the nearest known name by edit distance <= 2,
  !> else for the known names that `name` begins as a word ('cg' for
  !> 'cg_from_nose'; up to four: 'fin_root' for fin_root_chord and
  !> fin_root_le_from_nose, none for 'fin', which begins six).
  function closest(name, vars) result(s)
    character(len=*), intent(in) :: name
    type(nml_var), intent(in) :: vars(:)
    character(len=:), allocatable :: s
    character(len=:), allocatable :: known, words
    integer :: j, d, best, jbest, n_words
    s = ""
    best = 3
    jbest = 0
    do j = 1, size(vars)
      d = edit_distance(name, lower(trim(vars(j)%name)))
      if (d < best) then
        best = d
        jbest = j
      end if
    end do
    if (jbest > 0) then
      s = " (did you mean '" // lower(trim(vars(jbest)%name)) // "'?)"
      return
    end if
    words = ""
    n_words = 0
    do j = 1, size(vars)
      known = lower(trim(vars(j)%name))
      if (len(name) == 0 .or. len(known) <= len(name) + 1) cycle
      if (known(1:len(name) + 1) /= name // "_") cycle
      n_words = n_words + 1
      if (n_words > 1) words = words // "', '"
      words = words // known
    end do
    if (n_words == 1) s = " (did you mean '" // words // "'?)"
    if (n_words > 1 .and. n_words <= 4) s = " (did you mean one of '" // words // "'?)"
  end function closest

  !> Levenshtein distance between two names (for "did you mean" suggestions).
  pure integer function edit_distance(a, b) result(d)
    character(len=*), intent(in) :: a, b
    integer :: m(0:len(a), 0:len(b)), i, j
    do i = 0, len(a)
      m(i, 0) = i
    end do
    do j = 0, len(b)
      m(0, j) = j
    end do
    do j = 1, len(b)
      do i = 1, len(a)
        m(i, j) = min(m(i-1, j) + 1, m(i, j-1) + 1, m(i-1, j-1) + merge(0, 1, a(i:i) == b(j:j)))
      end do
    end do
    d = m(len(a), len(b))
  end function edit_distance
end module airlaunch_namelist
