"""The bipedal SLIP runner with swing-leg retraction against an independent SciPy runner
(tests/oracles/slip_biped_runner.py): events, states and the apex map, the running gait and its
multiplier (the runner's own Newton iteration and central differences), the stability the
retraction brings (the same gait with the leg held at its touchdown angle is unstable), the
conservation of energy, and the flight phase in the viewer."""

import json
import math
import re

import numpy as np
import pytest
from oracles.slip_biped_runner import BipedRunner

import amble
from amble.cli.main import main
from amble.models.slip_biped_runner import PARAMS, build

M, G, K, L0 = PARAMS["m"], PARAMS["g"], PARAMS["k"], PARAMS["L0"]


def _oracle(**over) -> BipedRunner:
    p = {n: PARAMS[n] for n in ("m", "L0", "k", "alpha", "omega", "g", "y0", "v0")}
    return BipedRunner(**{**p, **over})


def _apex(o: BipedRunner, y: float, alpha: float, omega: float) -> list[float]:
    """The descent state at an apex ``y`` m high on the runner's energy level."""
    return [0.0, y, alpha, o.apex_speed(y), 0.0, omega]


def _energy(x, mode):
    """Total energy (J) from a state of either domain, written out here."""
    if mode == "stance":
        u, w, ud, wd = x
        return M * G * w + 0.5 * M * (ud**2 + wd**2) + 0.5 * K * (L0 - math.hypot(u, w)) ** 2
    _, y, _, xd, yd, _ = x
    return M * G * y + 0.5 * M * (xd**2 + yd**2)


@pytest.fixture(scope="module")
def gait():
    o = _oracle()
    y = o.fixed_point(1.18)
    return o, y, amble.find_fixed_point(build())


def test_events_states_and_apex_map_match_oracle():
    # from an apex off the gait, lower: the leg lands sooner, so flatter
    o = _oracle()
    y = 1.16
    ref = o.stride(y)
    run = amble.simulate(build(), _apex(o, y, PARAMS["alpha"], PARAMS["omega"]), steps=1, rtol=1e-12, atol=1e-12,
                         samples=False)
    assert [e.name for e in run.events] == ["touchdown", "liftoff", "apex"]
    td, lo, apex = run.events
    assert abs(td.t - ref["t_td"]) <= 1e-9 and abs(lo.t - ref["t_lo"]) <= 1e-9 and abs(apex.t - ref["t_apex"]) <= 1e-9
    # the leg retracted for the descent's time: it lands at alpha + omega t
    assert abs(td.x_pre[2] - ref["angle_td"]) <= 1e-9 and ref["angle_td"] > PARAMS["alpha"] + 0.2
    assert np.max(np.abs(td.x_post - ref["touchdown"])) <= 1e-9
    assert np.max(np.abs(lo.x_pre - ref["liftoff"])) <= 1e-9
    assert abs(run.final_state[1] - ref["y_next"]) <= 1e-9 and abs(run.final_state[3] - ref["vx_next"]) <= 1e-9


def test_running_gait_is_periodic_and_matches_oracle(gait):
    o, y, cyc = gait
    assert abs(cyc.fixed_point[1] - y) <= 1e-9 and abs(cyc.fixed_point[3] - o.apex_speed(y)) <= 1e-9
    ref = o.stride(y)
    assert abs(cyc.step_time - ref["t_apex"]) <= 1e-9
    assert cyc.residual <= 1e-9
    # one step from the fixed point returns to it
    run = amble.simulate(build(), cyc.fixed_point, steps=1, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(run.final_state - cyc.fixed_point)) <= 1e-9
    # the step's length: the mass's travel in the world from apex to apex
    world = run.world_points()
    assert abs((world["mass"][-1, 0] - world["mass"][0, 0]) - ref["step_length"]) <= 1e-9
    # closed loop: stable, nearly deadbeat
    (mu,) = cyc.multipliers
    assert abs(mu.imag) == 0.0 and abs(mu.real - o.multiplier(y)) <= 1e-6
    assert cyc.stable and abs(mu) < 0.1


