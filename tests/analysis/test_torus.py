"""Torus (Neimark–Sacker) bifurcations of a branch: located where a complex pair of multipliers
crosses the unit circle, with the pair's angle, beside folds and flips.

Truth: a kicked, damped linear oscillator timed by a clock, whose return map is known in closed
form. Between kicks the flow ``ẍ + c ẋ + κ x = 0`` runs for the time T (a clock coordinate τ
with τ̇ = 1 and the guard τ = T); the reset keeps x, scales the velocity by e and adds a kick k.
The section's map is ``(x, ẋ) ↦ diag(1, e) exp(B T) (x, ẋ) + (0, k)``, ``B = [[0, 1], [−κ, −c]]``,
so its multipliers are those of ``M = diag(1, e) exp(B T)``: det M = e·exp(−cT), and for κ > c²/4

    exp(B T) = exp(−cT/2) [cos(ω_d T) I + sin(ω_d T)/ω_d (B + c/2 I)],   ω_d = √(κ − c²/4).

The complex pair's modulus is √det M: it crosses 1 at c* = ln(e)/T, where cos θ* = tr M / 2.
For κ < 0 the multipliers are real (a saddle) and their product crosses 1 at the same c*: a
neutral saddle, no bifurcation. Negative truth: the compass gait's branch over slope has only a
flip (its complex pair stays inside the circle and turns real, Goswami et al. 1998)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg

import amble
from amble import HybridSystem, bifurcations, continue_branch, sweep
from amble.analysis.multipliers import crossing_functions, resonance, second_compound, torus_pair
from amble.cli.main import main
from amble.errors import StateError

SYNC = {"scheduler": "synchronous", "progress": False}

MODEL = '''
from amble import Explicit, Guard, HybridSystem, Model


def build():
    m = Model("kicked-oscillator")
    x, tau = m.coordinates(["x", "tau"])
    xd, taud = m.qd
    c, kappa, T, e, k = m.parameters(c=0.1, kappa=1.0, T=1.0, e=1.2, k=0.5)
    m.add_kinetic((xd**2 + taud**2) / 2)
    m.add_potential(kappa * x**2 / 2)
    m.force([-c * xd, 0])
    s = HybridSystem("kicked-oscillator", m)
    s.transition("tick", "kicked-oscillator", Guard(tau - T, 1), Explicit(q=[x, 0], qd=[e * xd + k, 1]),
                 step=True)
    s.fixed_point_guess = [0.0, 0.0, 0.0, 1.0]
    return s
'''


def _oscillator() -> HybridSystem:
    ns: dict = {}
    exec(MODEL, ns)
    return ns["build"]()


@pytest.fixture(scope="module")
def oscillator():
    return _oscillator()


def _closed_form(kappa: float, T: float, e: float) -> tuple[float, float]:
    """(c*, θ*): where the pair of M = diag(1, e) exp(B T) crosses |μ| = 1, and its angle there."""
    c = math.log(e) / T
    wd = math.sqrt(kappa - c * c / 4)
    cs, sn = math.cos(wd * T), math.sin(wd * T)
    trace = math.exp(-c * T / 2) * ((1 + e) * cs + (1 - e) * (c / 2) * sn / wd)
    return c, math.acos(trace / 2)


CASES = [dict(kappa=1.0, T=1.0, e=1.0),           # the undamped oscillator: c* = 0, θ* = ω T = 1
         dict(kappa=1.0, T=1.0, e=1.2),           # a restitution > 1 moves it to c* = ln 1.2
         dict(kappa=6.0, T=0.7, e=1.5),
         dict(kappa=(math.pi / 2) ** 2, T=1.0, e=1.0)]  # θ* = π/2: the 1:4 strong resonance


@pytest.mark.parametrize("p", CASES)
def test_continuation_locates_the_torus_point_of_the_closed_form(oscillator, p):
    cstar, theta = _closed_form(**p)
    # the closed form itself against SciPy's matrix exponential at c*
    M = np.diag([1.0, p["e"]]) @ scipy.linalg.expm(np.array([[0, 1], [-p["kappa"], -cstar]]) * p["T"])
    assert np.abs(np.linalg.eigvals(M)) == pytest.approx([1, 1], abs=1e-13)
    assert abs(np.angle(np.linalg.eigvals(M))).max() == pytest.approx(theta, abs=1e-12)
    br = continue_branch(oscillator, "c", cstar + 0.3, cstar - 0.2, params=p)
    (torus,) = br.tori()
    assert br.bifurcations == [torus]  # no fold, no flip
    assert torus.located
    assert abs(torus.value - cstar) <= 1e-8
    assert abs(torus.angle - theta) <= 1e-8
    assert torus.rotation == pytest.approx(theta / (2 * math.pi), abs=1e-9)
    assert np.abs(torus.point.multipliers) == pytest.approx([1, 1], abs=1e-8)
    # damping falls along the branch: the pair leaves the circle, the gait loses its stability
    assert torus.direction == "stable→unstable"
    assert torus.resonance == ("1:4" if abs(theta - math.pi / 2) < 1e-3 else None)
    # the gait there is the closed form's fixed point (I − M)⁻¹ (0, k)
    x = np.linalg.solve(np.eye(2) - M, M @ [0.0, 0.0] + [0.0, 0.5])
    assert torus.point.state[[0, 2]] == pytest.approx(x, abs=1e-8)


def test_a_fixed_point_sweep_reports_the_torus_point(oscillator):
    p = dict(kappa=1.0, T=1.0, e=1.2)
    cstar, theta = _closed_form(**p)
    res = sweep(oscillator, "fixed-point", {"c": np.linspace(0.0, 0.4, 9)}, params=p, **SYNC)
    (torus,) = bifurcations(res, oscillator, params=p)
    assert torus.kind == "torus" and torus.located
    assert abs(torus.value - cstar) <= 1e-8 and abs(torus.angle - theta) <= 1e-8
    assert torus.direction == "unstable→stable"  # in grid order: damping grows
    # without the system: the bracketing grid point nearer to it (0.2), not located
    (near,) = bifurcations(res)
    assert near.kind == "torus" and not near.located and near.value == pytest.approx(0.2)
    with pytest.raises(StateError):
        bifurcations(sweep(oscillator, "bifurcation", {"c": [0.3]}, params=p, steps=20, **SYNC))


def test_a_neutral_saddle_is_no_torus_point(oscillator):
    """κ < 0: two real multipliers with product e·exp(−cT) through 1 — ψ_torus changes sign, but
    no pair crosses the circle."""
    p = dict(kappa=-1.0, T=1.0, e=1.2)
    br = continue_branch(oscillator, "c", 0.4, 0.0, params=p)
    mu = [np.sort(pt.multipliers.real) for pt in (br.points[0], br.points[-1])]
    assert np.prod(mu[0]) < 1 < np.prod(mu[1]) and all(np.all(pt.multipliers.imag == 0) for pt in br.points)
    assert br.bifurcations == []


def test_compass_gait_branch_has_flips_only(compass):
    """Over slope up to past the first doubling (0.0766 rad) the compass gait's complex pair stays
    inside the circle and turns real: one flip, no torus point."""
    system = compass
    res = sweep(system, "fixed-point", {"slope": np.linspace(0.01, 0.078, 10)}, **SYNC)
    found = bifurcations(res, system)
    assert [b.kind for b in found] == ["flip"]
    assert np.min(np.abs(found[0].point.multipliers + 1)) < 1e-8
    complex_pairs = [r for r in res.rows if any(abs(im) > 0 for _, im in json.loads(r["multipliers"]))]
    assert complex_pairs  # the test function met a complex pair, inside the circle
    assert all(r["stable"] == "true" for r in complex_pairs)


def test_second_compound_eigenvalues_are_the_pair_products():
    """Theorem: the eigenvalues of the second compound matrix are μᵢμⱼ, i < j."""
    rng = np.random.default_rng(3)
    for d in (2, 3, 5):
        A = rng.normal(size=(d, d))
        mu = np.linalg.eigvals(A)
        products = [mu[i] * mu[j] for i in range(d) for j in range(i + 1, d)]
        got = np.linalg.eigvals(second_compound(A))
        assert np.sort_complex(got) == pytest.approx(np.sort_complex(np.array(products)), abs=1e-10)
        fold, flip, torus = crossing_functions(A)
        assert torus == pytest.approx(float(np.prod(np.array(products) - 1).real), rel=1e-9)
        assert fold == pytest.approx(float(np.prod(mu - 1).real), rel=1e-9)


def test_pair_and_resonance_names():
    r = np.exp(1j * 2 * math.pi / 3)
    assert torus_pair([r, np.conj(r), 0.3])[1] == pytest.approx(2 * math.pi / 3)
    assert resonance(2 * math.pi / 3) == "1:3" and resonance(math.pi / 2 + 5e-4) == "1:4"
    assert resonance(1.0) is None
    assert torus_pair([2.0, 0.5]) is None           # a neutral saddle
    assert torus_pair([-1.0, -1.0])[1] == math.pi   # the double −1: the 1:2 point
    assert resonance(torus_pair([1.0, 1.0])[1]) == "1:1"


def test_cli_reports_the_torus_point(tmp_path, capsys):
    model = tmp_path / "kicked.py"
    model.write_text(MODEL)
    cstar, theta = _closed_form(kappa=1.0, T=1.0, e=1.2)
    rc = main(["sweep", f"{model}:build", "--kind", "continuation", "--param", "c=0.4:0:20", "--json"])
    assert rc == 0
    (b,) = json.loads(capsys.readouterr().out)["bifurcations"]
    assert b["kind"] == "torus" and abs(b["c"] - cstar) <= 1e-8 and abs(b["angle"] - theta) <= 1e-8
    assert b["direction"] == "stable→unstable" and b["resonance"] is None
    rc = main(["sweep", f"{model}:build", "--kind", "fixed-point", "--param", "c=0:0.4:5",
               "--scheduler", "synchronous"])
    assert rc == 0
    out = capsys.readouterr().out
    (line,) = [ln for ln in out.splitlines() if ln.startswith("  torus")]
    assert "Neimark–Sacker" in line and f"c = {cstar:.12g}" in line and "unstable→stable" in line
    assert amble.bifurcations is bifurcations


@pytest.mark.slow
def test_humanoid_torso_damping_torus_point_against_scipy_oracle():
    """A walker with a genuine torus point: the 2D humanoid's torso PD loses its damping ``kv``
    and the complex pair of its gait leaves the circle near kv = 1.1656 N·m·s/rad. Truth: the same
    robot written out and integrated by SciPy (tests/oracles/humanoid_2d.py), its own fixed point
    (Newton on its map) and multipliers (central differences), and the kv where its pair's
    modulus is 1 (secant in kv)."""
    from oracles.humanoid_2d import PARAMS, jacobian, on_section, step

    from amble.models import load

    br = continue_branch(load("humanoid-2d"), "kv", 2.0, 0.5, max_delta=0.1)
    (torus,) = br.tori()
    assert torus.located and torus.direction == "stable→unstable" and torus.resonance is None
    idx = [0, 2, 3, 4, 6, 7]

    def pair(kv: float, x: np.ndarray) -> tuple[complex, np.ndarray]:
        p = dict(PARAMS, kv=kv)
        z = x[idx]
        for _ in range(6):  # Newton on the oracle's 6-D map z ↦ z
            r = step(on_section(z), p)[0][idx] - z
            if np.max(np.abs(r)) < 1e-11:
                break
            z = z - np.linalg.solve(jacobian(on_section(z), p) - np.eye(6), r)
        mu = np.linalg.eigvals(jacobian(on_section(z), p))
        top = max((m for m in mu if m.imag > 1e-6), key=abs)
        return top, on_section(z)

    x = torus.point.state
    k0, k1 = torus.value - 0.02, torus.value + 0.02
    (m0, _), (m1, x1) = pair(k0, x), pair(k1, x)
    assert abs(m0) > 1 > abs(m1)  # the oracle's pair crosses between them
    for _ in range(4):  # secant on |μ(kv)| − 1
        k2 = k1 - (abs(m1) - 1) * (k1 - k0) / (abs(m1) - abs(m0))
        m2, x1 = pair(k2, x1)
        k0, m0, k1, m1 = k1, m1, k2, m2
        if abs(k1 - k0) < 1e-7:
            break
    print(f"kv: amble {torus.value:.10f}, oracle {k1:.10f}; θ: amble {torus.angle:.10f}, "
          f"oracle {abs(np.angle(m1)):.10f}")
    assert abs(torus.value - k1) < 1e-5
    assert abs(torus.angle - abs(np.angle(m1))) < 1e-5
