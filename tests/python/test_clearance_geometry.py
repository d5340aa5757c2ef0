"""The rocket-aircraft clearance with the fins and the tailplane's span, end to
end: an independent Python post-processing of the written trajectory (the
bodies' CG positions and Euler angles, the paper's fins and a tail segment,
each surface densely sampled) against the file's `clearance_m` and
`min_clearance_m` (docs/model.md, "Clearance").

The paper scenario with its tail 40 m aft of the aircraft's CG, 3 m above
it and 8.7 m each way (an Il-76's tailplane spans 17.4 m) has its minimum
clearance after the separation, a local minimum located as an event (3.99 s;
the separation is at 3.875 s), where a fin is nearest: 10.918 m, against
11.494 m from the empennage point to the body cylinder alone (before;
11.022 m from the point to the body and fins)."""
import numpy as np
import pytest
import xarray as xr
from scipy.spatial import cKDTree

from conftest import assert_input_error, nml_variant, run_airlaunch

R = 0.8                       # &rocket diameter / 2
CG = 9.25                     # cg_from_nose
LENGTH = 18.5
X_LE = CG - 16.5              # fin_root_le_from_nose, in rocket axes
ROOT, TIP, SWEEP, SPAN = 2.0, 1.0, 1.0, 1.34
TAIL = np.array([-40.0, 3.0, 0.0])
HALF = 8.7


def euler_dcm(e_deg):
    """Body-to-earth matrices Ry(yaw) Rz(pitch) Rx(roll) of (n, 3) angles
    [yaw, pitch, roll] in degrees (output.md: rocket_euler_deg)."""
    y, p, r = np.radians(e_deg).T
    c, s = np.cos, np.sin
    one, zero = np.ones_like(y), np.zeros_like(y)
    ry = np.array([[c(y), zero, s(y)], [zero, one, zero], [-s(y), zero, c(y)]])
    rz = np.array([[c(p), -s(p), zero], [s(p), c(p), zero], [zero, zero, one]])
    rx = np.array([[one, zero, zero], [zero, c(r), -s(r)], [zero, s(r), c(r)]])
    return np.einsum("ijn,jkn,kln->nil", ry, rz, rx)


def samples(n_tail, n_axis, n_fin):
    """The tail's points (aircraft axes), the axis's points and the four X
    fins' points (rocket axes), and how far a point of each surface can be from
    its nearest sample (half the spacing; the fin's half cell diagonal)."""
    tail = TAIL + np.outer(np.linspace(-HALF, HALF, n_tail), [0.0, 0.0, 1.0])
    axis = np.outer(np.linspace(CG - LENGTH, CG, n_axis), [1.0, 0.0, 0.0])
    f = np.linspace(0.0, 1.0, n_fin)
    span, chord = np.meshgrid(f, f, indexing="ij")
    x = X_LE - SWEEP * span - (ROOT + (TIP - ROOT) * span) * chord
    w = R + SPAN * span
    fins = []
    for k in range(4):
        phi = np.pi / 4 + k * np.pi / 2
        fins.append(np.stack([x.ravel(), w.ravel() * np.cos(phi), w.ravel() * np.sin(phi)], axis=1))
    delta = HALF / (n_tail - 1) + LENGTH / (2 * (n_axis - 1)) + 0.5 * (ROOT + np.hypot(SPAN, SWEEP)) / (n_fin - 1)
    return tail, axis, np.concatenate(fins), delta


def sampled_clearance(ds, idx, n_tail, n_axis, n_fin):
    """The least sampled distance, per record idx, of the tail from the body
    (axis less R) and the fins; and its sampling bound.  The tail's samples
    are taken into rocket axes (the written Euler angles and positions) and
    each finds its nearest axis and fin samples (k-d trees: the same least
    distance as comparing every pair)."""
    tail, axis, fins, delta = samples(n_tail, n_axis, n_fin)
    axis_tree, fin_tree = cKDTree(axis), cKDTree(fins)
    ca = euler_dcm(ds["aircraft_euler_deg"].values[idx])
    cr = euler_dcm(ds["rocket_euler_deg"].values[idx])
    ra = ds["aircraft_position"].values[idx]
    rr = ds["rocket_position"].values[idx]
    out = []
    for i in range(len(idx)):
        p = (ra[i] - rr[i] + tail @ ca[i].T) @ cr[i]
        out.append(min(axis_tree.query(p)[0].min() - R, fin_tree.query(p)[0].min()))
    return np.array(out), delta


@pytest.fixture(scope="module")
def run(airlaunch_exe, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("clearance")
    out = tmp / "c.nc"
    nml = nml_variant(tmp, edits=[(r"^  tail_x = \S+", "  tail_x = -40.0\n  tail_half_span = 8.7"),
                                  (r"^  tail_y = \S+", "  tail_y = 3.0"),
                                  (r"^  output_dt = \S+", "  output_dt = 0.002"),
                                  (r"^  t_end = \S+", "  t_end = 7.0")])
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        yield ds.load()


def test_records_match_the_sampled_geometry(run):
    """clearance_m at 40 records spread over the run (in the bay, on the edge,
    free) is the sampled geometry's within its sampling bound (the samples are
    never nearer than the exact distance, and at most the three surfaces' half
    spacings farther; the Euler angles' round trip adds ~1e-13 m)."""
    idx = np.linspace(0, run.sizes["time"] - 1, 40).astype(int)
    py, delta = sampled_clearance(run, idx, 1741, 1851, 201)
    c = run["clearance_m"].values[idx]
    assert np.all(py >= c - 1e-9), np.max(c - py)
    assert np.all(py - c <= delta), (np.max(py - c), delta)


def test_minimum_is_the_sampled_trajectorys(run):
    """min_clearance_m, an event (the rising zero of the nearest piece's rate),
    against the densely sampled minimum over the free records: never above it
    (the records are samples in time, the surfaces are sampled), and at most
    the sampling bound (1.9 cm) plus the records' time sampling below: a
    smooth minimum lies within dt/2 of a record, |c''| (dt/2)^2/2 lower, with
    |c''| bounded by the records' largest second difference / dt^2.  The
    samplings refine in three passes, each keeping the records whose sampled
    value less its bound (a lower bound of the exact one) is at most the
    pass's least sampled value.  It is an interior minimum (a record after
    the first free one) where a fin is nearer than the body."""
    free = np.nonzero(run["phase"].values == 3)[0]
    keep = free
    for n in ((30, 38, 9), (175, 186, 41), (1741, 1851, 201)):
        value, delta = sampled_clearance(run, keep, *n)
        best = value.min()
        keep = keep[value - delta <= best]
    reported = float(run.attrs["min_clearance_m"])
    c = run["clearance_m"].values[free]
    curvature = np.max(np.abs(np.diff(c, 2))) / 8
    assert reported <= best + 1e-9
    assert best - reported <= delta + curvature, (best - reported, delta, curvature)
    assert np.argmin(c) > 0
    assert reported == pytest.approx(10.918, abs=1e-3)
    # the body alone, from the empennage point (before the fins and span): 11.494 m
    assert reported < 11.494 - 0.5


def test_negative_tail_half_span_is_refused(airlaunch_exe, tmp_path):
    """A negative half span is bad input: one line naming the file, group,
    variable, value and the range allowed; exit 2."""
    out = tmp_path / "bad.nc"
    nml = nml_variant(tmp_path, "bad", edits=[(r"^  tail_x = \S+", "  tail_x = -24.0\n  tail_half_span = -1.0")])
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    line = assert_input_error(res, "&bay: tail_half_span = -1", out)
    assert "bad.nml" in line and "100" in line