def test_stability_comes_from_the_retraction(gait):
    o, y, cyc = gait
    # the leg held fixed at the gait's touchdown angle runs the same gait, unstably
    fixed = o.fixed_angle(y)
    passive = amble.find_fixed_point(build(), guess=[0.0, y, fixed.alpha, o.apex_speed(y), 0.0, 0.0],
                                     params={"alpha": fixed.alpha, "omega": 0.0})
    assert abs(passive.fixed_point[1] - cyc.fixed_point[1]) <= 1e-9
    assert abs(passive.step_time - cyc.step_time) <= 1e-9
    (mu,) = passive.multipliers
    assert abs(mu.real - fixed.multiplier(y)) <= 1e-6
    assert mu.real > 1.3 and not passive.stable
    # without retraction at the apex angle alpha there is no gait: every apex rises
    still = _oracle(omega=0.0)
    for h in (1.0, 1.1, 1.18, 1.25):
        run = amble.simulate(build(), _apex(still, h, PARAMS["alpha"], 0.0), steps=1, params={"omega": 0.0},
                             rtol=1e-12, atol=1e-12, samples=False)
        ref = still.apex_map(h)
        assert abs(run.final_state[1] - ref) <= 1e-9 and ref > h


def test_energy_conserved_over_50_steps():
    # carrying its own energy (no snap at the apex), from an apex off the gait; the legs are
    # massless, so the retraction costs nothing
    o = _oracle()
    start = _apex(o, 1.16, PARAMS["alpha"], PARAMS["omega"])
    run = amble.simulate(build(snap_to_energy=False), start, steps=50, rtol=1e-12, atol=1e-12)
    assert run.status == "completed" and len(run.events) == 150
    e0 = _energy(start, "descent")
    worst = max(abs(_energy(x, ev.source if i == 0 else ev.target) - e0) / e0
                for ev in run.events for i, x in enumerate((ev.x_pre, ev.x_post)))
    assert worst <= 1e-10
    stance = np.asarray(run.mode) == run.kernels.mode_index("stance")
    rows = [_energy(np.asarray(x)[: (4 if st else 6)], "stance" if st else "descent") for x, st in zip(run.x, stance)]
    assert max(abs(e - e0) for e in rows) / e0 <= 1e-10


def test_viewer_shows_the_flight_phase(capsys, tmp_path):
    out = tmp_path / "run.html"
    assert main(["limit-cycle", "slip-biped-runner", "--animate", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["stable"]
    page = out.read_text()
    scene = json.loads(re.search(r'id="amble-scene">(.*?)</script>', page, re.S).group(1))
    assert '"between":["foot","mass"]' in page and '"between":["mass","swing_foot"]' in page
    up = [np.asarray(scene["points"][n], float).reshape(-1, 3)[:, 2] for n in ("foot", "swing_foot")]
    steps = np.asarray(scene["labels"]["step"])
    on = [np.abs(h) <= 1e-6 for h in up]
    # never both feet on the ground (running, not walking); in every whole step frames with both
    # feet in the air (flight) and frames with one foot on the ground (stance)
    assert not np.any(on[0] & on[1])
    assert min(float(np.min(h)) for h in up) >= -1e-6
    whole = np.unique(steps)[:-1]
    assert len(whole) >= 5
    for k in whole:
        this = steps == k
        flight = this & ~on[0] & ~on[1] & (up[0] > 0.01) & (up[1] > 0.01)
        stance = this & (on[0] ^ on[1])
        assert flight.sum() >= 10 and stance.sum() >= 5
    # a flight phase is most of the step: 0.469 s of 0.647 s
    o = _oracle()
    y = o.fixed_point(1.18)
    ref = o.stride(y)
    assert abs((ref["t_td"] + ref["t_apex"] - ref["t_lo"]) / ref["t_apex"] - 0.725) < 0.01


def test_closed_loop_recovers_where_the_fixed_leg_drifts_away(gait):
    o, y, _ = gait
    # retracting: from apexes 8 cm below and 12 cm above the gait's, back to it within 8 steps,
    # apex by apex as the SciPy runner's map iterates
    for h in (1.10, 1.30):
        run = amble.simulate(build(), _apex(o, h, PARAMS["alpha"], PARAMS["omega"]), steps=8, rtol=1e-12,
                             atol=1e-12, samples=False)
        apexes = [e.x_post[1] for e in run.events if e.name == "apex"]
        ref = [h]
        for _ in range(8):
            ref.append(o.apex_map(ref[-1]))
        assert np.max(np.abs(np.array(apexes) - ref[1:])) <= 1e-9
        assert abs(apexes[-1] - y) <= 1e-8
    # the leg fixed at the gait's touchdown angle: 1 mm off the gait grows step by step
    fixed = o.fixed_angle(y)
    run = amble.simulate(build(), _apex(fixed, y + 1e-3, fixed.alpha, 0.0), steps=8, rtol=1e-12, atol=1e-12,
                         params={"alpha": fixed.alpha, "omega": 0.0}, samples=False)
    off = [e.x_post[1] - y for e in run.events if e.name == "apex"]
    assert all(b > a > 0 for a, b in zip(off, off[1:])) and off[-1] > 5e-3
