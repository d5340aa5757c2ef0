!> One case of a sweep: the base scenario's text with the case's values
!> written into their groups, read by the standard scenario readers (so every
!> case is validated exactly like a single run of `airlaunch`) and run in
!> summary mode.
!>
!> How a case is applied: each varied `group%variable = value` is inserted just
!> before the `/` that closes `&group` in the base text (or a new group is
!> appended), and the base's own assignment of that variable is taken out (its
!> lines commented out, or the assignment cut from a line it shares): the
!> readers reject a variable assigned twice.  Values are written with 17
!> significant digits (integers as integers), so they read back bit for bit.
module airlaunch_sweep_case
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str, lower
  use airlaunch_namelist, only: nml_file, nml_assignment, edit_distance
  use airlaunch_run_config, only: run_config, read_run_config
  use airlaunch_scenario_config, only: scenario_config, read_scenario_config
  use airlaunch_launch_scene, only: launch_result, run_launch
  use airlaunch_line_scene, only: line_scene_config, read_line_scene_config, run_line_scene, line_result
  use airlaunch_sweep_definition, only: sweep_definition, sweep_input, whole_and_element, both_note
  use airlaunch_sweep_files, only: read_text_file, write_text_file
  use airlaunch_sweep_row, only: sweep_row, row_from_result, row_from_line_result, invalid_row, metric_set, &
    metrics_of
  implicit none
  private
  public :: base_scenario, known_variable, load_base_scenario, check_varied_inputs, case_namelist
  public :: run_case, run_trajectory, inject_assignments, strike_assignments, value_text, check_common_settings
  public :: echo_elements

  !> A variable the scenario readers know (from the resolved input they echo).
  type :: known_variable
    character(len=32) :: group = ""
    character(len=32) :: name = ""
    character(len=8) :: kind = ""      !< real, integer, logical, string or vector (several values)
    !> its value as echoed (a vector's values, `x, y, z` or `3*x`; '' for strings)
    character(len=1024) :: value = ""
  end type known_variable

  !> The base scenario of a sweep.
  type :: base_scenario
    character(len=:), allocatable :: path       !< its file
    character(len=:), allocatable :: text       !< its text, as written
    character(len=:), allocatable :: echo       !< its fully resolved input
    type(known_variable), allocatable :: known(:)  !< variables a case may set
    type(nml_assignment), allocatable :: assigned(:)  !< the assignments written in `text`
    real(dp) :: t_end = 0.0_dp                  !< its &run t_end [s]
    character(len=16) :: scene = "airlaunch"    !< its &run scene: 'airlaunch' or 'line'
    type(metric_set) :: metrics                 !< the summary variables of that scene
  end type base_scenario

  !> A case's inputs as read: &run and the scene's own (the airlaunch scene's
  !> or the line scene's, as &run scene says).
  type :: scene_input
    type(run_config) :: run
    type(scenario_config) :: cfg                !< scene = 'airlaunch'
    type(line_scene_config) :: line_cfg         !< scene = 'line'
    character(len=:), allocatable :: echo       !< the resolved input
  end type scene_input

contains

  !> Read and validate the base scenario.
  subroutine load_base_scenario(path, base, error)
    character(len=*), intent(in) :: path                  !< base scenario file
    type(base_scenario), intent(out) :: base              !< the scenario
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    type(nml_file) :: f
    type(scene_input) :: in

    base%path = path
    call f%load(path, error)
    if (.not. allocated(error)) call read_scene(f, in, error)
    if (allocated(error)) then
      error%message = "base scenario " // error%message
      return
    end if
    base%echo = in%echo
    base%t_end = in%run%t_end
    base%scene = in%run%scene
    base%metrics = metrics_of(base%scene)
    base%assigned = f%items
    call read_text_file(path, base%text, error)
    if (allocated(error)) return
    base%known = echo_variables(base%echo)
  end subroutine load_base_scenario

  !> The variables of the resolved input the readers echo: the runtime writes
  !> a group as `&GROUP`, one ` NAME=value,` per line (continuation lines of
  !> long arrays start without `NAME=`), and ` /`.
  function echo_variables(echo) result(known)
    character(len=*), intent(in) :: echo
    type(known_variable), allocatable :: known(:)
    character(len=:), allocatable :: line, group
    integer :: p, q, eq
    allocate(known(0))
    group = ""
    p = 1
    do while (p <= len(echo))
      q = index(echo(p:), new_line("a"))
      if (q == 0) q = len(echo) - p + 2
      line = trim(adjustl(echo(p:p+q-2)))
      p = p + q
      if (len(line) == 0) cycle
      if (line(1:1) == "&") then
        group = lower(line(2:))
        cycle
      end if
      if (line(1:1) == "/") then
        group = ""
        cycle
      end if
      eq = index(line, "=")
      if (eq < 2 .or. len(group) == 0) then
        ! a continuation line of a long vector: more of its values
        if (size(known) > 0 .and. len(group) > 0 .and. eq == 0) then
          if (known(size(known))%kind == "vector") known(size(known))%value = trim(known(size(known))%value) // &
            " " // line
        end if
        cycle
      end if
      if (verify(lower(line(:eq-1)), "abcdefghijklmnopqrstuvwxyz0123456789_") /= 0) cycle
      known = [known, known_variable(group, lower(line(:eq-1)), value_kind(line(eq+1:)), "")]
      if (known(size(known))%kind == "vector") known(size(known))%value = line(eq+1:)
    end do
  end function echo_variables

  !> Every varied input must name a numeric variable of the scenario; an
  !> integer variable takes integer values only (distribution 'list').
  subroutine check_varied_inputs(def, base, error)
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(base_scenario), intent(in) :: base               !< its base scenario
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    integer :: k, j, hit, n
    character(len=:), allocatable :: where, groups, names
    character(len=8) :: kind
    do k = 1, size(def%inputs)
      associate(s => def%inputs(k))
        where = def%path // ":" // str(s%line) // ": &input #" // str(k) // " '" // s%name // "': "
        if (.not. any(base%known%group == s%group)) then
          groups = ""
          do j = 1, size(base%known)
            if (index(" " // groups // ",", " " // trim(base%known(j)%group) // ",") == 0) &
              groups = groups // trim(base%known(j)%group) // ", "
          end do
          call fatal_error(error, where // "unknown group &" // s%group // " (the scenario's groups: " // &
            groups(:len(groups)-2) // ")")
          return
        end if
        hit = 0
        names = ""
        do j = 1, size(base%known)
          if (base%known(j)%group /= s%group) cycle
          names = names // trim(base%known(j)%name) // ", "
          if (base%known(j)%name == s%variable) hit = j
        end do
        if (hit == 0) then
          call fatal_error(error, where // "unknown variable '" // s%variable // "' in &" // s%group // &
            closest(s%variable, base%known, s%group) // " (allowed: " // names(:len(names)-2) // ")")
          return
        end if
        call check_not_replaced(where, s%group, s%variable, base, error)
        if (allocated(error)) return
        kind = base%known(hit)%kind
        if (s%element > 0) then
          call check_element(where, s%name, s%group // "%" // s%variable, s%element, base%known(hit), kind, error)
          if (allocated(error)) return
        end if
        select case (trim(kind))
        case ("real")
        case ("integer")
          if (s%distribution /= "list") then
            call fatal_error(error, where // s%name // " is an integer: vary it with distribution = 'list' " // &
              "of integer values")
            return
          end if
          if (any(s%values /= aint(s%values))) then
            call fatal_error(error, where // s%name // " is an integer: its values must be integers")
            return
          end if
        case ("vector")
          n = size(echo_elements(base%known(hit)%value))
          call fatal_error(error, where // s%name // " is a vector of " // str(n) // " values; a sweep varies " // &
            "one value: vary its elements one by one (allowed: " // s%name // "(1) to " // s%name // "(" // &
            str(n) // "), each an &input), or set the whole vector in every case with &fixed value = 'x, y, z'")
          return
        case default
          call fatal_error(error, where // s%name // " is a " // trim(base%known(hit)%kind) // &
            " variable; only real and integer variables can be varied")
          return
        end select
      end associate
    end do
    do k = 1, size(def%fixed)
      associate(x => def%fixed(k))
        where = def%path // ":" // str(x%line) // ": &fixed #" // str(k) // " '" // x%name // "': "
        if (.not. any(base%known%group == x%group)) then
          call fatal_error(error, where // "unknown group &" // x%group // " in the base scenario")
          return
        end if
        if (.not. any(base%known%group == x%group .and. base%known%name == x%variable)) then
          call fatal_error(error, where // "unknown variable '" // x%variable // "' in &" // x%group // &
            closest(x%variable, base%known, x%group))
          return
        end if
        call check_not_replaced(where, x%group, x%variable, base, error)
        if (allocated(error)) return
        if (x%element > 0) then
          hit = findloc(base%known%group == x%group .and. base%known%name == x%variable, .true., dim=1)
          call check_element(where, x%name, x%group // "%" // x%variable, x%element, base%known(hit), kind, error)
          if (allocated(error)) return
          ! several values (`1.0, 2.0`, `2*1.0`, `1.0 2.0`) would run on into the next elements
          if (scan(x%value, ", *") > 0) then
            call fatal_error(error, where // "value = '" // x%value // "' is not allowed: " // x%name // &
              " is one element (allowed: one number; the whole vector is &fixed name = '" // x%group // "%" // &
              x%variable // "', value = 'x, y, z')")
            return
          end if
        end if
      end associate
    end do
    call check_vectors_once(def, error)
  end subroutine check_varied_inputs

  !> A scalar that a table of the base scenario replaces (&rocket c_dn by
  !> c_dn_table, c_axial by c_axial_table: input.md) would change no case:
  !> varied, its sensitivities would read "no effect".  Refused, naming the
  !> table's values as what to vary instead.
  subroutine check_not_replaced(where, group, variable, base, error)
    character(len=*), intent(in) :: where                 !< the &input's or &fixed's place
    character(len=*), intent(in) :: group, variable       !< the variable set
    type(base_scenario), intent(in) :: base               !< the base scenario
    type(error_type), allocatable, intent(inout) :: error !< set if a table replaces it
    character(len=*), parameter :: scalars(2) = [character(len=7) :: "c_dn", "c_axial"]
    character(len=:), allocatable :: table, instead
    integer :: i, hit
    if (group /= "rocket") return
    do i = 1, size(scalars)
      if (variable /= trim(scalars(i))) cycle
      table = trim(scalars(i)) // "_table"
      hit = findloc(base%known%group == "rocket" .and. base%known%name == table, .true., dim=1)
      if (hit == 0) return
      ! a table of one point is echoed (and so set) as one value, not element by element
      instead = "rocket%" // table
      if (base%known(hit)%kind == "vector") instead = instead // "(k)"
      call fatal_error(error, where // "rocket%" // variable // " has no effect: the base scenario gives " // &
        table // ", which replaces it (docs/input.md, &rocket); set the table's values instead, " // instead)
      return
    end do
  end subroutine check_not_replaced

  !> A vector is set whole or by its elements, not both (the readers refuse
  !> an element that the whole vector also assigns): by the varied inputs and
  !> the &fixed ones.  After the checks of each against the base, so that a
  !> vector varied whole or a scalar with an index gets its own message.
  subroutine check_vectors_once(def, error)
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(error_type), allocatable, intent(inout) :: error !< set if a vector is set both ways
    integer :: k, j
    character(len=:), allocatable :: where
    do k = 1, size(def%inputs)
      associate(s => def%inputs(k))
        where = def%path // ":" // str(s%line) // ": &input #" // str(k) // " '" // s%name // "': "
        do j = 1, k - 1
          if (whole_and_element(def%inputs(j)%group, def%inputs(j)%variable, def%inputs(j)%element, &
              s%group, s%variable, s%element)) then
            call fatal_error(error, where // s%name // " and " // def%inputs(j)%name // " (&input #" // str(j) // &
              ") both set " // s%group // "%" // s%variable // both_note(s%group // "%" // s%variable))
            return
          end if
        end do
      end associate
    end do
    do k = 1, size(def%fixed)
      associate(x => def%fixed(k))
        where = def%path // ":" // str(x%line) // ": &fixed #" // str(k) // " '" // x%name // "': "
        do j = 1, size(def%inputs)
          if (whole_and_element(def%inputs(j)%group, def%inputs(j)%variable, def%inputs(j)%element, &
              x%group, x%variable, x%element)) then
            call fatal_error(error, where // x%name // " and the varied input " // def%inputs(j)%name // &
              " (&input #" // str(j) // ") both set " // x%group // "%" // x%variable // &
              both_note(x%group // "%" // x%variable))
            return
          end if
        end do
        do j = 1, k - 1
          if (whole_and_element(def%fixed(j)%group, def%fixed(j)%variable, def%fixed(j)%element, &
              x%group, x%variable, x%element)) then
            call fatal_error(error, where // x%name // " and " // def%fixed(j)%name // " (&fixed #" // str(j) // &
              ") both set " // x%group // "%" // x%variable // both_note(x%group // "%" // x%variable))
            return
          end if
        end do
      end associate
    end do
  end subroutine check_vectors_once

  !> An element `name` = vector(element) must be one of a vector's: `kind`
  !> is then the element's kind (real or integer).
  subroutine check_element(where, name, vector, element, known, kind, error)
    character(len=*), intent(in) :: where, name, vector   !< message start; the element; its vector
    integer, intent(in) :: element                        !< its index
    type(known_variable), intent(in) :: known             !< the vector as the base resolves it
    character(len=8), intent(out) :: kind                 !< the element's kind
    type(error_type), allocatable, intent(inout) :: error !< set if it is none of the vector's
    character(len=40), allocatable :: items(:)
    kind = known%kind
    if (known%kind /= "vector") then
      call fatal_error(error, where // vector // " is a " // trim(known%kind) // " of one value, not a " // &
        "vector: it has no element " // str(element) // " (allowed: " // vector // ", without an index)")
      return
    end if
    items = echo_elements(known%value)
    if (element > size(items)) then
      call fatal_error(error, where // name // " is not allowed: index " // str(element) // " is out of " // &
        "range (" // vector // " has " // str(size(items)) // " elements: allowed " // vector // "(1) to " // &
        vector // "(" // str(size(items)) // "))")
      return
    end if
    kind = value_kind(items(element))
  end subroutine check_element

  !> The values of a vector as echoed (`a, b, c`, `2*a, b`), one per element.
  pure function echo_elements(value) result(items)
    character(len=*), intent(in) :: value
    character(len=40), allocatable :: items(:)
    character(len=:), allocatable :: rest, item
    integer :: c, star, n, ios, j
    allocate(items(0))
    rest = value
    do while (len_trim(rest) > 0)
      c = index(rest, ",")
      if (c == 0) c = len(rest) + 1
      item = trim(adjustl(rest(:c-1)))
      rest = rest(min(c + 1, len(rest) + 1):)
      if (len(item) == 0) cycle
      star = index(item, "*")
      n = 1
      if (star > 0) then
        read(item(:star-1), *, iostat=ios) n
        if (ios /= 0) n = 1
        item = item(star+1:)
      end if
      do j = 1, n
        items = [character(len=40) :: items, item]
      end do
    end do
  end function echo_elements

  !> Read the base scenario with the sweep's t_end and &fixed values (no
  !> varied input) through the scenario readers, so that a bad fixed value
  !> stops the sweep before any case runs.  `scratch` is a writable file name.
  subroutine check_common_settings(def, base, scratch, error)
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(base_scenario), intent(in) :: base               !< its base scenario
    character(len=*), intent(in) :: scratch               !< scratch file
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    type(nml_file) :: f
    type(scene_input) :: in
    call write_text_file(scratch, sweep_namelist(def, base, -1, [real(dp) ::], .false.), error)
    if (allocated(error)) return
    call f%load(scratch, error)
    if (.not. allocated(error)) call read_scene(f, in, error, base%scene)
    if (allocated(error)) error%message = replace(error%message, scratch, def%path // &
      " (base scenario with the sweep's t_end and &fixed values)")
  end subroutine check_common_settings

  !> The namelist text of a case: base text + the sweep's t_end + the fixed
  !> values + the case's values.
  function case_namelist(def, base, id, values) result(text)
    type(sweep_definition), intent(in) :: def   !< the sweep
    type(base_scenario), intent(in) :: base     !< its base scenario
    integer, intent(in) :: id                   !< case id (for the comment)
    real(dp), intent(in) :: values(:)           !< the case's values, in the order of def%inputs
    character(len=:), allocatable :: text
    text = sweep_namelist(def, base, id, values, .true.)
  end function case_namelist

  !> Base text + t_end + fixed values (+ the case's values if `varied`).
  !> An element of a vector, `wind(1) = v`, is written as such; the base's
  !> own assignments of that vector are taken out (whole or by elements: the
  !> readers refuse an element the whole vector also assigns), so its other
  !> elements are written one by one with the base's resolved values.
  function sweep_namelist(def, base, id, values, varied) result(text)
    type(sweep_definition), intent(in) :: def
    type(base_scenario), intent(in) :: base
    integer, intent(in) :: id
    real(dp), intent(in) :: values(:)
    logical, intent(in) :: varied
    character(len=:), allocatable :: text
    character(len=32), allocatable :: groups(:), names(:)
    integer, allocatable :: elements(:)
    character(len=1200), allocatable :: lines(:)
    logical, allocatable :: replaced(:)
    integer :: k, m, j
    allocate(groups(0), names(0), elements(0), lines(0))
    if (def%t_end > 0.0_dp) call add("run", "t_end", 0, "t_end = " // value_text(def%t_end) // "   ! sweep " // &
      def%name)
    do k = 1, size(def%fixed)
      call add(def%fixed(k)%group, def%fixed(k)%variable, def%fixed(k)%element, &
        target_name(def%fixed(k)%variable, def%fixed(k)%element) // " = " // def%fixed(k)%value // &
        "   ! sweep " // def%name // ", fixed")
    end do
    if (varied) then
      do k = 1, size(def%inputs)
        call add(def%inputs(k)%group, def%inputs(k)%variable, def%inputs(k)%element, &
          target_name(def%inputs(k)%variable, def%inputs(k)%element) // " = " // value_text(values(k)) // &
          "   ! sweep " // def%name // ", case " // str(id))
      end do
    end if
    call keep_other_elements()
    m = size(lines)
    if (.not. allocated(base%assigned)) then   ! not from load_base_scenario: nothing located
      text = inject_assignments(base%text, groups(1:m), lines(1:m))
      return
    end if
    allocate(replaced(size(base%assigned)))
    do k = 1, size(base%assigned)
      replaced(k) = .false.
      do j = 1, m
        if (lower(trim(groups(j))) == base%assigned(k)%group .and. lower(trim(names(j))) == base%assigned(k)%name) &
          replaced(k) = .true.
      end do
    end do
    text = inject_assignments(strike_assignments(base%text, pack(base%assigned, replaced)), &
      groups(1:m), lines(1:m))
  contains
    subroutine add(group, name, element, line)
      character(len=*), intent(in) :: group, name, line
      integer, intent(in) :: element
      groups = [character(len=32) :: groups, group]
      names = [character(len=32) :: names, name]
      elements = [elements, element]
      lines = [character(len=1200) :: lines, line]
    end subroutine add
    !> For each vector of which only elements are set: its other elements,
    !> with the base's resolved values.
    subroutine keep_other_elements()
      character(len=40), allocatable :: items(:)
      integer :: n, i, h, q
      n = size(lines)
      do i = 1, n
        if (elements(i) == 0) cycle
        if (any(groups(:i-1) == groups(i) .and. names(:i-1) == names(i))) cycle   ! done with its first
        if (.not. allocated(base%known)) cycle
        h = findloc(base%known%group == groups(i) .and. base%known%name == names(i), .true., dim=1)
        if (h == 0) cycle   ! refused by check_varied_inputs
        items = echo_elements(base%known(h)%value)
        do q = 1, size(items)
          if (any(groups(:n) == groups(i) .and. names(:n) == names(i) .and. elements(:n) == q)) cycle
          call add(groups(i), names(i), q, trim(names(i)) // "(" // str(q) // ") = " // trim(adjustl(items(q))) // &
            "   ! the base's value (sweep " // def%name // " sets another element)")
        end do
      end do
    end subroutine keep_other_elements
  end function sweep_namelist

  !> `variable` or `variable(element)`.
  pure function target_name(variable, element) result(s)
    character(len=*), intent(in) :: variable
    integer, intent(in) :: element
    character(len=:), allocatable :: s
    s = variable
    if (element > 0) s = s // "(" // str(element) // ")"
  end function target_name

  !> `text` without the assignments `items` (as located by nml_file%load in
  !> that text): an assignment alone on its lines is commented out there (so
  !> the case's namelist still shows the base's value), one that shares a line
  !> with other input is cut out of it.
  function strike_assignments(text, items) result(out)
    character(len=*), intent(in) :: text                !< namelist text
    type(nml_assignment), intent(in) :: items(:)        !< assignments to remove (not overlapping)
    character(len=:), allocatable :: out
    integer, allocatable :: starts(:)
    integer :: k, m, l, a, b
    integer, allocatable :: order(:)
    out = text
    ! start of each line in `text`
    allocate(starts(1))
    starts(1) = 1
    do k = 1, len(text)
      if (text(k:k) == new_line("a")) starts = [starts, k + 1]
    end do
    starts = [starts, len(text) + 2]
    ! last assignment first, so that the earlier positions stay valid
    order = [(k, k = 1, size(items))]
    do k = 2, size(order)
      m = k
      do while (m > 1)
        if (before(items(order(m-1)), items(order(m)))) exit
        order([m-1, m]) = order([m, m-1])
        m = m - 1
      end do
    end do
    do k = 1, size(order)
      associate(it => items(order(k)))
        if (it%first_line < 1 .or. it%last_line + 1 > size(starts)) cycle
        a = starts(it%first_line) + it%first_col - 1
        b = starts(it%last_line) + it%last_col - 1
        if (len_trim(out(starts(it%first_line):a-1)) == 0 .and. &
            rest_is_comment(out(b+1:starts(it%last_line+1)-2))) then
          do l = it%last_line, it%first_line, -1
            out = out(:starts(l)-1) // "! (set by the sweep below) " // out(starts(l):)
          end do
        else
          out = out(:a-1) // out(b+1:)
        end if
      end associate
    end do
  contains
    logical function before(p, q)
      type(nml_assignment), intent(in) :: p, q
      before = p%first_line > q%first_line .or. (p%first_line == q%first_line .and. p%first_col > q%first_col)
    end function before
    logical function rest_is_comment(s)
      character(len=*), intent(in) :: s
      character(len=len(s)) :: t
      t = adjustl(s)
      rest_is_comment = len_trim(t) == 0
      if (.not. rest_is_comment) rest_is_comment = t(1:1) == "!"
    end function rest_is_comment
  end function strike_assignments

  !> Run case `id`: write its namelist to `scratch`, read it, run it.  A
  !> trajectory is written to `trajectory` unless it is "".  A failure to
  !> write the scratch file is not a result of the case: it is returned in
  !> `file_error` (and `row` is not a result then).
  subroutine run_case(def, base, id, values, scratch, trajectory, row, file_error)
    type(sweep_definition), intent(in) :: def   !< the sweep
    type(base_scenario), intent(in) :: base     !< its base scenario
    integer, intent(in) :: id                   !< case id
    real(dp), intent(in) :: values(:)           !< the case's values
    character(len=*), intent(in) :: scratch     !< per-rank scratch file for the namelist
    character(len=*), intent(in) :: trajectory  !< trajectory file ("" for summary mode)
    type(sweep_row), intent(out) :: row         !< the result
    type(error_type), allocatable, intent(inout) :: file_error  !< set if the scratch file cannot be written
    type(scene_input) :: in
    type(launch_result) :: res
    type(line_result) :: line_res
    type(error_type), allocatable :: error
    character(len=:), allocatable :: summary
    integer(i8) :: c0, c1, rate

    call system_clock(c0, rate)
    call load_case(def, base, id, values, scratch, in, error, file_error)
    if (allocated(file_error)) return
    if (allocated(error)) then
      call system_clock(c1)
      row = invalid_row(id, replace(error%message, scratch, "case " // str(id)), real(c1 - c0, dp)/rate, &
        base%metrics)
      return
    end if
    in%run%trajectory = len(trajectory) > 0
    if (in%run%trajectory) in%run%output = trajectory
    if (base%scene == "line") then
      call run_line_scene(in%run, in%line_cfg, in%echo, summary, error, line_res)
      call system_clock(c1)
      if (allocated(error)) then
        row = row_from_line_result(id, line_res, .true., error%message, real(c1 - c0, dp)/rate)
      else
        row = row_from_line_result(id, line_res, .false., "", real(c1 - c0, dp)/rate)
      end if
      return
    end if
    call run_launch(in%run, in%cfg, in%echo, res, error)
    call system_clock(c1)
    if (allocated(error) .and. res%status == "invalid_input") then
      ! a case the aircraft cannot fly (its trim): rejected input, not a failed run
      row = invalid_row(id, "case " // str(id) // ": " // error%message, real(c1 - c0, dp)/rate, base%metrics)
    else if (allocated(error)) then
      row = row_from_result(id, res, .true., error%message, real(c1 - c0, dp)/rate)
    else
      row = row_from_result(id, res, .false., "", real(c1 - c0, dp)/rate)
    end if
  end subroutine run_case

  !> Run case `id` again with its full output into `trajectory`.  `written`:
  !> the file exists afterwards.  A file error (the scratch namelist, or the
  !> trajectory file that the run began to write and could not finish) is
  !> returned in `file_error`; a case that fails before its first output
  !> record (e.g. in the trim) writes no file and is no file error, but a
  !> case that ran without error and left no file is one (so is a file name
  !> longer than a run's output can hold).
  subroutine run_trajectory(def, base, id, values, scratch, trajectory, written, file_error)
    type(sweep_definition), intent(in) :: def   !< the sweep
    type(base_scenario), intent(in) :: base     !< its base scenario
    integer, intent(in) :: id                   !< case id
    real(dp), intent(in) :: values(:)           !< the case's values
    character(len=*), intent(in) :: scratch     !< per-rank scratch file for the namelist
    character(len=*), intent(in) :: trajectory  !< trajectory file
    logical, intent(out) :: written             !< the trajectory file exists
    type(error_type), allocatable, intent(inout) :: file_error  !< set on a file error
    type(scene_input) :: in
    type(launch_result) :: res
    type(line_result) :: line_res
    type(error_type), allocatable :: error
    character(len=:), allocatable :: summary
    logical :: exists
    written = .false.
    call load_case(def, base, id, values, scratch, in, error, file_error)
    if (allocated(file_error)) return
    if (allocated(error)) return   ! an invalid case: no trajectory (the summary holds its message)
    if (len(trajectory) > len(in%run%output)) then
      ! refused by the definition check (output_dir); never cut the name short
      call fatal_error(file_error, "case " // str(id) // ": cannot write its trajectory: the file name " // &
        trajectory // " is " // str(len(trajectory)) // " characters long; a run's output holds at most " // &
        str(len(in%run%output)))
      return
    end if
    in%run%trajectory = .true.
    in%run%output = trajectory
    if (base%scene == "line") then
      call run_line_scene(in%run, in%line_cfg, in%echo, summary, error, line_res)
      if (allocated(line_res%output_error)) then
        call fatal_error(file_error, "case " // str(id) // ": cannot write its trajectory: " // &
          line_res%output_error)
        return
      end if
    else
      call run_launch(in%run, in%cfg, in%echo, res, error)
      if (allocated(res%output_error)) then
        call fatal_error(file_error, "case " // str(id) // ": cannot write its trajectory: " // res%output_error)
        return
      end if
    end if
    inquire(file=trajectory, exist=exists)
    written = exists
    ! no file is a result of the case only when the case failed (before its
    ! first output record); a run that ended without error wrote its file
    if (.not. exists .and. .not. allocated(error)) call fatal_error(file_error, "case " // str(id) // &
      ": cannot write its trajectory: the run ended without error but " // trajectory // " does not exist")
  end subroutine run_trajectory

  !> Write case `id`'s namelist to `scratch` and read it: a write failure is
  !> `file_error` (not a result of the case), bad input `error`.
  subroutine load_case(def, base, id, values, scratch, in, error, file_error)
    type(sweep_definition), intent(in) :: def   !< the sweep
    type(base_scenario), intent(in) :: base     !< its base scenario
    integer, intent(in) :: id                   !< case id
    real(dp), intent(in) :: values(:)           !< the case's values
    character(len=*), intent(in) :: scratch     !< per-rank scratch file for the namelist
    type(scene_input), intent(out) :: in        !< its inputs
    type(error_type), allocatable, intent(inout) :: error       !< set on bad input
    type(error_type), allocatable, intent(inout) :: file_error  !< set if the scratch file cannot be written
    type(nml_file) :: f
    call write_text_file(scratch, case_namelist(def, base, id, values), file_error)
    if (allocated(file_error)) then
      file_error%message = "case " // str(id) // ": " // file_error%message
      return
    end if
    call f%load(scratch, error)
    if (.not. allocated(error)) call read_scene(f, in, error, base%scene)
  end subroutine load_case

  !> Read a scenario: &run, then the groups of its scene (the airlaunch
  !> scene's, or the line scene's with the line scheme's own rtol, atol and
  !> largest order where &run does not set them, as `airlaunch` runs it).
  !> `scene`: the scene the sweep's base runs (a case may not change it).
  subroutine read_scene(f, in, error, scene)
    type(nml_file), intent(inout) :: f                    !< scanned input
    type(scene_input), intent(out) :: in                  !< what it says
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    character(len=*), intent(in), optional :: scene       !< the base's scene
    call read_run_config(f, in%run, in%echo, error)
    if (allocated(error)) return
    if (present(scene)) then
      if (trim(in%run%scene) /= trim(scene)) then
        call fatal_error(error, f%path // ": &run: scene = '" // trim(in%run%scene) // "' is not allowed (the " // &
          "base scenario's scene is '" // trim(scene) // "')")
        return
      end if
    end if
    select case (trim(in%run%scene))
    case ("airlaunch")
      call read_scenario_config(f, in%cfg, in%echo, error)
    case ("line")
      call f%check_groups([character(len=16) :: "run", "line", "line_scene", "parachute"], error)
      if (.not. allocated(error)) call read_line_scene_config(f, in%run, in%line_cfg, in%echo, error)
      if (allocated(error)) return
      in%run%rtol = in%line_cfg%integration%rtol
      in%run%atol = in%line_cfg%integration%atol
      in%run%max_order = in%line_cfg%integration%max_order
    case default
      call fatal_error(error, f%path // ": &run: scene = '" // trim(in%run%scene) // "' cannot be swept " // &
        "(allowed: 'airlaunch', 'line')")
    end select
  end subroutine read_scene

  !> Insert line(k) before the end of group groups(k) in `text` (appending
  !> the group if the text lacks it).  Comments and strings are respected.
  function inject_assignments(text, groups, lines) result(out)
    character(len=*), intent(in) :: text         !< namelist text
    character(len=*), intent(in) :: groups(:)    !< group of each assignment
    character(len=*), intent(in) :: lines(:)     !< assignments `name = value`
    character(len=:), allocatable :: out
    character(len=32), allocatable :: names(:)
    integer, allocatable :: ends(:)
    character(len=1), parameter :: nl = new_line("a")
    character(len=:), allocatable :: extra
    integer :: k, j, prev
    logical, allocatable :: used(:)

    call group_ends(text, names, ends)
    allocate(used(size(groups)))
    used = .false.
    out = ""
    prev = 1
    do j = 1, size(names)
      extra = ""
      do k = 1, size(groups)
        if (lower(trim(groups(k))) == trim(names(j)) .and. .not. used(k)) then
          extra = extra // "  " // trim(lines(k)) // nl
          used(k) = .true.
        end if
      end do
      if (len(extra) > 0) then
        out = out // text(prev:ends(j)-1) // nl // extra
        prev = ends(j)
      end if
    end do
    out = out // text(prev:)
    if (len(out) > 0) then
      if (out(len(out):) /= nl) out = out // nl
    end if
    do k = 1, size(groups)
      if (used(k)) cycle
      out = out // "&" // lower(trim(groups(k))) // nl // "  " // trim(lines(k)) // nl
      used(k) = .true.
      do j = k + 1, size(groups)
        if (lower(trim(groups(j))) == lower(trim(groups(k))) .and. .not. used(j)) then
          out = out // "  " // trim(lines(j)) // nl
          used(j) = .true.
        end if
      end do
      out = out // "/" // nl
    end do
  end function inject_assignments

  !> The groups of a namelist text and the position of the character that
  !> ends each (its `/`, or the `&` of `&end`).
  subroutine group_ends(text, names, ends)
    character(len=*), intent(in) :: text
    character(len=32), allocatable, intent(out) :: names(:)
    integer, allocatable, intent(out) :: ends(:)
    integer :: i, j, n
    logical :: in_group
    character :: quote, c
    allocate(names(0), ends(0))
    n = len(text)
    i = 1
    in_group = .false.
    quote = " "
    do while (i <= n)
      c = text(i:i)
      if (quote /= " ") then
        if (c == quote) quote = " "
        i = i + 1
        cycle
      end if
      if (c == "!") then
        j = index(text(i:), new_line("a"))
        if (j == 0) exit
        i = i + j
        cycle
      end if
      if (c == "&" .or. c == "$") then
        j = i + 1
        do while (j <= n)
          if (.not. is_name_char(text(j:j))) exit
          j = j + 1
        end do
        if (lower(text(i+1:j-1)) == "end") then
          if (in_group) ends(size(ends)) = i
          in_group = .false.
        else if (.not. in_group) then
          names = [character(len=32) :: names, lower(text(i+1:j-1))]
          ends = [ends, n + 1]
          in_group = .true.
        end if
        i = j
        cycle
      end if
      if (in_group) then
        if (c == "'" .or. c == '"') then
          quote = c
        else if (c == "/") then
          ends(size(ends)) = i
          in_group = .false.
        end if
      end if
      i = i + 1
    end do
  end subroutine group_ends

  !> Namelist text of a value: an integer if it is one, else 17 significant
  !> digits (reads back bit for bit).
  function value_text(x) result(s)
    real(dp), intent(in) :: x   !< value
    character(len=:), allocatable :: s
    character(len=40) :: buf
    if (x == aint(x) .and. abs(x) < 1.0e15_dp) then
      write(buf, '(i0)') int(x, i8)
    else
      write(buf, '(es25.16e3)') x
    end if
    s = trim(adjustl(buf))
  end function value_text

  !> Kind of a value as the runtime writes it in the resolved input.
  pure function value_kind(v) result(k)
    character(len=*), intent(in) :: v
    character(len=8) :: k
    character(len=:), allocatable :: u
    u = trim(adjustl(v))
    if (len(u) > 0) then
      if (u(len(u):) == ",") u = trim(u(:len(u)-1))
    end if
    if (len(u) == 0) then
      k = "string"
    else if (u(1:1) == "'" .or. u(1:1) == '"') then
      k = "string"
    else if (u == "T" .or. u == "F" .or. u == ".TRUE." .or. u == ".FALSE." .or. u == ".true." .or. &
      u == ".false.") then
      k = "logical"
    else if (scan(u, ",*") > 0) then   ! several values (`x, y, z`, `3*0.0`): a vector
      k = "vector"
    else if (scan(u, ".eEdD") > 0) then
      k = "real"
    else
      k = "integer"
    end if
  end function value_kind

  !> `s` with every occurrence of `old` replaced by `new`.
  pure function replace(s, old, new) result(t)
    character(len=*), intent(in) :: s, old, new
    character(len=:), allocatable :: t
    integer :: i, p
    t = ""
    i = 1
    if (len(old) == 0) then
      t = s
      return
    end if
    do
      p = index(s(i:), old)
      if (p == 0) exit
      t = t // s(i:i+p-2) // new
      i = i + p - 1 + len(old)
    end do
    t = t // s(i:)
  end function replace

  pure logical function is_name_char(c)
    character, intent(in) :: c
    is_name_char = (c >= "a" .and. c <= "z") .or. (c >= "A" .and. c <= "Z") .or. (c >= "0" .and. c <= "9") &
      .or. c == "_"
  end function is_name_char

  !> " (did you mean 'x'?)" for the nearest variable of the group (edit distance <= 2).
  function closest(name, known, group) result(s)
    character(len=*), intent(in) :: name, group
    type(known_variable), intent(in) :: known(:)
    character(len=:), allocatable :: s
    integer :: j, d, best
    s = ""
    best = 3
    do j = 1, size(known)
      if (known(j)%group /= group) cycle
      d = edit_distance(name, trim(known(j)%name))
      if (d < best) then
        best = d
        s = " (did you mean '" // trim(known(j)%name) // "'?)"
      end if
    end do
  end function closest

end module airlaunch_sweep_case
