"""The SLIP walker against an independent SciPy walker (tests/oracles/slip_walker.py): events,
states and the midstance return map, the walking gait and its multipliers (finite differences of
the SciPy map), the conservation of energy, and the drawing of both legs."""

import json
import math

import numpy as np
import pytest
from oracles.slip_walker import SlipWalker

import amble
from amble.cli.main import main
from amble.models.slip_walker import PARAMS, build

M, G, K, L0 = PARAMS["m"], PARAMS["g"], PARAMS["k"], PARAMS["L0"]


def _energy(x, mode):
    """Total energy (J) from a state of either domain, written out here."""
    if mode == "double":
        u, w, d, ud, wd, dd = x
        springs = 0.5 * K * ((L0 - math.hypot(u, w)) ** 2 + (L0 - math.hypot(u - d, w)) ** 2)
        return M * G * w + 0.5 * M * (ud**2 + wd**2 + dd**2) + springs
    u, w, ud, wd = x
    return M * G * w + 0.5 * M * (ud**2 + wd**2) + 0.5 * K * (L0 - math.hypot(u, w)) ** 2


@pytest.fixture(scope="module")
def gait():
    o = SlipWalker(alpha=PARAMS["alpha"], E=PARAMS["energy"])
    p = o.fixed_point()
    return o, p, amble.find_fixed_point(build())


def test_events_states_and_return_map_match_oracle():
    # from midstance off the gait: lower, and rising
    o = SlipWalker(alpha=PARAMS["alpha"], E=PARAMS["energy"])
    y, yd = 0.985, 0.05
    ref = o.step(y, yd)
    start = [0.0, y, o.speed(y, yd), yd]
    run = amble.simulate(build(), start, steps=1, rtol=1e-12, atol=1e-12, samples=False)
    assert [e.name for e in run.events] == ["touchdown", "liftoff", "midstance"]
    td, lo, mid = run.events
    assert abs(td.t - ref["t_td"]) <= 1e-9 and abs(lo.t - ref["t_lo"]) <= 1e-9 and abs(mid.t - ref["t_mid"]) <= 1e-9
    u, w, d, ud, wd, dd = td.x_post
    assert np.max(np.abs(np.array([u, w, ud, wd]) - ref["s_td"])) <= 1e-9
    assert abs(d - ref["d"]) <= 1e-9 and dd == 0.0
    assert np.max(np.abs(lo.x_post - ref["s_lo"])) <= 1e-9
    assert np.max(np.abs(run.final_state - ref["s_mid"])) <= 1e-9


def test_energy_conserved_over_25_steps():
    # carrying its own energy (no snap at midstance), from off the gait; d_dot stays exactly zero
    o = SlipWalker(alpha=PARAMS["alpha"], E=PARAMS["energy"])
    start = [0.0, 0.985, o.speed(0.985, 0.05), 0.05]
    run = amble.simulate(build(snap_to_energy=False), start, steps=25, rtol=1e-12, atol=1e-12)
    assert run.status == "completed" and len(run.events) == 75
    e0 = _energy(start, "single")
    worst = max(abs(_energy(x, ev.source if i == 0 else ev.target) - e0) / e0
                for ev in run.events for i, x in enumerate((ev.x_pre, ev.x_post)))
    assert worst <= 1e-10
    double = np.asarray(run.mode) == run.kernels.mode_index("double")
    assert np.all(np.asarray(run.x)[double, 5] == 0.0)
    rows = [_energy(np.asarray(x)[: (6 if dbl else 4)], "double" if dbl else "single") for x, dbl in zip(run.x, double)]
    assert max(abs(e - e0) for e in rows) / e0 <= 1e-10


def test_walking_gait_and_multipliers_match_oracle(gait):
    o, p, cyc = gait
    assert abs(cyc.fixed_point[1] - p[0]) <= 1e-9 and abs(cyc.fixed_point[3] - p[1]) <= 1e-9
    assert abs(cyc.fixed_point[2] - o.speed(*p)) <= 1e-9
    mu = np.array(sorted(cyc.multipliers, key=lambda z: z.imag))
    ref = sorted(o.multipliers(p), key=lambda z: z.imag)
    assert np.max(np.abs(np.array(mu) - np.array(ref))) <= 1e-5
    assert cyc.stable and max(abs(mu)) < 0.97
    # periodic: one step from the fixed point returns to it
    run = amble.simulate(build(), cyc.fixed_point, steps=1, rtol=1e-12, atol=1e-12, samples=False)
    assert np.max(np.abs(run.final_state - cyc.fixed_point)) <= 1e-9
    # a walking gait: a double-support phase of a quarter of the step (0.122 s of 0.417 s)
    td, lo, _ = run.events
    ref = o.step(*p)
    assert lo.t - td.t > 0.1 and abs((lo.t - td.t) - ref["double_support"]) <= 1e-9
    assert abs(cyc.step_time - ref["t_mid"]) <= 1e-9


def test_paper_walking_energy_gait_matches_oracle():
    # Geyer et al.'s 820 J at 20 kN/m and 69°: the symmetric gait exists, with a complex pair of
    # multipliers just outside the unit circle (|μ| = 1.16); it becomes stable near 835 J
    o = SlipWalker(alpha=PARAMS["alpha"], E=820.0)
    p = o.fixed_point()
    cyc = amble.find_fixed_point(build(), params={"energy": 820.0})
    assert abs(cyc.fixed_point[1] - p[0]) <= 1e-9
    ref = o.multipliers(p)
    assert abs(max(abs(cyc.multipliers)) - max(abs(ref))) <= 1e-5 and 1.1 < max(abs(ref)) < 1.2


def test_limit_cycle_animation_draws_both_legs(capsys, tmp_path):
    out = tmp_path / "walk.html"
    assert main(["limit-cycle", "slip-walker", "--animate", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["stable"]
    page = out.read_text()
    assert '"between":["foot","mass"]' in page and '"between":["mass","swing_foot"]' in page
    # the legs in the world: a stance foot stays where it landed, both feet on the ground in
    # double support, and the front foot of double support is the next stance foot
    run = amble.simulate(build(), steps=3, rtol=1e-12, atol=1e-12)
    world = run.world_points()
    up = int(np.argmax(np.ptp(world["mass"], axis=0)[1:])) + 1  # the vertical axis of the world
    double = np.asarray(run.mode) == run.kernels.mode_index("double")
    assert np.max(np.abs(world["foot"][:, up])) <= 1e-12
    assert np.max(np.abs(world["swing_foot"][double, up])) <= 1e-12
    lands = [i for i, e in enumerate(run.events) if e.name == "touchdown"]
    assert len(lands) == 3
    feet = np.unique(np.round(world["foot"][:, 0], 9))
    assert len(feet) == 4 and np.all(np.diff(feet) > 0.4)
