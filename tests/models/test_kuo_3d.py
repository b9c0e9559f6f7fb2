"""Kuo's 3D walker: conservation laws at heel strike and between impacts, and Kuo's result — one
unstable lateral multiplier passively, none with his once-per-step foot placement.

Angular momenta come from the compiled kinematics and the masses written out here, with numpy;
the closed-loop multipliers from finite differences of the controlled walk itself.
"""

import numpy as np
import pytest

from amble import simulate
from amble.analysis.poincare import find_fixed_point
from amble.backend.kernels import compiled
from amble.models import kuo_3d, load
from amble.simulation.simulate import parameter_vector

MIRROR = np.array([-1.0, 1.0, -1.0])  # angular momentum (a pseudovector) under the y → −y relabel


@pytest.fixture(scope="module")
def kuo():
    return load("kuo-3d")


def _momentum(k, p, x, about):
    pos, vel = k.kinematics_rows([0.0], [0], x, p)
    names = k.meta["points"]
    par = dict(zip(k.meta["params"], p))
    masses = {"pelvis": par["M"], "stance_leg": par["m"], "swing_leg": par["m"]}
    o = pos[0][names.index(about)]
    return sum(mi * np.cross(pos[0][names.index(n)] - o, vel[0][names.index(n)]) for n, mi in masses.items())


def _heel_strike_conserves_angular_momentum(system, n):
    """At 40 random pre-impact states (``n`` coordinates): the angular momentum about the roll axis
    and the pelvis axis through the impact point is the same before and after heel strike, and the
    kinetic energy does not grow."""
    k = compiled(system)
    p = parameter_vector(k, None)
    rng = np.random.default_rng(17)
    for _ in range(40):
        x = np.concatenate([rng.uniform(-0.4, 0.4, n), rng.uniform(-2, 2, n)])
        _, post = k.reset("heel_strike", 0.0, x, p)
        roll = x[2]
        axes = np.array([[1.0, 0, 0], [0, np.cos(roll), np.sin(roll)]])  # roll axis, pelvis axis
        h0 = axes @ _momentum(k, p, x, "swing_foot")
        h1 = axes @ (MIRROR * _momentum(k, p, post, "stance_foot"))
        assert np.allclose(h1, h0, rtol=0, atol=1e-11 * max(1.0, np.abs(h0).max()))
        kin0, kin1 = (k.energy_rows([0.0], [0], s, p)[0, 0] for s in (x, post))
        assert kin1 <= kin0 + 1e-12


def test_heel_strike_conserves_angular_momentum_about_the_roll_and_pelvis_axes(kuo):
    _heel_strike_conserves_angular_momentum(kuo, 5)


def test_energy_is_conserved_between_impacts_without_dampers(kuo):
    x0 = np.array(kuo_3d.FIXED_POINT)
    x0[7:] = [-0.3, 0.2, 0.1]  # a different start, hip rates at rest
    tr = simulate(kuo, x0, params={"c_hip": 0.0, "c_stance": 0.0}, t_end=0.25, sample_dt=0.005)
    first = tr.events[0].t if tr.events else tr.t[-1]
    e = tr.energy().sum(axis=1)[tr.t < first]
    assert len(e) > 10 and np.ptp(e) < 1e-8 * np.abs(e).max()


def test_passive_gait_has_exactly_one_unstable_lateral_multiplier(kuo):
    lc = find_fixed_point(kuo)
    assert lc.residual < 1e-9
    outside = np.abs(lc.multipliers) > 1
    assert outside.sum() == 1 and abs(lc.multipliers[outside][0].imag) < 1e-9  # a real multiplier


def _closed_loop_multipliers(system, gain, h=1e-6):
    x_star = np.array(kuo_3d.FIXED_POINT)

    def step(x):
        status, states = kuo_3d.walk_with_foot_placement(system, x, 1, gain)
        assert status == "completed"
        return states[-1]

    J = np.column_stack([(step(x_star + h * e) - step(x_star - h * e)) / (2 * h) for e in np.eye(len(x_star))])
    return np.linalg.eigvals(J)


def test_foot_placement_moves_every_multiplier_inside_the_unit_circle(kuo):
    passive = _closed_loop_multipliers(kuo, 0.0)
    controlled = _closed_loop_multipliers(kuo, 1.0)
    assert np.sum(np.abs(passive) > 1) == 1
    assert np.all(np.abs(controlled) < 1)


def test_foot_placement_recovers_from_a_sideways_push_that_fells_the_passive_walker(kuo):
    x0 = np.array(kuo_3d.FIXED_POINT)
    x0[7] += 1e-4  # roll rate, rad/s: the lateral mode grows about tenfold per step
    status, _ = kuo_3d.walk_with_foot_placement(kuo, x0, 20, gain=0.0)
    assert status != "completed"
    status, states = kuo_3d.walk_with_foot_placement(kuo, x0, 20, gain=1.0)
    assert status == "completed"
    assert np.max(np.abs(states[-1] - kuo_3d.FIXED_POINT)) < 1e-6


def test_rigid_hips_give_kuos_three_degrees_of_freedom_the_same_kind_of_gait():
    """Kuo's model itself (hips rigid, three coordinates): its heel strike keeps the same two
    components of angular momentum, and its passive gait has one unstable multiplier."""
    rigid = kuo_3d.rigid_walker()
    _heel_strike_conserves_angular_momentum(rigid, 3)
    lc = find_fixed_point(rigid)
    assert np.sum(np.abs(lc.multipliers) > 1) == 1
