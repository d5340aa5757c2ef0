"""Monte Carlo sweeps of the air-launch scenario and of the standalone line scene: case tables,
safety envelopes, figures.

The chain (docs/sweep.md):

1. ``python -m postproc.sweep table SWEEP.nml`` draws the case table (scipy.stats.qmc);
2. ``mpirun -np K build/release/bin/airlaunch-sweep SWEEP.nml`` runs the cases;
3. ``python -m postproc.sweep envelope SWEEP.nml`` evaluates the safety criteria and
   draws the figures.

Every module here is free of global state: functions take what they need and
return new objects.
"""

__all__ = ["DefinitionError", "InputSpec", "SweepDefinition", "read_definition"]


def __getattr__(name):
    """The names of __all__, imported when first used: ``python -m
    postproc.sweep`` imports this package before its command line can take an
    interrupt in one line (__main__.py), so the package itself imports nothing."""
    if name in __all__:
        from . import definition
        return getattr(definition, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
