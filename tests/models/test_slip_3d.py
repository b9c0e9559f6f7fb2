"""The 3D SLIP runner against an independent SciPy implementation (tests/oracles/slip_3d.py), the
conservation of energy, and the published result (Seipel & Holmes 2005): with the legs placed at
fixed touchdown angles the left–right symmetric running gait is laterally unstable, where the
planar SLIP of the same leg, angle of attack and energy is self-stable (Seyfarth et al. 2002)."""

import math

import numpy as np
import pytest
from oracles.slip_3d import Slip3D

import amble
from amble.models import slip as planar
from amble.models.slip_3d import build

M, G, K, L0 = 80.0, 9.81, 20000.0, 1.0


def _energy(x, mode):
    if mode == "stance":
        return M * G * x[2] + 0.5 * M * float(np.dot(x[3:], x[3:])) + 0.5 * K * (L0 - math.hypot(*x[:3])) ** 2
    return M * G * x[2] + 0.5 * M * float(np.dot(x[3:], x[3:]))


@pytest.fixture(scope="module")
def oracle_gait():
    o = Slip3D()
    p = o.fixed_point()
    return o, p


def test_energy_conserved_over_50_strides(oracle_gait):
    # near the gait, carrying its own energy (no snap at the apex): a lateral push of 1e-5 m/s
    # grows by |μ| = 1.21 a step, to about 0.1 m/s in 50 steps, still running
    o, p = oracle_gait
    start = o.apex_state(p[0], p[1] + 1e-5)
    run = amble.simulate(build(snap_to_energy=False), start, steps=50, rtol=1e-12, atol=1e-12, samples=False)
    assert run.status == "completed" and len(run.events) == 150
    assert abs(run.final_state[4] - p[1]) > 1e-2  # it did drift sideways
    e0 = _energy(start, "descent")
    worst = max(abs(_energy(ev.x_post, ev.target) - e0) / e0 for ev in run.events)
    assert worst <= 1e-10


def test_events_and_apex_map_match_oracle():
    # from a flight state off the gait and off the apex (falling, drifting sideways)
    x0 = np.array([0.1, -0.02, 0.97, 5.05, -0.12, -0.4])
    ref = Slip3D().from_flight(x0)
    run = amble.simulate(build(snap_to_energy=False), x0, steps=1, rtol=1e-12, atol=1e-12, samples=False)
    assert [e.name for e in run.events] == ["touchdown", "liftoff", "apex"]
    for ev in run.events:
        t, x = ref[ev.name]
        assert abs(ev.t - t) <= 1e-8, ev.name
        assert np.max(np.abs(ev.x_post - x)) <= 1e-8, ev.name


def test_symmetric_gait_and_multipliers_match_oracle(oracle_gait):
    o, p = oracle_gait
    cyc = amble.find_fixed_point(build())
    assert np.max(np.abs(cyc.fixed_point - o.apex_state(*p))) <= 1e-8
    mu = sorted(cyc.multipliers, key=abs)
    ref = sorted(o.multipliers(p), key=abs)
    assert np.max(np.abs(np.array(mu) - np.array(ref))) <= 1e-5


def test_symmetric_gait_is_laterally_unstable_where_the_planar_slip_is_self_stable():
    planar_gait = amble.find_fixed_point(planar.build())  # same m, L0, k, alpha, g and energy
    (mu_planar,) = planar_gait.multipliers
    assert planar_gait.stable and abs(mu_planar) < 1
    # with the leg straight ahead (beta = 0) the 3D gait is the planar one: the same apex and the
    # planar runner's multiplier, and besides it a lateral one outside the unit circle
    z, vx = planar_gait.fixed_point[1:3]
    flat = amble.find_fixed_point(build(), [0.0, 0.0, z, vx, 0.0, 0.0], params={"beta": 0.0})
    assert abs(flat.fixed_point[2] - z) <= 1e-9 and abs(flat.fixed_point[4]) <= 1e-12
    small, large = sorted(flat.multipliers.real, key=abs)
    assert abs(small - mu_planar.real) <= 1e-8 and large < -1.2
    for beta_deg in (1.0, 5.0, 10.0):
        o = Slip3D(beta=math.radians(beta_deg))
        p = o.fixed_point(guess=(0.94, 0.0083 * beta_deg))
        cyc = amble.find_fixed_point(build(), o.apex_state(*p), params={"beta": math.radians(beta_deg)})
        assert not cyc.stable
        mu, vec = np.linalg.eig(cyc.jacobian)
        i = int(np.argmax(np.abs(mu)))
        assert abs(mu[i]) > 1.2  # the sideways fall, −1.21 to −1.23 over these angles
        # its direction is the lateral velocity (section coordinates: forward speed, lateral velocity)
        assert cyc.section_coordinates == ["x_dot", "y_dot"] and abs(vec[1, i]) > 0.99 * np.linalg.norm(vec[:, i])
        # the other multiplier is the apex-height mode the planar runner has, and stable
        assert abs(mu[1 - i]) < 1


def test_leg_placed_relative_to_the_heading_leaves_the_lateral_mode_neutral():
    # the docstring's contrast, in the independent runner: measured from the mass's heading, the
    # placement is symmetric under rotations about the vertical, so the lateral multiplier is −1
    o = Slip3D(placement="heading")
    mu = o.multipliers(o.fixed_point(guess=(0.939, 0.045)))
    assert abs(mu[0] + 1) <= 1e-6 and abs(mu[1]) < 1


# (leg stiffness N/m, angle of attack deg) across Seyfarth's self-stable band of the planar runner
BAND = [(16000.0, 66.0), (20000.0, 67.0), (24000.0, 69.0), (24000.0, 70.0), (28000.0, 70.0)]


@pytest.mark.parametrize(("k", "alpha_deg"), BAND)
def test_lateral_instability_across_the_planar_self_stable_band(k, alpha_deg):
    at = {"k": k, "alpha": math.radians(alpha_deg)}
    planar_gait = amble.find_fixed_point(planar.build(), params=at)
    assert planar_gait.stable
    z, vx = planar_gait.fixed_point[1:3]
    o = Slip3D(k=k, alpha=at["alpha"])
    p = o.fixed_point(guess=(z, 0.04))
    cyc = amble.find_fixed_point(build(), o.apex_state(*p), params=at)
    assert np.max(np.abs(cyc.fixed_point - o.apex_state(*p))) <= 1e-8
    mu = np.linalg.eigvals(cyc.jacobian)
    ref = o.multipliers(p)
    assert np.max(np.abs(np.sort_complex(mu) - np.sort_complex(ref))) <= 1e-5
    assert min(mu.real) < -1.15 and not cyc.stable  # the sideways fall, in every case
