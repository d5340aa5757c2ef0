"""Which envelope and summary the figures of OUTPUT_DIR/figures/ show.

The envelope step draws the figures from the envelope it has just written and
then writes ``figures/drawn_from.txt``: the SHA-256 of that envelope.nc and of
the summary it was evaluated from.  airlaunch-sweep removes summary.nc and
envelope.nc when the sweep's cases run again (``--restart``, a resume) but not
the figures, which then show the earlier summary.  Figures are current only
while drawn_from.txt names the envelope.nc beside them and the summary (where
that file still is): ``stale_figures`` says why they are not.
"""
from __future__ import annotations

import hashlib
import pathlib

from .files import write_text_atomic

#: The files the envelope step draws into figures/ (figures.draw_all), by key.
FIGURE_FILES = {"passfail_map": "passfail_map.png", "margins": "margins.png", "probability": "probability.png",
                "worst_cases": "worst_cases.png", "worst_cases_md": "worst_cases.md",
                "sensitivity": "sensitivity.png"}
#: The record of what they were drawn from, written after them.
STAMP = "drawn_from.txt"


def sha256(path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def file_stat(path) -> str:
    """A file's size and modification time (ns), as the record keeps them."""
    st = pathlib.Path(path).stat()
    return f"{st.st_size} {st.st_mtime_ns}"


def unchanged(path, stamp, name) -> bool:
    """The file is the one the record names under `name`: the same size and
    modification time (no need to read it: a summary of 10^7 cases is
    gigabytes), else the same SHA-256 (a copy, or a file touched)."""
    if stamp.get(f"{name}_stat") == file_stat(path):
        return True
    return sha256(path) == stamp[f"{name}_sha256"]


def write_stamp(figure_dir, envelope_path, summary_path, summary_created="") -> pathlib.Path:
    """Record (atomically) the envelope and summary the figures were just drawn from."""
    stamp = pathlib.Path(figure_dir) / STAMP
    text = ("# the envelope step drew the figures of this directory from these files "
            "(docs/sweep.md, 'Figures and the summary they show')\n"
            f"envelope = {pathlib.Path(envelope_path).resolve()}\n"
            f"envelope_sha256 = {sha256(envelope_path)}\n"
            f"envelope_stat = {file_stat(envelope_path)}\n"
            f"summary = {pathlib.Path(summary_path).resolve()}\n"
            f"summary_sha256 = {sha256(summary_path)}\n"
            f"summary_stat = {file_stat(summary_path)}\n"
            f"summary_created = {summary_created}\n")
    return write_text_atomic(stamp, text)


def read_stamp(figure_dir) -> dict:
    """The record's entries ({} if there is none, or it cannot be read)."""
    try:
        lines = (pathlib.Path(figure_dir) / STAMP).read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    pairs = (line.partition(" = ") for line in lines if not line.startswith("#"))
    return {key: value for key, sep, value in pairs if sep}


def stale_figures(figure_dir, envelope_path):
    """Why the figures in figure_dir do not show envelope_path and its summary
    as they are now (None: they do, or there are none)."""
    d = pathlib.Path(figure_dir)
    if not any((d / name).is_file() for name in FIGURE_FILES.values()):
        return None
    stamp = read_stamp(d)
    if not {"envelope_sha256", "summary", "summary_sha256"} <= stamp.keys():
        return (f"{d / STAMP} is missing or incomplete (drawing them was cut short, or they are older than the "
                "record): not known to show this sweep's envelope")
    envelope = pathlib.Path(envelope_path)
    if not envelope.is_file():
        return (f"{envelope}, which they were drawn from, is gone (airlaunch-sweep removes it when the sweep's "
                "cases run again)")
    if not unchanged(envelope, stamp, "envelope"):
        return f"{envelope} was made again since they were drawn"
    summary = pathlib.Path(stamp["summary"])
    if summary.is_file() and not unchanged(summary, stamp, "summary"):
        return f"{summary} was made again since they were drawn"
    return None


def remove_figures(figure_dir) -> None:
    """Remove the envelope step's figures and their record (other files stay)."""
    d = pathlib.Path(figure_dir)
    for name in (STAMP, *FIGURE_FILES.values()):
        (d / name).unlink(missing_ok=True)
    try:
        d.rmdir()
    except OSError:   # not empty (files of the user's), or already gone
        pass
