"""The bifurcation curves of a two-parameter stability map: fold, flip and torus crossings between
neighbouring cells of one branch, read from the cells' multipliers.

Truth: the compass gait's period doubling from the independent SciPy oracle (tests/oracles/
compass_gait.py: its own fixed point and det(J + I) at each cell's parameters, and the published
first doubling at 4.391° for the default hip mass, docs/references.md); the kicked, damped
oscillator's Neimark–Sacker curve in closed form, c* = ln(e) / T (tests/analysis/test_torus.py);
its neutral saddle (κ < 0), where ψ_torus changes sign but no pair crosses the circle; and a map
whose branch changes between two cells, whose sign change is no bifurcation."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from test_torus import _oscillator

import amble
from amble import sweep
from amble.analysis.branch_bifurcations import multiplier_tests
from amble.analysis.map_bifurcations import branch_boundaries, crossed_kinds, map_crossings
from amble.cli.main import main
from amble.errors import StateError

SYNC = {"scheduler": "synchronous", "progress": False}
FLIP_DEG = 4.391  # the compass gait's first period doubling at mh = 10 kg (docs/references.md)
SLOPES_DEG = np.linspace(4.2, 4.6, 5)
HIP = [9.0, 10.0, 11.0]


@pytest.fixture(scope="module")
def oscillator():
    return _oscillator()


@pytest.fixture(scope="module")
def compass_map(compass):
    return sweep(compass, "fixed-point", {"mh": HIP, "slope": np.radians(SLOPES_DEG)}, **SYNC)


def _oracle_flip_sign(mh: float, slope_deg: float) -> float:
    """The sign of det(J + I) of the oracle's own period-1 gait at (mh, slope)."""
    from oracles.compass_gait import DEFAULT, fixed_point

    par = (DEFAULT[0], mh, *DEFAULT[2:])
    _, jac = fixed_point(math.radians(slope_deg), par=par)
    return float(np.sign(np.linalg.det(jac + np.eye(3))))


def test_compass_gait_map_flip_curve_brackets_the_oracle(compass, compass_map):
    with_system = map_crossings(compass_map, compass)
    without = map_crossings(compass_map)
    assert [c[:7] for c in with_system] == [c[:7] for c in without]  # the heuristic agrees here
    assert {c.kind for c in with_system} == {"flip"}
    assert {c.link for c in with_system if c.i2 != c.i} == {"continued"}
    assert {c.link for c in without if c.i2 != c.i} == {"near"}
    known: dict[tuple[int, int], float] = {}
    for i, mh in enumerate(HIP):
        (c,) = [c for c in with_system if c.i == c.i2 == i]  # one flip along the slope in each row
        lo, hi = SLOPES_DEG[c.j], SLOPES_DEG[c.j2]
        assert c.b_mid == pytest.approx(math.radians(0.5 * (lo + hi)))
        if mh == 10.0:  # the published value
            assert lo < FLIP_DEG < hi
            known.update({(i, j): 1.0 if s < FLIP_DEG else -1.0 for j, s in enumerate(SLOPES_DEG)})
        else:  # the oracle's own gait changes the sign of det(J + I) between the two cells
            known[i, c.j], known[i, c.j2] = _oracle_flip_sign(mh, lo), _oracle_flip_sign(mh, hi)
            assert known[i, c.j] > 0 > known[i, c.j2]
    # across the hip mass: a crossing where the oracle's sign changes between two known cells, none where not
    pairs = {(c.i, c.j) for c in with_system if c.i2 == c.i + 1}
    checked = 0
    for (i, j), s in known.items():
        if (i + 1, j) in known:
            assert ((i, j) in pairs) == (s != known[i + 1, j]), (i, j)
            checked += 1
    assert checked >= 1 and pairs


def test_torus_curve_of_the_kicked_oscillator_is_the_closed_form(oscillator):
    """c* = ln(e)/T: every crossing is a torus crossing between two cells on either side of the
    closed-form curve, and every such pair of neighbours has one (along c and along e)."""
    p = {"kappa": 1.0, "T": 1.0}
    es, cs = [1.1, 1.2, 1.3], np.linspace(0.0, 0.4, 9)
    res = sweep(oscillator, "fixed-point", {"e": es, "c": cs}, params=p, **SYNC)
    found = map_crossings(res, oscillator, params=p)
    assert {c.kind for c in found} == {"torus"}
    assert [c[:7] for c in map_crossings(res)] == [c[:7] for c in found]

    def side(i: int, j: int) -> bool:
        return cs[j] > math.log(es[i]) / p["T"]

    expected = {(i, j, i2, j2) for i in range(3) for j in range(9) for i2, j2 in ((i + 1, j), (i, j + 1))
                if i2 < 3 and j2 < 9 and side(i, j) != side(i2, j2)}
    assert {c[:4] for c in found} == expected
    assert any(c.i2 == c.i + 1 for c in found) and any(c.j2 == c.j + 1 for c in found)


def test_a_neutral_saddle_draws_no_torus_curve(oscillator):
    p = {"kappa": -1.0, "T": 1.0}
    res = sweep(oscillator, "fixed-point", {"e": [1.1, 1.3], "c": np.linspace(0.0, 0.4, 5)}, params=p, **SYNC)
    tests = [multiplier_tests([complex(*m) for m in json.loads(r["multipliers"])])[2] for r in res.rows]
    assert min(tests) < 0 < max(tests)  # ψ_torus changes sign: the product of the real pair crosses 1
    assert map_crossings(res, oscillator, params=p) == [] and map_crossings(res) == []


