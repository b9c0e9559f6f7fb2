"""Walker notions on the Walker type, declared units in tables, files and plots, the model listing."""

from __future__ import annotations

import csv

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import amble  # noqa: E402
from amble import R3, Guard, HybridSystem, Model, ModelError, Walker, walker  # noqa: E402
from amble.models import load, names  # noqa: E402


def _ball() -> HybridSystem:
    m = Model("ball")
    x, z = m.coordinates("x z", unit="m")
    mass, g = m.parameters(mass=1.0, g=9.81)
    m.declare_units(mass="kg", g="m/s²")
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    s = HybridSystem("ball", m)
    s.terminal("landed", "ball", Guard(z, -1), status="landed")
    return s


def test_units_are_read_from_the_model():
    s = _ball()
    assert (s.unit("x"), s.unit("z_dot"), s.unit("mass"), s.unit("g")) == ("m", "m/s", "kg", "m/s²")
    assert s.unit("nothing") == ""
    with pytest.raises(ModelError, match="unknown name"):
        s.modes["ball"].declare_units(nope="m")


def test_csv_header_and_plot_labels_carry_the_units(tmp_path):
    tr = amble.simulate(_ball(), [0.0, 1.0, 0.5, 0.0], t_end=2.0)
    path = tr.save(tmp_path / "ball.csv")
    with path.open() as f:
        header = next(csv.reader(f))
    assert header[:6] == ["t [s]", "mode", "x [m]", "z [m]", "x_dot [m/s]", "z_dot [m/s]"]
    fig = amble.plot_trajectory(tr)
    assert fig.axes[0].get_ylabel() == "position [m]"  # not "angle [rad]": the ball's x and z are metres
    npz = np.load(tr.save(tmp_path / "ball.npz"))
    assert dict(zip(npz["columns"], npz["units"]))["z_dot"] == "m/s"


def test_a_scaled_model_says_its_time_unit(tmp_path):
    tr = amble.simulate(load("simplest-walker"), steps=1)
    assert tr.unit("t") == "√(l/g)" and tr.unit("theta_dot") == "rad/√(l/g)"
    assert tr.unit("kinetic_energy") == ""  # scaled energies have no unit of J


def _legs() -> Model:
    m = Model("legs", dims=3)
    st, sw = m.coordinates("stance swing")
    m.point("stance_foot", (0, 0, 0))
    hip = m.point("hip", R3(st, 0), mass=1)
    m.point("swing_foot", hip - R3(sw, 0), mass=0.1)
    m.gravity(9.81)
    return m


def test_mirror_reflects_the_lateral_axis_at_steps_only():
    m = _legs()
    st, sw = m.q
    w = walker(m, foot="swing_foot", hip="hip", slope=0.0, relabel={st: sw, sw: st}, mirror="y")
    assert w.frame_change("heel_strike") == ("swing_foot", (1.0, -1.0, 1.0))
    assert w.frame_change("hip_on_ground") == (None, (1.0, 1.0, 1.0))
    plain = walker(m, foot="swing_foot", hip="hip", slope=0.0, relabel={st: sw, sw: st})
    assert plain.frame_change("heel_strike") == ("swing_foot", (1.0, 1.0, 1.0))


def test_walker_refuses_a_bad_mirror_or_hip():
    m = _legs()
    with pytest.raises(ModelError, match="mirror"):
        Walker("w", m, mirror="sideways")
    with pytest.raises(ModelError, match="hip"):
        Walker("w", m, hip="pelvis")


def test_walker_slope_resolves_a_parameter():
    w = load("compass-gait")
    assert isinstance(w, Walker)
    assert w.slope_value({}) == pytest.approx(0.05)
    assert w.slope_value({"slope": 0.08}) == pytest.approx(0.08)


def test_mirrored_walk_alternates_sides_in_the_world():
    # humanoid-3d-yaw (a pelvis of width w) swaps its legs with y → −y: the footholds must alternate
    # sides (a straight walk), which they do only if the world frame is reflected at every footfall
    tr = amble.simulate(load("humanoid-3d-yaw"), steps=4, sample_dt=0.01)
    wp = tr.world_points()["stance_foot"]
    ys = [wp[np.searchsorted(tr.t, e.t, side="right") - 1, 1] for e in tr.step_events]  # post-impact rows
    assert all(abs(ys[i] - ys[i + 2]) < 1e-3 for i in range(len(ys) - 2))
    assert abs(ys[0] - ys[1]) > 0.05


def test_model_listing_follows_declared_positions():
    import importlib

    import amble.models as lib

    positions = [importlib.import_module(f"amble.models.{lib.registry()[n]}").POSITION for n in names()]
    assert positions == sorted(positions)
    assert names()[:4] == ["compass-gait", "kneed-biped", "humanoid-2d", "humanoid-3d"]
