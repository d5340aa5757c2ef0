!> Sweep journal rows and files: checksums against published test vectors,
!> rows that read back bit for bit (NaN, -0, subnormals, extremes), every
!> truncation of a line rejected (a kill mid-write never yields a wrong row),
!> a torn last line closed before the next row, duplicates counted; a full
!> device (/dev/full: every write(2) fails with ENOSPC) is an error at once for
!> a whole file and for a journal row, and a large file is written in full;
!> a row's runtime-environment tag reads back (none as none, a malformed one
!> rejected), and the environments file keeps each environment once.
program test_sweep_journal
  use, intrinsic :: iso_fortran_env, only: int64
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_sweep_row
  use airlaunch_sweep_journal
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  use airlaunch_sweep_files, only: make_dir, delete_file, write_text_file, read_text_file
  use testing
  implicit none
  type(sweep_row) :: row, back
  type(sweep_row), allocatable :: rows(:)
  logical, allocatable :: done(:)
  logical :: ok, all_rejected, same
  character(len=:), allocatable :: line, dir
  type(journal_writer) :: jw
  type(error_type), allocatable :: error
  integer :: i, k, dup, bad, u, n_metrics
  type(metric_set) :: launch_set, line_set
  real(dp) :: nan
  character(len=:), allocatable :: big, back_text
  character(len=16), allocatable :: env_tags(:)
  character(len=8) :: sum_text
  character(len=environment_len), allocatable :: env_texts(:)
  interface
    integer(c_int) function c_symlink(target, linkpath) bind(C, name="symlink")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: target(*), linkpath(*)
    end function c_symlink
    integer(c_int) function c_unlink(path) bind(C, name="unlink")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_unlink
  end interface

  call section("checksums: published test vectors")
  ! Adler-32 of "Wikipedia" is 0x11E60398 (RFC 1950 algorithm, Wikipedia's example)
  call check(adler32("Wikipedia") == int(z'11E60398', int64), "adler32('Wikipedia') = 11E60398")
  call check(adler32("") == 1_int64, "adler32('') = 1")
  ! FNV-1a 64-bit test vectors (Fowler, Noll, Vo reference code)
  call check(fnv1a("") == "CBF29CE484222325", "fnv1a64('') = cbf29ce484222325")
  call check(fnv1a("a") == "AF63DC4C8601EC8C", "fnv1a64('a') = af63dc4c8601ec8c")
  call check(fnv1a("foobar") == "85944171F73967E8", "fnv1a64('foobar') = 85944171f73967e8")

  call section("a row reads back bit for bit")
  launch_set = metrics_of("airlaunch")
  line_set = metrics_of("line")
  n_metrics = launch_set%size()
  allocate(row%metrics(n_metrics))
  nan = ieee_value(1.0_dp, ieee_quiet_nan)
  row%id = 4711
  row%status = status_failed
  do k = 1, n_metrics
    row%metrics(k) = (-1.0_dp)**k*exp(real(k, dp))/3.0_dp
  end do
  row%metrics(1) = nan
  row%metrics(2) = -0.0_dp
  row%metrics(3) = tiny(1.0_dp)/2**20       ! subnormal
  row%metrics(4) = huge(1.0_dp)
  row%metrics(5) = -huge(1.0_dp)
  row%metrics(6) = 0.1_dp + 0.2_dp
  row%message = "free flight, t = 12.5 s: altitude -2000.0 m | below the atmosphere model / 100% sure"
  line = format_row(row)
  call parse_row(line, n_metrics, back, ok)
  call check(ok, "the line parses")
  call check(back%id == row%id .and. back%status == row%status, "id and status")
  call check(ieee_is_nan(back%metrics(1)), "NaN stays NaN")
  same = .true.
  do k = 2, n_metrics
    same = same .and. transfer(back%metrics(k), 1_int64) == transfer(row%metrics(k), 1_int64)
  end do
  call check(same, "every other metric identical bit for bit (-0, subnormal, +-huge, 0.1+0.2)")
  call check(back%message == row%message, "message kept whole")
  call check(back%environment == "", "no environment tag: none read back")
  row%environment = fnv1a("cpu_model=A; blas_core=Haswell")
  line = format_row(row)
  call parse_row(line, n_metrics, back, ok)
  call check(ok .and. back%environment == row%environment .and. back%message == row%message, &
    "an environment tag reads back (" // row%environment // "), the message with it")
  k = index(line, row%environment)
  line = line(:k+14) // "g" // line(k+16:)   ! not a hex digit (the checksum made to match)
  line = line(10:)
  write(sum_text, '(z8.8)') adler32(line)
  call parse_row(sum_text // " " // line, n_metrics, back, ok)
  call check(.not. ok, "a tag that is not 16 hex digits: rejected (checksum right)")
  row%environment = ""

  call section("a cut or corrupted line is rejected")
  all_rejected = .true.
  do i = 0, len(line) - 1
    call parse_row(line(1:i), n_metrics, back, ok)
    all_rejected = all_rejected .and. .not. ok
  end do
  call check(all_rejected, "all " // trim(itoa(len(line))) // " truncations rejected")
  k = index(line, "E+000")
  call parse_row(line(:k-2) // achar(iachar(line(k-1:k-1)) + 1) // line(k:), n_metrics, back, ok)
  call check(.not. ok, "one digit changed: rejected")
  call parse_row(line, line_set%size(), back, ok)
  call check(.not. ok, "a row of the airlaunch scene's " // trim(itoa(n_metrics)) // " metrics is not one of " // &
    "the line scene's " // trim(itoa(line_set%size())))

  call section("journal files: append, torn last line, duplicates")
  dir = "sweep_journal_test"
  call make_dir(dir, error)
  call check(.not. allocated(error), "directory made")
  call remove_journal(dir)
  call jw%open(dir, 0, error)
  row%status = status_ok
  row%message = ""
  do i = 0, 2
    row%id = i
    call jw%append(row, error)
  end do
  call jw%close()
  ! a kill in the middle of the row of case 3: no new line at the end
  open(newunit=u, file=journal_file(dir, 0), access="stream", form="unformatted", position="append")
  row%id = 3
  line = format_row(row)
  write(u) line(1:len(line)/2)
  close(u)
  call jw%open(dir, 0, error)
  row%id = 4
  call jw%append(row, error)
  row%id = 1                      ! the same case twice (two runs on one directory)
  call jw%append(row, error)
  call jw%close()
  call jw%open(dir, 1, error)     ! a second rank's file
  row%id = 5
  call jw%append(row, error)
  call jw%close()
  call read_journals(dir, 6, n_metrics, rows, done, dup, bad, error)
  call check(.not. allocated(error), "journals read")
  call check(all(done .eqv. [.true., .true., .true., .false., .true., .true.]), &
    "cases 0, 1, 2, 4 (after the torn line) and 5 (rank 1) done; case 3 not")
  call check(bad == 1, "one torn line ignored")
  call check(dup == 1, "one duplicate counted")
  call check(rows(5)%id == 4 .and. rows(6)%id == 5, "rows stored by id")
  ! case 3 runs again later: its torn line is no longer counted; a line cut
  ! inside its id (no blank after it) still is
  call jw%open(dir, 1, error)
  row%id = 3
  call jw%append(row, error)
  call jw%close()
  open(newunit=u, file=journal_file(dir, 1), access="stream", form="unformatted", position="append")
  write(u) "0A1B2C3D 3"
  close(u)
  call read_journals(dir, 6, n_metrics, rows, done, dup, bad, error)
  call check(all(done), "every case done once case 3 has a row")
  call check(bad == 1, "the torn row of case 3 (which has a row now) not counted; a line cut inside its id is: " &
    // trim(itoa(bad)))
  call remove_journal(dir)
  call delete_file(dir // "/fingerprint.txt")

  call section("environments: each once, read back")
  ! three ranks, two of them alike; a second run adds a third environment
  call record_environments(dir, [character(len=environment_len) :: "blas_core=Haswell", "blas_core=SkylakeX", &
    "blas_core=Haswell"], error)
  call check(.not. allocated(error), "recorded")
  call read_environments(dir, env_tags, env_texts, error)
  call check(size(env_tags) == 2, "two distinct environments of three ranks: " // trim(itoa(size(env_tags))))
  call check(env_tags(1) == fnv1a("blas_core=Haswell") .and. env_texts(1) == "blas_core=Haswell" .and. &
    env_tags(2) == fnv1a("blas_core=SkylakeX") .and. env_texts(2) == "blas_core=SkylakeX", &
    "each line: the FNV-1a tag of its text, the text")
  call record_environments(dir, [character(len=environment_len) :: "blas_core=SkylakeX", "blas_core=Zen"], error)
  call read_environments(dir, env_tags, env_texts, error)
  call check(size(env_tags) == 3 .and. env_texts(3) == "blas_core=Zen", "a later run adds only its new one")
  call remove_journal(dir)
  call read_environments(dir, env_tags, env_texts, error)
  call check(.not. allocated(error) .and. size(env_tags) == 0, "--restart removes them with the journal")

  call section("fingerprint")
  call check_fingerprint(dir, "a = 1" // new_line("a"), error)
  call check(.not. allocated(error), "first run writes it")
  call check_fingerprint(dir, "a = 1" // new_line("a"), error)
  call check(.not. allocated(error), "same sweep: accepted")
  call check_fingerprint(dir, "a = 2" // new_line("a"), error)
  call check(allocated(error), "different sweep: refused")
  if (allocated(error)) call check(index(error%message, "was a = 1, now a = 2") > 0, "message names the change: " &
    // error%message)
  call remove_journal(dir)

  call section("write errors: a full device, a large file")
  ! 20000 bytes: more than any buffer of 4 or 8 KiB, so a buffered write would
  ! hold part of it until close
  big = repeat("0123456789abcdefghi" // new_line("a"), 1000)
  if (allocated(error)) deallocate(error)
  call write_text_file("/dev/full", big, error)
  call check(allocated(error), "write_text_file to /dev/full: an error")
  if (allocated(error)) call check(index(error%message, "/dev/full") > 0 .and. &
    index(error%message, "No space left on device") > 0, "it names the file and ENOSPC: " // error%message)
  if (allocated(error)) deallocate(error)
  call write_text_file("sweep_journal_big.txt", big, error)
  call check(.not. allocated(error), "write_text_file of 20000 bytes: no error")
  call read_text_file("sweep_journal_big.txt", back_text, error)
  call check(.not. allocated(error) .and. back_text == big, "the 20000 bytes read back unchanged")
  call delete_file("sweep_journal_big.txt")
  ! a journal whose rank file is /dev/full: the first row is an error
  dir = "sweep_journal_full"
  call make_dir(dir, error)
  k = c_unlink(dir // "/rank_0000.txt" // c_null_char)
  call check(c_symlink("/dev/full" // c_null_char, dir // "/rank_0000.txt" // c_null_char) == 0, &
    "rank_0000.txt -> /dev/full")
  call jw%open(dir, 0, error)
  call check(.not. allocated(error), "the journal opens")
  row = sweep_row(id=7)
  call jw%append(row, error)
  call check(allocated(error), "appending a row to a full device: an error")
  if (allocated(error)) call check(index(error%message, "rank_0000.txt") > 0 .and. &
    index(error%message, "case 7") > 0 .and. index(error%message, "No space left on device") > 0, &
    "it names the file, the case and ENOSPC: " // error%message)
  call jw%close()
  k = c_unlink(dir // "/rank_0000.txt" // c_null_char)
  call finish()
contains
  function itoa(i) result(s)
    integer, intent(in) :: i
    character(len=16) :: s
    write(s, '(i0)') i
  end function itoa
end program test_sweep_journal
