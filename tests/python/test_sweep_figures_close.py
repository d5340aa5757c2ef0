"""The envelope's figures are closed whatever happens while they are drawn or
written (an audit: a figure whose drawing or savefig raised, e.g. a full disk,
was left open in pyplot's registry, which grows over a session that draws many
envelopes: a test run, a notebook)."""
import errno

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from test_sweep_support import ROOT  # noqa: E402,F401  (puts the repository on sys.path)

from postproc.sweep import figures  # noqa: E402
from postproc.sweep.criteria import parse_criteria  # noqa: E402
from postproc.sweep.envelope import evaluate  # noqa: E402


def small_envelope(n=12):
    rng = np.random.default_rng(3)
    ds = xr.Dataset({"a": ("case", rng.uniform(0, 1, n), {"units": "s"}),
                     "b": ("case", rng.uniform(0, 1, n), {"units": "m2"}),
                     "status": ("case", np.zeros(n, dtype=np.int32)),
                     "min_clearance_m": ("case", rng.uniform(0, 3, n)),
                     "pitch_max_deg": ("case", rng.uniform(40, 90, n))}, coords={"case": np.arange(n)})
    ds.attrs.update(inputs="a b", sweep_name="close")
    return evaluate(ds, parse_criteria("&criteria min_clearance_m = 1.0, firing_pitch_min_deg = 75 /"))


DRAWERS = ["passfail_map", "margins", "probability", "sensitivity", "worst_table"]


def _draw(name, env, path):
    if name == "worst_table":
        figures.worst_table(env, path, None)
    else:
        getattr(figures, name)(env, path)


@pytest.mark.parametrize("name", DRAWERS)
def test_a_figure_whose_write_fails_is_closed(name, tmp_path, monkeypatch):
    env = small_envelope()
    plt.close("all")

    def full_disk(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", full_disk)
    with pytest.raises(OSError):
        _draw(name, env, tmp_path / "f.png")
    assert plt.get_fignums() == [], f"{name} left {len(plt.get_fignums())} figure(s) open"


@pytest.mark.parametrize("name", DRAWERS)
def test_a_figure_whose_drawing_fails_is_closed(name, tmp_path, monkeypatch):
    env = small_envelope()
    plt.close("all")

    def broken(self, *args, **kwargs):
        raise RuntimeError("drawing failed")

    monkeypatch.setattr(matplotlib.figure.Figure, "tight_layout", broken)
    with pytest.raises(RuntimeError):
        _draw(name, env, tmp_path / "f.png")
    assert plt.get_fignums() == [], f"{name} left {len(plt.get_fignums())} figure(s) open"


def test_draw_all_leaves_no_figure_open_when_a_write_fails(tmp_path, monkeypatch):
    env = small_envelope()
    plt.close("all")
    calls = []
    real = matplotlib.figure.Figure.savefig

    def third_fails(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", third_fails)
    with pytest.raises(OSError):
        figures.draw_all(env, tmp_path / "figures")
    assert plt.get_fignums() == []
    assert not list((tmp_path / "figures").glob("*.part"))
