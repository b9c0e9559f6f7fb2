"""check_gait against closed forms: the rimless wheel's hub rides a massless spoke, so the
ground pushes along the spoke with F = m (g cos θ − l θ̇²)."""

import math

import numpy as np
import pytest

from amble.analysis.gait_check import check_gait, ground_reaction
from amble.analysis.poincare import find_fixed_point
from amble.models import load


@pytest.fixture(scope="module")
def wheel_walk():
    lc = find_fixed_point(load("rimless-wheel"))
    return lc.trajectory(steps=3)


def test_ground_reaction_of_the_rimless_wheel_is_along_the_spoke(wheel_walk):
    tr = wheel_walk
    p = tr.parameters
    th, thd = tr.column("theta"), tr.column("theta_dot")
    F, Fn, Ft = ground_reaction(tr)
    along = p["m"] * (p["g"] * np.cos(th) - p["l"] * thd**2)
    np.testing.assert_allclose(F[:, 0], along * np.sin(th), atol=1e-9)
    np.testing.assert_allclose(F[:, 2], along * np.cos(th), atol=1e-9)
    np.testing.assert_allclose(Fn, along * np.cos(th - p["slope"]), atol=1e-9)
    np.testing.assert_allclose(Ft, np.abs(along * np.sin(th - p["slope"])), atol=1e-9)


def test_check_gait_of_the_rimless_wheel(wheel_walk):
    c = check_gait(wheel_walk)
    a = math.pi / 8
    assert c.max_friction_ratio == pytest.approx(math.tan(a), rel=1e-3)  # |θ − γ| ≤ α
    assert c.ok and c.friction_ok and c.impulse_positive and c.trailing_foot_leaves
    assert not check_gait(wheel_walk, mu=0.3).friction_ok  # tan(π/8) = 0.414 > 0.3
    assert c.max_input_ratio == 0.0


def _compass_momentum(x: np.ndarray, p: dict) -> np.ndarray:
    """Σ mᵢ vᵢ (x, z) of the compass gait, by hand: hip at l(sin s, cos s), the stance leg's mass
    at b(sin s, cos s), the swing leg's at hip − a(sin w, cos w); s, w the stance and swing angles
    from the vertical (foot → hip), l = a + b."""
    s, w, sd, wd = x[..., 0], x[..., 1], x[..., 2], x[..., 3]
    a, b, mh, m = p["a"], p["b"], p["mh"], p["m"]
    hip = (a + b) * np.stack([np.cos(s) * sd, -np.sin(s) * sd])
    st = b * np.stack([np.cos(s) * sd, -np.sin(s) * sd])
    sw = hip - a * np.stack([np.cos(w) * wd, -np.sin(w) * wd])
    return mh * hip + m * st + m * sw


def test_check_gait_of_the_controlled_compass_gait_agrees_with_a_recomputation():
    # every number of the report recomputed from the gait's samples with the compass gait's
    # kinematics written out here: the ground reaction as d(Σ mᵢ vᵢ)/dt − M g by central
    # differences of the momentum within each step (h = 1e-4 s: error ~ h² ≈ 1e-8 relative), the
    # swing foot's height l (cos s − cos w) on level ground, the footfall impulse and the
    # trailing foot's lift speed from the event states
    import json

    import amble

    lc = find_fixed_point(load("compass-gait-level"))
    tr = amble.simulate(lc.hybrid_system, lc.fixed_point, params=lc.parameters, steps=2, sample_dt=1e-4)
    c = check_gait(tr)
    p = tr.parameters
    assert p["slope"] == 0.0  # level ground: the normal is z
    l, M = p["a"] + p["b"], p["mh"] + 2 * p["m"]
    # a footfall is two rows at one time (the states before and after): the steps lie between
    cuts = np.flatnonzero(np.diff(tr.t) == 0) + 1
    segments = [(t, x) for t, x in zip(np.split(tr.t, cuts), np.split(tr.x, cuts)) if t.size > 2]
    assert len(segments) == 2 and len(tr.step_events) == 2
    fn, ratio, clear = [], [], []
    for t, x in segments:
        t0, t1 = t[0], t[-1]
        P = _compass_momentum(x, p)
        dP = np.gradient(P, t, axis=1, edge_order=2)
        F = dP - M * np.array([0.0, -p["g"]])[:, None]
        fn.append(F[1])
        ratio.append(np.abs(F[0]) / F[1])
        inner = (t > t0 + 0.05 * (t1 - t0)) & (t < t1 - 0.05 * (t1 - t0))
        clear.append(np.min(l * (np.cos(x[inner, 0]) - np.cos(x[inner, 1]))))
    fn, ratio = np.concatenate(fn), np.concatenate(ratio)
    assert c.min_normal_force == pytest.approx(fn.min(), rel=1e-6)
    assert c.max_friction_ratio == pytest.approx(ratio.max(), rel=1e-6)
    assert c.min_swing_clearance == pytest.approx(min(clear), rel=1e-9, abs=1e-12)
    impulses = [(_compass_momentum(e.x_post, p) - _compass_momentum(e.x_pre, p))[1] for e in tr.step_events]
    # just after a footfall the old stance foot is the swing foot, at height l (cos s − cos w)
    lifts = [l * (-np.sin(e.x_post[0]) * e.x_post[2] + np.sin(e.x_post[1]) * e.x_post[3]) for e in tr.step_events]
    assert c.min_normal_impulse == pytest.approx(min(impulses), rel=1e-9)
    assert c.min_trailing_foot_lift_speed == pytest.approx(min(lifts), rel=1e-9)
    assert c.max_input_ratio == 0.0  # no input has a limit
    verdicts = {"normal_force_positive": fn.min() > 0, "friction_ok": ratio.max() < c.mu,
                "swing_foot_clear": min(clear) > 0, "impulse_positive": min(impulses) > 0,
                "trailing_foot_leaves": min(lifts) > 0, "within_limits": True}
    out = json.loads(json.dumps(c.to_json()))
    assert {k: out[k] for k in verdicts} == verdicts
    assert out["ok"] is all(verdicts.values()) and out["mu"] == 0.7
    assert out["min_normal_force"] == pytest.approx(fn.min(), rel=1e-6)


def test_limit_cycle_json_reports_the_checks_of_an_actuated_model(capsys):
    import json

    from amble.cli.main import main

    assert main(["limit-cycle", "compass-gait-level", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["stable"] and out["checks"]["normal_force_positive"] and out["checks"]["mu"] == 0.7
    assert out["checks"]["max_friction_ratio"] > 0
    assert set(out["work_per_step"]) == {"hip", "ankle"} and out["cost_of_transport"] > 0
