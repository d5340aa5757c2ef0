!> The journal of a sweep: OUTPUT_DIR/journal/rank_NNNN.txt, one append-only
!> file per rank, one line per finished case (airlaunch_sweep_row), written
!> with one unbuffered write(2) per row (O_APPEND), each byte count checked, so
!> a kill loses only the cases in flight and a full disk is an error at the
!> first row it would lose.  Every run
!> creates the files of its ranks before any case runs, so the files present
!> are always rank_0000 ... rank_M-1 and a reader finds them all by counting.
!>
!> OUTPUT_DIR/journal/fingerprint.txt records what the rows were computed from
!> (code version, base scenario text, table values, t_end); a rerun with a
!> different fingerprint refuses to mix its rows with the old ones.
!>
!> OUTPUT_DIR/journal/environments.txt names the runtime numerical
!> environments the rows were computed in (airlaunch_runtime_env: BLAS kernel,
!> libm, libraries, processor), one line `<tag> <environment>` each, the tag
!> (FNV-1a of the text) the one each row carries: ranks on different node
!> types give the same case other bits, and the summary says which ran where.
module airlaunch_sweep_journal
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_sweep_files, only: file_exists, delete_file, read_text_file, replace_text_file, open_for_writing, &
    write_bytes, close_file
  use airlaunch_sweep_row, only: sweep_row, format_row, parse_row
  implicit none
  private
  public :: journal_writer, journal_file, read_journals, check_fingerprint, check_ran_settings, remove_journal, fnv1a
  public :: record_environments, read_environments, environment_len

  !> Largest number of rank files looked for.
  integer, parameter :: max_rank_files = 100000
  !> Longest environment line kept (airlaunch_runtime_env's line: some 600
  !> characters; a longer one is cut).
  integer, parameter :: environment_len = 2048

  !> One rank's open journal.
  type :: journal_writer
    integer :: fd = -1                        !< POSIX file descriptor (O_APPEND)
    character(len=:), allocatable :: path
  contains
    procedure :: open => jw_open
    procedure :: append => jw_append
    procedure :: close => jw_close
  end type journal_writer

