"""Files written whole or not at all: under a temporary name of their own,
PATH.PID-RANDOM.part, renamed to PATH once complete, so a write cut short (a
full disk, an interrupt) never leaves a file under its final name, and two
writers of the same file (two envelope steps on one sweep) do not write into
each other's temporary file."""
from __future__ import annotations

import os
import pathlib
import secrets


def write_atomic(path, write):
    """`write(tmp)` a file under PATH.PID-RANDOM.part and rename it to `path`.
    On any failure the temporary file is removed and the exception goes on; an
    OSError that names no file (matplotlib's savefig on a full disk) is raised
    again naming `path`, with its reason.  The temporary name is this call's
    own: with a shared PATH.part a second writer truncated the first one's
    file, and the first one's rename then put the second one's half-written
    bytes under the final name."""
    path = pathlib.Path(path)
    tmp = path.with_name(f"{path.name}.{os.getpid()}-{secrets.token_hex(4)}.part")
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        if isinstance(exc, OSError) and not exc.filename:
            raise OSError(exc.errno, exc.strerror or str(exc) or type(exc).__name__, str(path)) from exc
        raise
    return path


def write_text_atomic(path, text):
    """`text` into the file `path`, whole or not at all."""
    return write_atomic(path, lambda tmp: pathlib.Path(tmp).write_text(text))
