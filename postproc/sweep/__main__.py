"""Command line of the sweep post-processing (run from the repository root):

    python -m postproc.sweep table SWEEP.nml [--check]
    python -m postproc.sweep envelope SWEEP.nml [--criteria FILE] [--summary FILE] [--no-figures] [--check]

Exit status 0 on success, 2 for bad input (one line on stderr).
"""
from __future__ import annotations

import argparse
import pathlib
import sys

from .definition import DefinitionError, check_base, read_definition


def cmd_table(args) -> int:
    """Draw the case table (or check an existing one against the definition)."""
    from .table import check_table, output_dir_error, write_table

    defn = read_definition(args.definition)
    check_base(defn)
    if args.check:
        check_table(defn)
        print(f"table: {defn.table_path} is the table of {defn.path}")
        return 0
    try:
        path = write_table(defn)
    except (OSError, RuntimeError) as exc:   # netCDF4 reports some write errors as RuntimeError
        raise output_dir_error(defn, defn.table_path, exc) from None
    print(f"table: {path} ({defn.n_cases} cases, {len(defn.inputs)} inputs, design {defn.design}, "
          f"seed {defn.seed})")
    if defn.design == "sobol" and defn.n_cases & (defn.n_cases - 1):
        print(f"note: {defn.n_cases} is not a power of 2: the Sobol points lose their balance properties")
    return 0


def check_summary_belongs(defn, summary, summary_path) -> None:
    """Raise DefinitionError unless the summary is that of the definition's
    current table: same design, seed and case count as the definition, and the
    same input values, case by case, as OUTPUT_DIR/table.nc (or, without that
    file, as the table the definition draws).  A summary left by an earlier
    sweep in the same output_dir (a rerun killed before its new summary) is
    refused, not evaluated."""
    import numpy as np

    from .table import make_table, open_netcdf

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
    table_path = defn.table_path
    if table_path.is_file():
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


def cmd_envelope(args) -> int:
    """Evaluate the criteria on the summary; write the envelope and the figures."""
    from .criteria import SCENE_CRITERION_METRICS, base_scene, check_scene, read_criteria
    from .envelope import evaluate, worst_case_table
    from .table import open_netcdf, output_dir_error, write_atomic

    defn = read_definition(args.definition)
    criteria_path = args.criteria or defn.criteria
    if not criteria_path:
        raise DefinitionError(f"{defn.path}: &sweep: no criteria file (set criteria = 'FILE' or give --criteria)")
    criteria = read_criteria(criteria_path)
    # criteria of another scene than the base's: refused before any case runs (scripts/sweep checks first)
    scene = base_scene(defn.base)
    check_scene(criteria, scene, SCENE_CRITERION_METRICS.get(scene), criteria_path)
    if args.check:
        print(f"envelope: criteria {criteria_path} ({len(criteria)} criteria) for {defn.path}")
        return 0
    summary_path = pathlib.Path(args.summary or defn.summary_path)
    if not summary_path.is_file():
        raise DefinitionError(f"{summary_path}: summary does not exist (run airlaunch-sweep first)")
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
    from .sensitivity import DRIVERS_HEADING, drivers_table

    print(f"{DRIVERS_HEADING}, over {int(env['sensitivity_cases'].values[0])} computed cases:")
    print(drivers_table(env), end="")
    if not args.no_figures:
        from .figures import draw_all

        try:
            paths = draw_all(env, defn.figure_dir)
        except OSError as exc:
            raise output_dir_error(defn, getattr(exc, "filename", None) or defn.figure_dir, exc) from None
        print(f"figures: {defn.figure_dir} ({', '.join(p.name for p in paths.values())})")
    print("worst cases:")
    print(worst_case_table(env, 10), end="")
    return 0


def main(argv=None) -> int:
    """Parse the command line and run one step; bad input is one line and status 2."""
    parser = argparse.ArgumentParser(prog="python -m postproc.sweep", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="step", required=True)
    p = sub.add_parser("table", help="draw the case table of a sweep definition")
    p.add_argument("definition")
    p.add_argument("--check", action="store_true", help="check that the existing table is the definition's")
    p.set_defaults(func=cmd_table)
    p = sub.add_parser("envelope", help="safety envelope and figures from the summary")
    p.add_argument("definition")
    p.add_argument("--criteria", help="criteria file (default: the definition's)")
    p.add_argument("--summary", help="summary file (default: OUTPUT_DIR/summary.nc)")
    p.add_argument("--no-figures", action="store_true")
    p.add_argument("--check", action="store_true",
                   help="only check that the criteria file is given and valid (before a run)")
    p.set_defaults(func=cmd_envelope)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except DefinitionError as exc:
        print(f"sweep: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