contains

  !> DIR/rank_NNNN.txt
  function journal_file(dir, rank) result(p)
    character(len=*), intent(in) :: dir   !< journal directory
    integer, intent(in) :: rank           !< MPI rank
    character(len=:), allocatable :: p
    character(len=16) :: buf
    write(buf, '(i4.4)') rank
    p = dir // "/rank_" // trim(buf) // ".txt"
  end function journal_file

  !> Open (create or append to) the rank's journal.  A last line cut short by
  !> a kill is closed with a new line first, so the next row starts clean.
  subroutine jw_open(self, dir, rank, error)
    class(journal_writer), intent(inout) :: self
    character(len=*), intent(in) :: dir                   !< journal directory
    integer, intent(in) :: rank                           !< MPI rank
    type(error_type), allocatable, intent(inout) :: error !< set if not writable
    integer :: ios, fsize, unit
    character(len=1) :: last
    self%path = journal_file(dir, rank)
    last = new_line("a")
    if (file_exists(self%path)) then
      open(newunit=unit, file=self%path, access="stream", form="unformatted", status="old", &
        action="read", iostat=ios)
      if (ios == 0) then
        inquire(unit=unit, size=fsize)
        if (fsize > 0) read(unit, pos=fsize, iostat=ios) last
        close(unit)
      end if
    end if
    call open_for_writing(self%path, .true., self%fd, error)
    if (allocated(error)) then
      error%message = self%path // ": cannot open the journal for appending (" // error%message // ")"
      return
    end if
    if (last /= new_line("a")) call write_bytes(self%fd, new_line("a"), error)
    if (allocated(error)) then
      error%message = self%path // ": cannot end the journal's torn last line (" // error%message // ")"
      call close_file(self%fd, error)
    end if
  end subroutine jw_open

  !> Append one row: one write(2) of the whole line, every byte checked (a
  !> full disk is an error here, not a row lost in a buffer).
  subroutine jw_append(self, row, error)
    class(journal_writer), intent(inout) :: self
    type(sweep_row), intent(in) :: row                    !< finished case
    type(error_type), allocatable, intent(inout) :: error !< set if the write fails
    call write_bytes(self%fd, format_row(row) // new_line("a"), error)
    if (allocated(error)) error%message = self%path // ": cannot append the row of case " // str(row%id) // &
      " to the journal (" // error%message // ")"
  end subroutine jw_append

  !> Close the journal; a failure of close(2) sets `error` if present.
  subroutine jw_close(self, error)
    class(journal_writer), intent(inout) :: self
    type(error_type), allocatable, intent(inout), optional :: error !< set if close fails
    type(error_type), allocatable :: err
    if (self%fd < 0) return
    call close_file(self%fd, err)
    if (allocated(err) .and. present(error)) then
      if (.not. allocated(error)) call fatal_error(error, self%path // ": cannot close the journal (" // &
        err%message // ")")
    end if
  end subroutine jw_close

  !> Read every rank file of `dir`: rows(id+1) and done(id+1) for the valid
  !> rows with ids in [0, n_cases); a second valid row of an id counts in
  !> `duplicates`, a torn or corrupt line in `bad` - unless its case id can
  !> still be read whole and that case has a valid row (a line torn by a kill
  !> whose case ran again later: no longer news).
  subroutine read_journals(dir, n_cases, n_metrics, rows, done, duplicates, bad, error)
    character(len=*), intent(in) :: dir                   !< journal directory
    integer, intent(in) :: n_cases                        !< number of cases
    integer, intent(in) :: n_metrics                      !< summary variables of the sweep's scene
    type(sweep_row), allocatable, intent(out) :: rows(:)  !< rows by id + 1
    logical, allocatable, intent(out) :: done(:)          !< finished, by id + 1
    integer, intent(out) :: duplicates                    !< extra rows of finished ids
    integer, intent(out) :: bad                           !< lines that are not rows
    type(error_type), allocatable, intent(inout) :: error !< set if a file is unreadable
    integer :: r, unit, ios, torn_id
    character(len=:), allocatable :: path, line
    type(sweep_row) :: row
    logical :: ok
    integer, allocatable :: torn(:)
    allocate(rows(n_cases), done(n_cases), torn(0))
    done = .false.
    duplicates = 0
    bad = 0
    do r = 0, max_rank_files - 1
      path = journal_file(dir, r)
      if (.not. file_exists(path)) exit
      open(newunit=unit, file=path, status="old", action="read", iostat=ios)
      if (ios /= 0) then
        call fatal_error(error, path // ": cannot read the journal")
        return
      end if
      do
        call read_line(unit, line, ios)
        if (ios /= 0) exit
        if (len_trim(line) == 0) cycle
        call parse_row(line, n_metrics, row, ok)
        if (ok) ok = row%id < n_cases
        if (.not. ok) then
          torn_id = torn_line_id(line)
          if (torn_id >= 0 .and. torn_id < n_cases) then
            torn = [torn, torn_id]
          else
            bad = bad + 1
          end if
        else if (done(row%id + 1)) then
          duplicates = duplicates + 1
        else
          rows(row%id + 1) = row
          done(row%id + 1) = .true.
        end if
      end do
      close(unit)
    end do
    do r = 1, size(torn)
      if (.not. done(torn(r) + 1)) bad = bad + 1
    end do
  end subroutine read_journals

  !> The case id of a line that is not a valid row, if it can be read whole
  !> (8 hex digits, a blank, the id's digits, a blank after them); else -1.
  function torn_line_id(line) result(id)
    character(len=*), intent(in) :: line
    integer :: id
    integer :: q, ios
    id = -1
    if (len(line) < 11) return
    if (line(9:9) /= " " .or. verify(line(1:8), "0123456789abcdefABCDEF") /= 0) return
    q = index(line(10:), " ")
    if (q < 2 .or. q > 10) return   ! no blank after the id (cut inside it), or no id
    if (verify(line(10:8+q), "0123456789") /= 0) return
    read(line(10:8+q), *, iostat=ios) id
    if (ios /= 0) id = -1
  end function torn_line_id

  !> Compare the journal's fingerprint with `text`; write it if there is none
  !> (atomically: a fingerprint cut short by a full disk is never left).
  !> `differs` (if present) tells a different sweep's journal (bad input)
  !> from a file that cannot be read or written.
  subroutine check_fingerprint(dir, text, error, differs)
    character(len=*), intent(in) :: dir                   !< journal directory
    character(len=*), intent(in) :: text                  !< this sweep's fingerprint
    type(error_type), allocatable, intent(inout) :: error !< set if they differ or on a file error
    logical, intent(out), optional :: differs             !< the error is a different fingerprint
    character(len=:), allocatable :: path, have
    if (present(differs)) differs = .false.
    path = dir // "/fingerprint.txt"
    if (file_exists(path)) then
      call read_text_file(path, have, error)
      if (allocated(error)) return
      if (have /= text) then
        call fatal_error(error, dir // ": the journal holds cases of a different sweep (" // &
          first_difference(have, text) // "); rerun with --restart to discard them, or use another output_dir")
        if (present(differs)) differs = .true.
      end if
    else
      call replace_text_file(path, text, error)
    end if
  end subroutine check_fingerprint

  !> A query of a sweep that ran (--case-namelist): the settings its journal's
  !> fingerprint records (the base's text, t_end, the inputs, the fixed values,
  !> the table's values) must be those of `text`, this sweep's fingerprint now,
  !> or the case's namelist now would not be the case the sweep ran (an edited
  !> base or definition).  The base's path and the code may differ: the text
  !> decides, and `ran_digest` returns the code digest the rows were computed
  !> with ('' if the same as `text`'s, or if the sweep never ran: no
  !> fingerprint, nothing to compare).  Nothing is written.
  subroutine check_ran_settings(dir, text, error, ran_digest)
    character(len=*), intent(in) :: dir                   !< journal directory
    character(len=*), intent(in) :: text                  !< this sweep's fingerprint
    type(error_type), allocatable, intent(inout) :: error !< set if the settings differ, or on a read error
    character(len=:), allocatable, intent(out) :: ran_digest !< the journal's code digest, if another
    character(len=:), allocatable :: path, have
    ran_digest = ""
    path = dir // "/fingerprint.txt"
    if (.not. file_exists(path)) return
    call read_text_file(path, have, error)
    if (allocated(error)) return
    if (settings_of(have) /= settings_of(text)) then
      call fatal_error(error, dir // ": the sweep ran other settings than its definition gives now (" // &
        first_difference(settings_of(have), settings_of(text)) // "): the case's namelist would not be " // &
        "the case the sweep ran (restore the base scenario and the definition as they were)")
      return
    end if
    if (line_of(have, "code_digest = ") /= line_of(text, "code_digest = ")) &
      ran_digest = line_of(have, "code_digest = ")
  end subroutine check_ran_settings

  !> A fingerprint's lines but the code's digest and the base's path.
  function settings_of(text) result(s)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: s, line
    integer :: p, q
    s = ""
    p = 1
    do while (p <= len(text))
      q = index(text(p:), new_line("a"))
      if (q == 0) q = len(text) - p + 2
      line = text(p:p+q-2)
      if (index(line, "code_digest = ") /= 1 .and. index(line, "base = ") /= 1) s = s // line // new_line("a")
      p = p + q
    end do
  end function settings_of

  !> The rest of the first line of `text` that starts with `key` ('' if none).
  function line_of(text, key) result(s)
    character(len=*), intent(in) :: text, key
    character(len=:), allocatable :: s
    integer :: p, q
    s = ""
    p = index(new_line("a") // text, new_line("a") // key)
    if (p == 0) return
    p = p + len(key)
    q = index(text(p:), new_line("a"))
    if (q == 0) q = len(text) - p + 2
    s = text(p:p+q-2)
  end function line_of

  !> Delete the journal files, the fingerprint and the environments (--restart).
  subroutine remove_journal(dir)
    character(len=*), intent(in) :: dir   !< journal directory
    integer :: r
    do r = 0, max_rank_files - 1
      if (.not. file_exists(journal_file(dir, r))) exit
      call delete_file(journal_file(dir, r))
    end do
    call delete_file(dir // "/fingerprint.txt")
    call delete_file(dir // "/environments.txt")
  end subroutine remove_journal

  !> Add to DIR/environments.txt the environments of `texts` (one line each,
  !> several ranks may share one) it does not hold yet, as `<fnv1a> <text>`
  !> lines; the file is replaced whole (a full disk leaves the old one).
  subroutine record_environments(dir, texts, error)
    character(len=*), intent(in) :: dir                   !< journal directory
    character(len=*), intent(in) :: texts(:)              !< environment lines (blank-padded)
    type(error_type), allocatable, intent(inout) :: error !< set on a file error
    character(len=16), allocatable :: tags(:)
    character(len=environment_len), allocatable :: have_texts(:)
    character(len=:), allocatable :: text
    integer :: k
    logical :: added
    call read_environments(dir, tags, have_texts, error)
    if (allocated(error)) return
    text = ""
    do k = 1, size(tags)
      text = text // tags(k) // " " // trim(have_texts(k)) // new_line("a")
    end do
    added = .false.
    do k = 1, size(texts)
      if (any(tags == fnv1a(trim(texts(k))))) cycle
      tags = [tags, fnv1a(trim(texts(k)))]
      text = text // fnv1a(trim(texts(k))) // " " // trim(texts(k)) // new_line("a")
      added = .true.
    end do
    if (added) call replace_text_file(dir // "/environments.txt", text, error)
  end subroutine record_environments

  !> The environments of DIR/environments.txt: tags(k) names texts(k) (none
  !> without the file; a line that is not `<16 hex digits> <text>` is skipped).
  subroutine read_environments(dir, tags, texts, error)
    character(len=*), intent(in) :: dir                   !< journal directory
    character(len=16), allocatable, intent(out) :: tags(:) !< the tags
    character(len=environment_len), allocatable, intent(out) :: texts(:) !< their environments
    type(error_type), allocatable, intent(inout) :: error !< set if the file is unreadable
    character(len=:), allocatable :: path, text, line
    integer :: p, q
    allocate(tags(0), texts(0))
    path = dir // "/environments.txt"
    if (.not. file_exists(path)) return
    call read_text_file(path, text, error)
    if (allocated(error)) return
    p = 1
    do while (p <= len(text))
      q = index(text(p:), new_line("a"))
      if (q == 0) q = len(text) - p + 2
      line = text(p:p+q-2)
      p = p + q
      if (.not. is_environment_line(line)) cycle
      tags = [tags, line(1:16)]
      texts = [character(len=environment_len) :: texts, line(18:)]
    end do
  end subroutine read_environments

  !> `<16 hex digits> <text>`.
  pure logical function is_environment_line(line)
    character(len=*), intent(in) :: line
    is_environment_line = .false.
    if (len(line) < 18) return
    if (line(17:17) /= " ") return
    is_environment_line = verify(line(1:16), "0123456789abcdefABCDEF") == 0
  end function is_environment_line

  !> 64-bit FNV-1a hash of a string, as 16 hex digits.
  function fnv1a(s) result(h)
    character(len=*), intent(in) :: s   !< bytes to hash
    character(len=16) :: h
    integer(i8) :: x
    integer(i8), parameter :: prime = 1099511628211_i8
    integer :: i
    x = -3750763034362895579_i8   ! 14695981039346656037 as a signed 64-bit integer
    do i = 1, len(s)
      x = ieor(x, int(iachar(s(i:i)), i8))
      x = x*prime                    ! wraps modulo 2^64 (two's complement)
    end do
    write(h, '(z16.16)') x
  end function fnv1a

  !> "name: old -> new" of the first line that differs.
  function first_difference(a, b) result(s)
    character(len=*), intent(in) :: a, b
    character(len=:), allocatable :: s, la, lb
    integer :: pa, pb, qa, qb
    pa = 1
    pb = 1
    s = "fingerprints differ"
    do while (pa <= len(a) .and. pb <= len(b))
      qa = index(a(pa:), new_line("a"))
      qb = index(b(pb:), new_line("a"))
      if (qa == 0) qa = len(a) - pa + 2
      if (qb == 0) qb = len(b) - pb + 2
      la = a(pa:pa+qa-2)
      lb = b(pb:pb+qb-2)
      if (la /= lb) then
        s = "was " // la // ", now " // lb
        return
      end if
      pa = pa + qa
      pb = pb + qb
    end do
  end function first_difference

  !> Read one line of any length.
  subroutine read_line(unit, line, ios)
    integer, intent(in) :: unit
    character(len=:), allocatable, intent(out) :: line
    integer, intent(out) :: ios
    character(len=4096) :: buf
    integer :: n
    line = ""
    do
      read(unit, '(a)', advance="no", iostat=ios, size=n) buf
      line = line // buf(:n)
      if (is_iostat_eor(ios)) then
        ios = 0
        return
      end if
      if (ios /= 0) return
    end do
  end subroutine read_line
end module airlaunch_sweep_journal
