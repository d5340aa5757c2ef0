"""The line scene says where its peak tension is: the attribute
`peak_tension_segment` and the summary's "in segment k". Before, the file gave
`peak_tension_N` and its time only; on a winch-driven rope that snatches the
peak (59.0 kN) sat inside the line between two records, and no output said
which segment carried it.

Case with an independent answer: a line hanging from a fixed top end with a
50 kg point mass at the bottom, released straight (its strain the mass's
weight alone) and damped. Every segment carries the weight of what hangs below
it, so the top segment's tension is the largest at every instant (statics:
ρ g ℓ = 19.6 N above the next one; the records show 20 N of margin through the
transient). The top is end a (segment 1) or, mirrored, end b (segment N): the
answer must follow the line's orientation, in both schemes. Exact: an index."""
import pytest
import xarray as xr

from conftest import run_airlaunch

G = 9.80665
L, N, EA, RHO, MASS = 10.0, 10, 1.0e6, 2.0, 50.0


def hanging_nml(tmp_path, top, scheme):
    d = L * (1.0 + MASS * G / EA)                    # stretched by the mass's weight
    fixed = "kind = 'fixed'\n  {e}_position = 0, 0, 0"
    mass = f"kind = 'point_mass'\n  {{e}}_position = 0, {-d!r}, 0\n  {{e}}_mass = {MASS}"
    ends = {"a": fixed if top == "a" else mass, "b": fixed if top == "b" else mass}
    path = tmp_path / f"hang_{top}_{scheme}.nml"
    path.write_text(f"""&run
  scene = 'line'
  t_end = 1.0
  output_dt = 0.01
  output = '{tmp_path / f"hang_{top}_{scheme}.nc"}'
/
&line
  length = {L}
  n_seg = {N}
  ea = {EA}
  mass_per_length = {RHO}
  damping = 2000.0
  settling_damping = 5.0
/
&line_scene
  a_{ends['a'].format(e='a')}
  b_{ends['b'].format(e='b')}
  scheme = '{scheme}'
/
""")
    return path


@pytest.mark.parametrize("scheme", ["cvode", "marching"])
@pytest.mark.parametrize("top,segment", [("a", 1), ("b", N)])
def test_peak_tension_segment_is_the_top_of_a_hanging_line(airlaunch_exe, tmp_path, scheme, top, segment):
    nml = hanging_nml(tmp_path, top, scheme)
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    assert f"N in segment {segment}, first reached at" in res.stdout, res.stdout
    with xr.open_dataset(nml.with_suffix(".nc")) as ds:
        assert int(ds.attrs["peak_tension_segment"]) == segment
        # the records agree: the largest recorded tension is in that segment too
        assert int(ds["line_tension"].max("time").argmax("segment")) + 1 == segment
        # and the peak is a dynamic overshoot above the static top tension (m + ρL) g
        assert float(ds.attrs["peak_tension_N"]) > (MASS + RHO * L) * G