def _row(i: int, j: int, mu: list[complex], x: float, branch: int, broke: str = "") -> dict[str, str]:
    return {"i": str(i), "j": str(j), "a": str(float(i)), "b": str(float(j)), "status": "ok",
            "multipliers": json.dumps([[m.real, m.imag] for m in map(complex, mu)]),
            "x_q": str(x), "x_qd": "0.5", "branch": str(branch), "branch_break": broke,
            "seeded": "false" if broke else "true", "max_modulus": str(max(abs(complex(m)) for m in mu))}


def _map(rows: list[dict[str, str]]) -> SimpleNamespace:
    return SimpleNamespace(kind="fixed-point-map", params=["a", "b"], rows=rows, state_names=["q", "qd"])


def test_a_branch_change_is_no_bifurcation():
    """Row 0 changes gait between b = 1 and 2 (a new branch with another multiplier past −1):
    ψ_flip changes sign there but no crossing is reported, and the boundary is a branch boundary.
    The same multipliers on one branch are a flip crossing."""
    stable, doubled = [0.5, -0.8], [0.5, -1.3]
    assert crossed_kinds(np.array(stable, complex), np.array(doubled, complex)) == ["flip"]
    changed = _map([_row(0, 0, stable, 0.1, 0), _row(0, 1, stable, 0.1, 0),
                    _row(0, 2, doubled, 0.9, 2, "ConvergenceError: the branch folds")])
    assert map_crossings(changed) == []
    assert branch_boundaries(changed) == [(0, 1, 0, 2)]
    kept = _map([_row(0, 0, stable, 0.1, 0), _row(0, 1, stable, 0.1, 0), _row(0, 2, doubled, 0.12, 0)])
    (c,) = map_crossings(kept)
    assert (c.i, c.j, c.i2, c.j2, c.kind, c.b_mid, c.link) == (0, 1, 0, 2, "flip", 1.5, "branch")
    assert branch_boundaries(kept) == []
    # across rows (each its own task and ids): far gaits are another branch, near ones one
    rows = [_row(0, 0, stable, 0.1, 0), _row(1, 0, doubled, 0.9, 1)]
    assert map_crossings(_map(rows)) == []
    rows[1] = _row(1, 0, doubled, 0.11, 1)
    assert [c.kind for c in map_crossings(_map(rows))] == ["flip"]
    with pytest.raises(StateError):
        map_crossings(SimpleNamespace(kind="fixed-point", params=["a"], rows=[]))


def test_map_plot_draws_the_curves_on_cell_boundaries(tmp_path, oscillator, saved_figures):
    from amble.viz.sweep_plots import plot_parameter_map

    p = {"kappa": 1.0, "T": 1.0}
    cs = np.linspace(0.0, 0.4, 5)
    res = sweep(oscillator, "fixed-point", {"e": [1.1, 1.3], "c": cs}, params=p, **SYNC)
    figs = saved_figures
    plot_parameter_map(res, tmp_path / "m.png", system=oscillator, params=p)
    plot_parameter_map(_map([_row(0, 0, [0.5, -0.8], 0.1, 0), _row(0, 1, [0.5, -1.3], 0.9, 1, "lost")]),
                       tmp_path / "b.png")
    ax = figs[0].axes[0]
    (tor,) = [c for c in ax.collections if c.get_gid() == "crossing_torus"]
    segs = [np.asarray(s) for s in tor.get_segments()]
    # ln 1.1 = 0.095 between c = 0 and 0.1, ln 1.3 = 0.262 between 0.2 and 0.3: vertical edges
    # at the midpoints, each one cell (Δe = 0.2) tall; between the rows at c = 0.1 and 0.2, horizontal
    # edges at e = 1.2, each one cell (Δc = 0.1) wide
    vertical = sorted((s[0, 0], s[0, 1], s[1, 1]) for s in segs if s[0, 0] == s[1, 0])
    horizontal = sorted((s[0, 1], s[0, 0], s[1, 0]) for s in segs if s[0, 1] == s[1, 1])
    np.testing.assert_allclose(vertical, [(0.05, 1.0, 1.2), (0.25, 1.2, 1.4)], atol=1e-12)
    np.testing.assert_allclose(horizontal, [(1.2, 0.05, 0.15), (1.2, 0.15, 0.25)], atol=1e-12)
    assert "torus (Neimark–Sacker, complex |μ| = 1)" in ax.get_legend_handles_labels()[1]
    b = figs[1].axes[0]
    assert [c.get_gid() for c in b.collections if c.get_gid() in ("branch_boundary", "crossing_flip")] == \
        ["branch_boundary"]


def test_cli_reports_the_map_curves(capsys):
    rc = main(["sweep", "compass-gait", "--param", "mh=9:11:3", "--param", "slope=0.0733:0.0803:5",
               "--scheduler", "synchronous", "--json"])
    assert rc == 0
    crossings = json.loads(capsys.readouterr().out)["crossings"]
    assert crossings and {c["kind"] for c in crossings} == {"flip"}
    (mid,) = [c for c in crossings if c["i"] == c["i2"] == 1]  # mh = 10: bracketing 4.391°
    assert mid["b_mid"] - 0.00175 / 2 < math.radians(FLIP_DEG) < mid["b_mid"] + 0.00175 / 2
    rc = main(["sweep", "compass-gait", "--param", "mh=9:11:3", "--param", "slope=0.0733:0.0803:5",
               "--scheduler", "synchronous"])
    assert rc == 0 and "bifurcation curves: flip between" in capsys.readouterr().out
    assert amble.map_crossings is map_crossings
