"""A scenario saved with a UTF-8 byte-order mark (as some Windows editors
write one) reads as the same scenario: the mark is three blanks to the reader
(docs/input.md).  Reference: the same file without the mark, `--check`'s
resolved input compared as text (every value, 17 digits)."""
from conftest import PAPER, run_airlaunch


def test_a_byte_order_mark_reads_as_blanks(airlaunch_exe, tmp_path):
    plain = tmp_path / "plain.nml"
    marked = tmp_path / "marked.nml"
    text = PAPER.read_bytes()
    plain.write_bytes(text)
    marked.write_bytes(b"\xef\xbb\xbf" + text)
    a = run_airlaunch(airlaunch_exe, plain, "--check", "--output", tmp_path / "a.nc")
    b = run_airlaunch(airlaunch_exe, marked, "--check", "--output", tmp_path / "a.nc")
    assert a.returncode == 0 and b.returncode == 0, (a.stderr, b.stderr)
    assert b.stdout.replace(str(marked), str(plain)) == a.stdout
