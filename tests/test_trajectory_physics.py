"""The physics columns of `amble simulate --out`: ground reaction, friction ratio, torques, work.

The truth is independent of amble: Newton's law for the whole robot (the ground's force equals the
total mass times the acceleration of the centre of mass, less gravity), with the acceleration from
central differences of the centre of mass's velocity over the file's own samples, and for RABBIT
the torques from M q̈ + h = B u with M, h written out in tests/oracles/rabbit_zero_dynamics.py.
"""

import csv
import math

import numpy as np
import pytest
from oracles import rabbit_zero_dynamics as rabbit_oracle

from amble.cli.main import main


def _read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    cols = {}
    for j, h in enumerate(header):
        name = h.split(" [")[0]
        vals = [r[j] for r in body]
        try:
            cols[name] = np.array([float(v) for v in vals])
        except ValueError:
            cols[name] = np.array(vals)
    return header, cols


def _segments(t):
    """Row ranges between events (an event writes two rows at the same time)."""
    cuts = [0] + [i for i in range(1, len(t)) if t[i] == t[i - 1]] + [len(t)]
    return [(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if b - a >= 5]


def _interior_derivative(t, y):
    """d y / d t by second-order central differences on each segment between events, NaN on
    the segments' end rows (a one-sided difference there is first order only)."""
    out = np.full(y.shape, np.nan)
    for a, b in _segments(t):
        out[a + 1:b - 1] = np.gradient(y[a:b], t[a:b], axis=0, edge_order=2)[1:-1]
    return out


def test_rabbit_csv_holds_ground_force_and_torques_that_obey_newton(tmp_path, capsys):
    path = tmp_path / "walk.csv"
    assert main(["simulate", "rabbit", "--steps", "1", "--out", str(path)]) == 0
    header, c = _read(path)
    for col in ("stance_force_x [N]", "stance_force_z [N]", "stance_force_normal [N]", "friction_ratio",
                "u_stance_hip [N·m]", "power_u_stance_hip [W]", "work_u_stance_hip [J]"):
        assert col in header
    p = rabbit_oracle.PARAMS
    names = ["torso", "stance_hip", "swing_hip", "stance_knee", "swing_knee"]
    q = np.stack([c[n] for n in names], axis=1)
    qd = np.stack([c[n + "_dot"] for n in names], axis=1)
    t = c["t"]
    masses = rabbit_oracle._masses(p)
    total = masses.sum()
    # centre-of-mass velocity from the oracle's hand-written Jacobians
    vcom = np.array([[masses @ (jx[:5] @ v), masses @ (jz[:5] @ v)]
                     for (jx, jz, _, _), v in ((rabbit_oracle._terms(a, b, p), b) for a, b in zip(q, qd))]) / total
    acom = _interior_derivative(t, vcom)
    newton = total * (acom + np.array([0.0, p["g"]]))
    ok = np.isfinite(newton[:, 0])
    assert ok.sum() > 50
    scale = total * p["g"]
    assert np.max(np.abs(newton[ok, 0] - c["stance_force_x"][ok])) < 2e-3 * scale
    assert np.max(np.abs(newton[ok, 1] - c["stance_force_z"][ok])) < 2e-3 * scale
    assert np.allclose(c["stance_force_normal"], c["stance_force_z"])  # level ground
    assert np.allclose(c["friction_ratio"][ok], np.abs(c["stance_force_x"][ok]) / c["stance_force_z"][ok])
    # torques: M q̈ + h = B u, B the four joint columns; the torso row carries no input
    qdd = _interior_derivative(t, qd)
    u = np.stack([c["u_" + n] for n in names[1:]], axis=1)
    for i in np.flatnonzero(ok):
        M, h = rabbit_oracle.dynamics(q[i], qd[i], p)
        gen = M @ qdd[i] + h
        assert abs(gen[0]) < 0.5  # N·m, against torques of up to ~110 N·m
        assert np.max(np.abs(gen[1:] - u[i])) < 0.5
    # work: the integral of power, from zero at the start
    w = c["work_u_stance_hip"]
    assert w[0] == 0.0
    pw = c["power_u_stance_hip"]
    assert math.isclose(w[-1], float(np.sum(0.5 * (pw[1:] + pw[:-1]) * np.diff(t))), rel_tol=1e-9, abs_tol=1e-12)


def test_compass_gait_file_ground_force_is_total_mass_times_com_acceleration(tmp_path, capsys):
    path = tmp_path / "walk.csv"
    assert main(["simulate", "compass-gait", "--steps", "2", "--out", str(path)]) == 0
    _, c = _read(path)
    mh, m, a, b, g = 10.0, 5.0, 0.5, 0.5, 9.81  # Goswami's walker, a = b (the defaults)
    l = a + b
    st, sw, dst, dsw = c["stance"], c["swing"], c["stance_dot"], c["swing_dot"]
    total = mh + 2 * m
    # COM = (mh l R(st) + m b R(st) + m (l R(st) - a R(sw))) / total, R(θ) = (sin θ, cos θ)
    k_st, k_sw = (mh * l + m * b + m * l) / total, -m * a / total
    vx = k_st * np.cos(st) * dst + k_sw * np.cos(sw) * dsw
    vz = -k_st * np.sin(st) * dst - k_sw * np.sin(sw) * dsw
    acc = _interior_derivative(c["t"], np.stack([vx, vz], axis=1))
    newton = total * (acc + np.array([0.0, g]))
    ok = np.isfinite(newton[:, 0])
    assert ok.sum() > 50
    assert np.max(np.abs(newton[ok, 0] - c["stance_force_x"][ok])) < 1e-3 * total * g
    assert np.max(np.abs(newton[ok, 1] - c["stance_force_z"][ok])) < 1e-3 * total * g
    slope = 0.05  # the default: the normal is (sin φ, cos φ)
    normal = c["stance_force_x"] * math.sin(slope) + c["stance_force_z"] * math.cos(slope)
    assert np.allclose(c["stance_force_normal"], normal)
    assert np.all(c["stance_force_normal"] > 0)


@pytest.mark.parametrize("bad", [{"x": (np.zeros(3), "N")}, {"t": (None, "s")}])
def test_extra_columns_must_fit_the_samples(bad):
    from amble.errors import AmbleError
    from amble.models import load
    from amble.simulation.simulate import simulate

    tr = simulate(load("compass-gait"), steps=1, sample_dt=0.05)
    with pytest.raises(AmbleError):
        tr.table(bad)
