"""Command line of the sweep post-processing (run from the repository root):

    python -m postproc.sweep table SWEEP.nml [--check] [--exe-dir DIR]
    python -m postproc.sweep envelope SWEEP.nml [--criteria FILE] [--summary FILE] [--no-figures] [--check]
    python -m postproc.sweep verify SWEEP.nml [--cases K | --ids I,J,...] [--segments F] [--tolerance F] [--jobs J]

Exit status 0 on success, 2 for bad input or a file that cannot be read or
written (one line on stderr), 4 when the step completed but its standard output
could not be written (a full disk, a closed pipe: one line on stderr), 130 when
interrupted (SIGINT, Ctrl-C: one line, ``sweep: interrupted``), 143 on SIGTERM
(``sweep: interrupted (SIGTERM)``); every file is written under a temporary
name and renamed once whole, so none is left cut short under its final name.
"""
from __future__ import annotations

import sys

INTERRUPTED = 130
STDOUT_LOST = 4


class CheckedStdout:
    """sys.stdout that keeps the step going when its output cannot be written
    (a full disk, `| head` that has closed the pipe): the first error is kept
    and later output dropped, so the step finishes its files; main() then
    reports it in one line (exit 4), as airlaunch and airlaunch-sweep do."""

    def __init__(self, stream):
        self._stream = stream
        self.error = None

    def write(self, text):
        if self.error is None:
            try:
                return self._stream.write(text)
            except OSError as exc:
                self.error = exc
        return len(text)

    def flush(self):
        if self.error is None:
            try:
                self._stream.flush()
            except OSError as exc:
                self.error = exc

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _silence_stdout():
    """Point file descriptor 1 at /dev/null: the interpreter's last flush of
    what could not be written then neither fails nor prints a traceback."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.__stdout__.fileno())
    except (OSError, ValueError, AttributeError):
        pass


class Terminated(BaseException):
    """SIGTERM (kill, Slurm's time limit, scripts/sweep passing it on): the
    step ends as on an interrupt, its temporary files removed."""


def _terminate(signum, frame):
    raise Terminated()


def interrupted(exc=None) -> int:
    """One line for an interrupt or SIGTERM (not a traceback); the exit status."""
    if isinstance(exc, Terminated):
        print("sweep: interrupted (SIGTERM)", file=sys.stderr)
        return 128 + 15
    print("sweep: interrupted", file=sys.stderr)
    return INTERRUPTED


try:   # an interrupt while the modules load is one line too (SIGTERM: its default, below)
    import argparse
    import os
    import pathlib

    import numpy as np

    from .definition import DefinitionError, check_base, not_a_file, read_definition
except KeyboardInterrupt:
    sys.exit(interrupted())


def require_programs(exe_dir, names, purpose) -> list:
    """The programs `names` of `exe_dir`, each an executable file, or a
    DefinitionError naming the first missing one (before the step changes
    any file)."""
    exes = [pathlib.Path(exe_dir) / name for name in names]
    for exe in exes:
        if not (exe.is_file() and os.access(exe, os.X_OK)):
            raise DefinitionError(f"{exe}: no such program {purpose} (build it with scripts/setup release, or "
                                  "give --exe-dir)")
    return exes


def hold_sweep_lock(defn):
    """Take airlaunch-sweep's lock of the output directory, OUTPUT_DIR/journal/lock
    (flock, exclusive, not waiting), for the table step: a descriptor to close
    once the table is written, or None where no run has made the lock file (or
    it cannot be opened: the table's own write then says why).  While a run of
    the sweep holds it, the table it ran from is not replaced: a second
    submission of the job (scripts/sweep, scripts/sweep.slurm: the table step
    runs first) is refused here, in one line, before it removes the running
    sweep's table; and no run starts while the table is being replaced."""
    import fcntl

    journal = pathlib.Path(defn.output_dir) / "journal"
    try:   # read-write: on NFS an exclusive flock needs a descriptor open for writing
        fd = os.open(journal / "lock", os.O_RDWR | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise DefinitionError(f"{journal}: another airlaunch-sweep is running this sweep (its lock file 'lock' is "
                              f"held): its table {defn.table_path} is left as it is; wait for it to end, or give "
                              "this definition another output_dir") from None
    except OSError:
        os.close(fd)
        return None
    return fd


def cmd_table(args) -> int:
    """Draw the case table (or check an existing one against the definition);
    either way, refuse what airlaunch-sweep --check refuses, with its message."""
    from .table import check_table, check_with_sweep, make_table, output_dir_error, write_atomic

    defn = read_definition(args.definition)
    check_base(defn)
    sweep_exe, = require_programs(args.exe_dir, ["airlaunch-sweep"], "to check the definition with")
    if args.check:
        check_table(defn)
        check_with_sweep(defn, sweep_exe)
        print(f"table: {defn.table_path} is the table of {defn.path}")
        return 0
    table, path = make_table(defn), defn.table_path
    lock = hold_sweep_lock(defn)
    try:
        try:
            # the table this step replaces goes first: airlaunch-sweep --check then
            # judges the definition alone, and one it refuses is left no table
            path.unlink(missing_ok=True)
        except OSError as exc:
            raise output_dir_error(defn, path, exc) from None
        check_with_sweep(defn, sweep_exe)
        try:
            write_atomic(table, path)
        except (OSError, RuntimeError) as exc:   # netCDF4 reports some write errors as RuntimeError
            raise output_dir_error(defn, path, exc) from None
    finally:
        if lock is not None:
            os.close(lock)
    print(f"table: {path} ({defn.n_cases} cases, {len(defn.inputs)} inputs, design {defn.design}, "
          f"seed {defn.seed})")
    if defn.design == "sobol" and defn.n_cases & (defn.n_cases - 1):
        print(f"note: {defn.n_cases} is not a power of 2: the Sobol points lose their balance properties")
    return 0


def fnv1a(data: bytes) -> str:
    """FNV-1a 64 of the bytes, as airlaunch-sweep writes it (16 hex digits)."""
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016X}"


def check_summary_settings(defn, summary, where) -> None:
    """Raise DefinitionError if the base scenario's text, the &fixed settings
    or &sweep t_end changed since the summary was made (summaries written
    before the twenty-sixth session lack the first two: not checked)."""
    rerun = "the definition changed since the sweep ran: run airlaunch-sweep to evaluate it as it is now"
    recorded = summary.attrs.get("base_text_fnv1a")
    if isinstance(recorded, str):
        try:
            now = fnv1a(pathlib.Path(defn.base).read_bytes())
        except OSError:
            now = None
        if now is not None and now != recorded.strip():
            raise DefinitionError(f"{where} (the base scenario {defn.base} is not the text the sweep ran): {rerun}")
    recorded = summary.attrs.get("fixed")
    if isinstance(recorded, str):
        now = "\n".join(f"{name} = {value}" for name, value in defn.fixed)
        if now != recorded.strip():
            raise DefinitionError(f"{where} (its &fixed settings are not those the sweep ran: "
                                  f"{recorded.strip() or 'none'!r} then, {now or 'none'!r} now): {rerun}")
    t_end = summary.attrs.get("t_end_s")
    if defn.t_end > 0 and t_end is not None and float(t_end) != defn.t_end:
        raise DefinitionError(f"{where} (&sweep t_end = {defn.t_end:g} s, the sweep ran {float(t_end):g} s): "
                              f"{rerun}")
    # t_end = 0 is the base's &run t_end (unless &fixed or &input sets run%t_end): a sweep run at
    # &sweep t_end = 4 and then set to 0 was evaluated as the new definition's (found by an audit)
    sets_it = any(name == "run%t_end" for name, _ in defn.fixed) or any(s.name == "run%t_end" for s in defn.inputs)
    base_t_end = _base_t_end(summary.attrs.get("base_namelist"))
    if defn.t_end == 0 and not sets_it and t_end is not None and base_t_end is not None \
            and float(t_end) != base_t_end:
        raise DefinitionError(f"{where} (&sweep t_end = 0, the base's {base_t_end:g} s, the sweep ran "
                              f"{float(t_end):g} s): {rerun}")


def _base_t_end(base_namelist):
    """&run t_end of the base's resolved input as the summary records it
    (None if it cannot be read there)."""
    import f90nml

    try:
        return float(f90nml.reads(base_namelist)["run"]["t_end"])
    except Exception:   # noqa: BLE001 - f90nml raises several types; an unreadable record is not checked
        return None


def check_summary_belongs(defn, summary, summary_path) -> None:
    """Raise DefinitionError unless the summary is that of the definition's
    current table: same design, seed and case count as the definition, and the
    same input values, case by case, as OUTPUT_DIR/table.nc (or, without that
    file, as the table the definition draws).  A summary left by an earlier
    sweep in the same output_dir (a rerun killed before its new summary) is
    refused, not evaluated."""
    import numpy as np

    from .table import check_table, make_table, open_netcdf

    where = f"{summary_path}: the summary is not that of {defn.path}"
    again = "a summary left by an earlier sweep? run airlaunch-sweep to make this sweep's"
    for key, want in (("design", defn.design), ("seed", defn.seed), ("n_cases", defn.n_cases)):
        have = summary.attrs.get(key)
        if isinstance(have, np.ndarray) and have.size == 1:
            have = have.item()
        if isinstance(have, (np.integer, np.str_)):
            have = have.item()
        if have != want:
            raise DefinitionError(f"{where} ({key} is {have!r} in the summary, {want!r} in the definition): {again}")
    n = summary.sizes.get("case")
    if n != defn.n_cases:
        raise DefinitionError(f"{where} (it has {n} cases, the definition {defn.n_cases}): {again}")
    check_summary_settings(defn, summary, where)
    table_path = defn.table_path
    if table_path.is_file():
        # the table is the definition's as it is now (a changed distribution, say)
        check_table(defn)
        table = open_netcdf(table_path, "case table", "run the table step again")
        source = str(table_path)
    else:
        table, source = make_table(defn), f"the table that {defn.path} draws"
    for s in defn.inputs:
        if s.name not in table.variables or table[s.name].shape != (n,):
            raise DefinitionError(f"{table_path}: the case table does not match {defn.path} (run the table step "
                                  "again)")
        have = summary[s.name].values if s.name in summary.variables else None
        if have is None or have.shape != (n,) or not np.array_equal(have, table[s.name].values):
            raise DefinitionError(f"{where} (its values of {s.name} are not those of {source}): {again}")


def read_criteria_for(defn, args):
    """The criteria of the definition (or --criteria), refused in one line if
    they are not those of the base's scene."""
    from .criteria import SCENE_CRITERION_METRICS, base_scene, check_scene, check_tracked, read_criteria

    criteria_path = args.criteria or defn.criteria
    if not criteria_path:
        raise DefinitionError(f"{defn.path}: &sweep: no criteria file (set criteria = 'FILE' or give --criteria)")
    criteria = read_criteria(criteria_path)
    # criteria of another scene than the base's: refused before any case runs (scripts/sweep checks first)
    scene = base_scene(defn.base)
    check_scene(criteria, scene, SCENE_CRITERION_METRICS.get(scene), criteria_path)
    check_tracked(criteria, defn, criteria_path)
    return criteria, criteria_path


def load_summary(defn, summary_arg, criteria, criteria_path):
    """The sweep's summary (OUTPUT_DIR/summary.nc or summary_arg), checked: a
    sweep summary with the definition's inputs and the criteria's variables,
    of the definition's current table."""
    from .criteria import check_scene
    from .table import open_netcdf

    summary_path = pathlib.Path(summary_arg or defn.summary_path)
    if not summary_path.is_file():
        reason = "summary does not exist" if not summary_path.exists() else not_a_file(summary_path)
        raise DefinitionError(f"{summary_path}: {reason} (run airlaunch-sweep first)")
    hint = "give the summary.nc that airlaunch-sweep writes"
    summary = open_netcdf(summary_path, "summary", hint)
    names = [s.name for s in defn.inputs]
    inputs = summary.attrs.get("inputs")
    if not isinstance(inputs, str):
        raise DefinitionError(f"{summary_path}: not a sweep summary: the global attribute 'inputs' is missing ({hint})")
    if inputs.split() != names:
        raise DefinitionError(f"{summary_path}: the summary's inputs ({inputs}) are "
                              f"not those of {defn.path} ({' '.join(names)})")
    summary_scene = summary.attrs.get("scene")
    # a summary of another scene than the air-launch (whose summary has every criterion's variable);
    # an envelope file has a scene too, but not the summary's base_namelist
    if isinstance(summary_scene, str) and summary_scene != "airlaunch" and "base_namelist" in summary.attrs:
        check_scene(criteria, summary_scene, set(summary.variables), criteria_path)
    needed = ["status"] + names + sorted({m for c in criteria for m in c.metrics})
    for var in needed:
        if var not in summary.variables:
            raise DefinitionError(f"{summary_path}: not a sweep summary: variable '{var}' is missing ({hint})")
        if summary[var].dims != ("case",) or summary[var].dtype.kind not in "biuf":
            raise DefinitionError(f"{summary_path}: not a sweep summary: variable '{var}' is not a number per case "
                                  f"(dimensions {summary[var].dims}, type {summary[var].dtype}) ({hint})")
    check_summary_belongs(defn, summary, summary_path)
    return summary, summary_path


def warn_stale_figures(defn) -> None:
    """One line on stderr if OUTPUT_DIR/figures/ no longer shows the sweep's
    envelope and summary (the envelope step removes or redraws them)."""
    from .stamp import stale_figures

    why = stale_figures(defn.figure_dir, defn.envelope_path)
    if why:
        print(f"sweep: warning: {defn.figure_dir} is stale: {why}; run the envelope step to draw it again",
              file=sys.stderr)


def cmd_envelope(args) -> int:
    """Evaluate the criteria on the summary; write the envelope and the figures."""
    from .envelope import evaluate, undefined_metric_lines, worst_case_table
    from .stamp import STAMP, remove_figures, stale_figures, write_stamp
    from .table import output_dir_error, write_atomic

    defn = read_definition(args.definition)
    criteria, criteria_path = read_criteria_for(defn, args)
    if args.check:
        print(f"envelope: criteria {criteria_path} ({len(criteria)} criteria) for {defn.path}")
        warn_stale_figures(defn)
        return 0
    summary, summary_path = load_summary(defn, args.summary, criteria, criteria_path)
    env = evaluate(summary, criteria)
    env.attrs["criteria_file"] = str(criteria_path)
    env.attrs["summary"] = str(summary_path)
    try:
        out = write_atomic(env, defn.envelope_path)
    except (OSError, RuntimeError) as exc:
        raise output_dir_error(defn, defn.envelope_path, exc) from None
    print(f"envelope: {out}")
    all_ = env.sel(criterion="all")
    print(f"probability of success (all criteria): {float(all_['probability']):.4f} "
          f"(95% Wilson [{float(all_['wilson_low']):.4f}, {float(all_['wilson_high']):.4f}], "
          f"Clopper-Pearson [{float(all_['clopper_pearson_low']):.4f}, "
          f"{float(all_['clopper_pearson_high']):.4f}]) over {env.sizes['case']} cases")
    for c in env["criterion"].values[:-1]:
        row = env.sel(criterion=c)
        print(f"  {c:16s} {float(row['probability']):.4f} "
              f"[{float(row['wilson_low']):.4f}, {float(row['wilson_high']):.4f}]")
    # why criteria fail that no case could evaluate, beside their probabilities (before: P = 0 without a word)
    n_not_ok = int((env["status"].values != 0).sum())
    if n_not_ok == env.sizes["case"]:
        print(f"  warning: no case was computed ({n_not_ok} failed or had invalid input: the summary's 'failure' "
              "says why): every criterion fails")
    else:
        if n_not_ok:
            print(f"  note: {n_not_ok} of {env.sizes['case']} cases were not computed (failed or invalid input): "
                  "they pass no criterion")
        for line in undefined_metric_lines(env, criteria):
            print(line)
    from .sensitivity import DRIVERS_HEADING, drivers_table

    print(f"{DRIVERS_HEADING}, over {int(env['sensitivity_cases'].values[0])} computed cases:")
    print(drivers_table(env), end="")
    if not args.no_figures:
        from .figures import draw_all

        try:
            # the record goes first, so figures cut short are not taken as this envelope's
            (defn.figure_dir / STAMP).unlink(missing_ok=True)
            paths = draw_all(env, defn.figure_dir)
            write_stamp(defn.figure_dir, out, summary_path, summary.attrs.get("created", ""))
        except OSError as exc:
            # figures.write_atomic names the figure in every OSError it raises
            raise output_dir_error(defn, getattr(exc, "filename", None) or defn.figure_dir / "?", exc) from None
        print(f"figures: {defn.figure_dir} ({', '.join(p.name for p in paths.values())}, drawn from {out})")
    else:
        why = stale_figures(defn.figure_dir, out)
        if why:
            remove_figures(defn.figure_dir)
            print(f"figures: removed those of {defn.figure_dir}: {why}")
    print("worst cases:")
    print(worst_case_table(env, 10), end="")
    return 0


def cmd_verify(args) -> int:
    """Rerun the cases nearest the boundary (or --ids) refined; compare margins."""
    from .criteria import base_scene
    from .envelope import evaluate
    from .table import output_dir_error, write_atomic
    from .verify import nearest_the_boundary, verification_table, verify

    defn = read_definition(args.definition)
    criteria, criteria_path = read_criteria_for(defn, args)
    summary, _ = load_summary(defn, args.summary, criteria, criteria_path)
    env = evaluate(summary, criteria)
    n = env.sizes["case"]
    if args.ids:
        try:
            ids = [int(v) for v in args.ids.split(",")]
        except ValueError:
            raise DefinitionError(f"--ids {args.ids}: not a comma-separated list of case ids") from None
        bad = [i for i in ids if not 0 <= i < n]
        if bad:
            raise DefinitionError(f"--ids {args.ids}: case {bad[0]} is not in 0 ... {n - 1}")
        twice = [i for k, i in enumerate(ids) if i in ids[:k]]
        if twice:
            raise DefinitionError(f"--ids {args.ids}: case {twice[0]} is given twice (give each case once)")
    else:
        ids = list(nearest_the_boundary(env, args.cases))
    if not ids:   # not an error: the sweep has no case with a margin on every criterion
        print("verify: no computed case has a finite margin on every criterion (an event never came in any "
              "case): nothing near the boundary to verify; choose cases with --ids")
        warn_stale_figures(defn)
        return 0
    sweep_exe, exe = require_programs(args.exe_dir, ["airlaunch-sweep", "airlaunch"], "to rerun the cases with")
    out_dir = pathlib.Path(defn.output_dir)
    # an earlier verification's reruns (other cases, other settings) go: verify/ holds this one's only; and
    # so does its verify.nc, which named them (an interrupted or failed verification left it, stale, beside
    # the new runs: found by an audit)
    for old in (out_dir / "verify").glob("case_*"):
        old.unlink()
    (out_dir / "verify.nc").unlink(missing_ok=True)
    ds = verify(env, criteria, base_scene(defn.base) or "airlaunch", ids, defn.path, sweep_exe,
                exe, out_dir / "verify", segments=args.segments, tolerance=args.tolerance,
                jobs=args.jobs)
    try:
        path = write_atomic(ds, out_dir / "verify.nc")
    except (OSError, RuntimeError) as exc:
        raise output_dir_error(defn, out_dir / "verify.nc", exc) from None
    print(f"verify: {len(ids)} case(s) rerun with {ds.attrs['refinement']} ({path}; their runs in {out_dir / 'verify'})")
    print(verification_table(ds), end="")
    for c in ds["criterion"].values:
        row = ds.sel(criterion=c)
        diff, margin = np.abs(row["difference"].values), np.abs(row["margin_sweep"].values)
        units = str(row["criterion_units"].values)
        if np.isfinite(diff).any():
            print(f"  {c:16s} largest |difference| {np.nanmax(diff):.3g} {units}, smallest |margin| "
                  f"{np.nanmin(margin):.3g} {units}")
        else:
            print(f"  {c:16s} no margin computed at both settings")
    flips = int(ds["flipped"].values.any(axis=0).sum())
    not_run = int((ds["refined_status"].values != "ok").sum())
    worst = np.nanmax(np.abs(ds["relative_difference"].values)) if np.isfinite(
        ds["relative_difference"].values).any() else float("nan")
    print(f"verify: {flips} of {len(ids)} case(s) change pass/fail at the refined settings; "
          f"{not_run} refined run(s) did not complete; largest |difference| {worst:.3g} of a criterion's scale")
    warn_stale_figures(defn)
    return 0


class OneLineParser(argparse.ArgumentParser):
    """A command-line error is one line (the project's rule for bad input) and status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer")
    return value


def _factor(text):
    try:
        value = float(text)
    except ValueError:
        value = 0.0
    if not (value >= 1.0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r} is not a factor >= 1")
    return value


def _exe_dir_option(parser, help_text):
    parser.add_argument("--exe-dir", default=str(pathlib.Path(__file__).resolve().parents[2] / "build" / "release" /
                                                 "bin"), help=help_text)


def main(argv=None) -> int:
    """Parse the command line and run one step; bad input is one line and status 2."""
    parser = OneLineParser(prog="python -m postproc.sweep", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="step", required=True)
    p = sub.add_parser("table", help="draw the case table of a sweep definition")
    p.add_argument("definition")
    p.add_argument("--check", action="store_true", help="check that the existing table is the definition's")
    _exe_dir_option(p, "where airlaunch-sweep is, which checks the definition (default build/release/bin)")
    p.set_defaults(func=cmd_table)
    p = sub.add_parser("envelope", help="safety envelope and figures from the summary")
    p.add_argument("definition")
    p.add_argument("--criteria", help="criteria file (default: the definition's)")
    p.add_argument("--summary", help="summary file (default: OUTPUT_DIR/summary.nc)")
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--check", action="store_true",
                   help="only check that the criteria file is given and valid (before a run)")
    p.set_defaults(func=cmd_envelope)
    p = sub.add_parser("verify", help="rerun the cases nearest the boundary with refined settings")
    p.add_argument("definition")
    p.add_argument("--criteria", help="criteria file (default: the definition's)")
    p.add_argument("--summary", help="summary file (default: OUTPUT_DIR/summary.nc)")
    p.add_argument("--cases", type=_positive_int, default=8,
                   help="how many computed cases nearest the boundary (smallest |relative margin|; default 8)")
    p.add_argument("--ids", help="these case ids instead (comma-separated)")
    p.add_argument("--segments", type=_positive_int, default=4,
                   help="line segments times this (at most 1000 segments; default 4)")
    p.add_argument("--tolerance", type=_factor, default=100.0,
                   help="rtol and atol divided by this (default 100)")
    p.add_argument("--jobs", type=_positive_int, default=2, help="cases run at once (default 2)")
    _exe_dir_option(p, "where airlaunch and airlaunch-sweep are (default build/release/bin)")
    p.set_defaults(func=cmd_verify)
    out = sys.stdout = CheckedStdout(sys.stdout)
    try:
        args = parser.parse_args(argv)
        status = args.func(args)
    except DefinitionError as exc:
        print(f"sweep: error: {exc}", file=sys.stderr)
        status = 2
    except OSError as exc:
        # a path the step could not use that no check named: one line, not a traceback
        where = f"{exc.filename}: " if exc.filename is not None else ""
        print(f"sweep: error: {where}{exc.strerror or exc}", file=sys.stderr)
        status = 2
    except (KeyboardInterrupt, Terminated) as exc:
        return interrupted(exc)
    out.flush()
    if out.error is not None:
        done = "; the step's files are complete" if status == 0 else ""
        print(f"sweep: error: the standard output could not be written ({out.error.strerror or out.error}{done})",
              file=sys.stderr)
        _silence_stdout()
        return STDOUT_LOST if status == 0 else status
    return status


if __name__ == "__main__":
    try:
        import signal
        signal.signal(signal.SIGTERM, _terminate)
        status = main()
        # the step is done (its files renamed into place): an interrupt while
        # the interpreter shuts down (SIGINT's default action again) would
        # end it by the signal, silently, after the work
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    except (KeyboardInterrupt, Terminated) as exc:   # between main's return and here
        status = interrupted(exc)
    sys.exit(status)
