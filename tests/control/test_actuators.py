"""Actuators, input matrix, recorded inputs, power and work — against closed forms and the
work–energy theorem."""

import math

import numpy as np
import pytest
import sympy as sp

from amble import HybridSystem, Model, ModelError, R, derive, simulate, walker
from amble.models.compass_gait import model as compass_model


def _compass(law=None, limit=40.0):
    m = compass_model("cg-actuated")
    st, sw = m.q
    slope = m.symbol("slope")
    u = m.actuator("hip_torque", on=sw - st, limit=limit)
    if law is not None:
        m.control({u: law(m, st, sw)})
    return m, walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                     start=[-0.2168, 0.3168, 1.0839, 0.3981])


def test_input_matrix_is_the_gradient_of_what_the_actuator_drives():
    m, _ = _compass()
    st, sw = m.q
    x = m.actuator("ankle", on=st)
    assert m.inputs == [sp.Symbol("hip_torque", real=True), x]
    assert m.input_matrix() == sp.Matrix([[-1, 1], [1, 0]])
    assert m.input_limits == {"hip_torque": 40.0, "ankle": None}
    eq = derive(m)
    assert eq.B == m.input_matrix() and eq.inputs == m.inputs
    assert eq.Gamma == sp.zeros(2, 1)  # the passive force stays passive
    assert eq.closed_loop_force == sp.zeros(2, 1)  # no law: inputs are zero


def test_bad_declarations_are_model_errors():
    m, _ = _compass()
    st, sw = m.q
    with pytest.raises(ModelError, match="already taken"):
        m.actuator("hip_torque", on=st)
    with pytest.raises(ModelError, match="already taken"):
        m.actuator("mh", on=st)
    with pytest.raises(ModelError, match="already taken"):
        m.parameter("hip_torque", 1.0)
    with pytest.raises(ModelError, match="positive"):
        m.actuator("knee", on=st, limit=-1)
    with pytest.raises(ModelError, match="expression of the coordinates"):
        m.actuator("nothing", on=sp.Integer(3))
    with pytest.raises(ModelError, match="callable"):
        m.control({"hip_torque": lambda x: -x})
    with pytest.raises(ModelError, match="undefined function"):
        m.control({"hip_torque": sp.Function("k")(st)})
    with pytest.raises(ModelError, match="not an input"):
        m.control({"torque": st})
    with pytest.raises(ModelError, match="neither"):
        m.control({"hip_torque": sp.Symbol("z")})


def test_inputs_power_and_work_balance_the_energy():
    """Work–energy theorem: over each step's continuous phase the change of K + V equals the
    work of the inputs (the trapezoidal rule on a fine grid)."""
    m, sys_ = _compass(lambda m, st, sw: -8 * (sw + st) - 1.5 * (m.dot(sw) + m.dot(st)))
    tr = simulate(sys_, steps=2, sample_dt=1e-4)
    assert tr.status == "completed"
    u = tr.inputs()["hip_torque"]
    st, sw, std, swd = (tr.column(n) for n in ("stance", "swing", "stance_dot", "swing_dot"))
    np.testing.assert_allclose(u, -8 * (sw + st) - 1.5 * (swd + std), rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.joint_power()["hip_torque"], u * (swd - std), rtol=0, atol=1e-12)
    e = tr.energy().sum(axis=1)
    ev = [0] + [i for i in range(1, len(tr.t)) if tr.t[i] == tr.t[i - 1]] + [len(tr.t)]
    work = tr.work_per_step()["hip_torque"]
    assert len(work) == 2  # the run ends at its second footfall
    for k, (a, b) in enumerate(zip(ev[:-1], ev[1:])):
        if b - a > 2:
            assert work[k] == pytest.approx(e[b - 1] - e[a], abs=1e-6)
    absw = tr.work_per_step(absolute=True)["hip_torque"]
    assert np.all(absw >= np.abs(work) - 1e-12)
    cot = tr.cost_of_transport()
    hip = tr.world_points()["hip"][:, 0]
    assert cot == pytest.approx(absw.sum() / (20.0 * 9.81 * (hip[-1] - hip[0])), rel=1e-12)


def test_inputs_are_columns_with_units(tmp_path):
    m, sys_ = _compass(lambda m, st, sw: -2 * (sw + st))
    tr = simulate(sys_, steps=1, sample_dt=0.05)
    head = tr.save(tmp_path / "walk.csv").read_text().splitlines()[0]
    assert "hip_torque [N·m]" in head and "power_hip_torque [W]" in head


def test_a_torque_cancelling_gravity_lets_a_pendulum_turn_uniformly():
    """Computed torque from the model's own bias: u = h makes θ̈ = 0, θ(t) = θ₀ + ω₀ t."""
    m = Model("pendulum")
    (th,) = m.coordinates("theta")
    (l,) = m.parameters(l=0.7)
    m.point("pivot", (0, 0))
    m.point("bob", l * R(th), mass=2.0, link="pivot")
    m.gravity(9.81)
    u = m.actuator("motor", on=th)
    _, h = m.mass_and_bias()
    m.control({u: h[0]})
    s = HybridSystem("pendulum", m)
    tr = simulate(s, [0.3, 1.25], t_end=2.0, sample_dt=0.1)
    np.testing.assert_allclose(tr.column("theta"), 0.3 + 1.25 * tr.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.inputs()["motor"], -2.0 * 9.81 * 0.7 * np.sin(0.3 + 1.25 * tr.t), atol=1e-9)
    assert math.isfinite(tr.inputs()["motor"][0])
