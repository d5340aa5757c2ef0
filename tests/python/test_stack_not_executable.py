"""The built programs do not ask for an executable stack.

gfortran builds a trampoline on the stack for an internal procedure passed as an
argument (it needs its host's frame), and the linker then marks the whole
program's stack executable (PT_GNU_STACK with PF_X): a hardening loss that
security scanners flag, that systems denying executable stacks (SELinux
deny_execstack, systemd MemoryDenyWriteExecute) refuse to run, and that glibc
2.41 refuses in a shared library.  The resolved input's echo did that until it
wrote each namelist group where the group is declared (airlaunch_run_config's
echo_buffer).

The reference is the ELF file itself: its program headers, read here with the
struct layout of the ELF-64 specification (System V gABI), not with the build's
tools.
"""
import struct

import pytest

from conftest import BIN, ROOT

PT_GNU_STACK = 0x6474E551
PF_X = 0x1


def stack_flags(path):
    """The p_flags of PT_GNU_STACK in the ELF-64 little-endian file `path`, or
    None when the file has no such header (the loader then assumes an executable
    stack on x86-64)."""
    data = path.read_bytes()
    assert data[:4] == b"\x7fELF", f"{path} is not an ELF file"
    assert data[4] == 2 and data[5] == 1, f"{path}: not ELF-64 little-endian"
    e_phoff, = struct.unpack_from("<Q", data, 0x20)
    e_phentsize, e_phnum = struct.unpack_from("<HH", data, 0x36)
    for i in range(e_phnum):
        p_type, p_flags = struct.unpack_from("<II", data, e_phoff + i*e_phentsize)
        if p_type == PT_GNU_STACK:
            return p_flags
    return None


PROGRAMS = ["airlaunch", "airlaunch-sweep", "bench-line"]


@pytest.mark.parametrize("build", ["release", "checked"])
@pytest.mark.parametrize("name", PROGRAMS)
def test_stack_is_not_executable(build, name):
    directory = BIN if build == "release" else ROOT / "build" / "checked" / "bin"
    exe = directory / name
    if not exe.exists():
        pytest.fail(f"{exe} is missing: run scripts/setup first")
    flags = stack_flags(exe)
    assert flags is not None, f"{exe} has no PT_GNU_STACK header: its stack would be executable"
    assert flags & PF_X == 0, (f"{exe} asks for an executable stack (PT_GNU_STACK flags {flags:#x}): "
                               "an internal procedure passed as an argument? (-Wtrampolines names it)")
