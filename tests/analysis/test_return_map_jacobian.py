"""The exact Jacobian of the return map, taken in one compiled run, against central differences of
the return map written out here (each column from two runs of the map, Richardson-extrapolated):
the differences know nothing of the variational equations, the saltation matrices or the
section's chart. Their error is O(h⁴) + tol/h, about 1e-7 with the map's tolerances of 1e-12.
"""

import numpy as np
import pytest

from amble.analysis import return_map
from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.analysis.section import Section, chart
from amble.backend.variational_codegen import OPTIMISE_LIMIT, _unoptimised
from amble.models import load

H = 1e-4


def _central(P, x, v, h=H):
    """d P(x + s v)/ds at s = 0, Richardson-extrapolated central differences."""
    d = [(P(x + c * h * v)[0] - P(x - c * h * v)[0]) / (2 * c * h) for c in (1.0, 0.5)]
    return (4 * d[1] - d[0]) / 3


@pytest.fixture(scope="module", params=["compass-gait", "kneed-biped"])
def gait(request):
    system = load(request.param)
    return system, find_fixed_point(system)


def test_section_jacobian_matches_central_differences_of_the_map(gait):
    system, lc = gait
    P = ReturnMap(system, lc.parameters)
    # off the fixed point too: the chart and the Jacobian are those of the image's section
    for x in (lc.fixed_point, P(lc.fixed_point + 1e-3 * np.abs(lc.fixed_point))[0]):
        A, S, E = P.section_jacobian(x)
        fd = np.array([_central(P, x, E[:, j])[S] for j in range(len(S))]).T
        assert np.max(np.abs(A - fd)) < 1e-6 * max(1.0, np.max(np.abs(A)))
        # E is the chart of chart(): the same tangent space, E[S] = I
        U = Section.of(P, x).tangent()
        assert np.allclose(E[S], np.eye(len(S)), atol=1e-12)
        assert np.max(np.abs(E - U @ np.linalg.solve(U[S], np.eye(len(S))))) < 1e-10
    mult = np.sort(np.abs(np.linalg.eigvals(P.section_jacobian(lc.fixed_point)[0])))
    assert np.allclose(mult, np.sort(np.abs(lc.multipliers)), atol=1e-9)


def test_full_state_derivative_matches_central_differences(gait):
    """Every row of ∂P/∂x, along the directions of the section (off it, the kneed biped's knee
    would strike at once: the map is not smooth there), and for the compass gait along every
    coordinate."""
    system, lc = gait
    P = ReturnMap(system, lc.parameters)
    x = lc.fixed_point
    D = P.derivatives(x)[2].dx_dx0
    _, S, E = P.section_jacobian(x)
    directions = np.eye(x.size) if system.name == "compass-gait" else E.T
    for v in directions:
        assert np.max(np.abs(D @ v - _central(P, x, v))) < 1e-6 * max(1.0, np.max(np.abs(D)))


def test_the_exact_jacobian_is_one_run(gait, monkeypatch):
    system, lc = gait
    P = ReturnMap(system, lc.parameters)
    calls = []
    real = return_map.run

    def counted(*a, **kw):
        calls.append(kw.get("sensitivities", False))
        return real(*a, **kw)

    monkeypatch.setattr(return_map, "run", counted)
    P.section_jacobian(lc.fixed_point)
    P.section_jacobian(lc.fixed_point)
    assert calls == ["state", "state"]  # one run each, without parameter columns


def test_parameters_are_computed_only_when_asked(gait):
    system, lc = gait
    P = ReturnMap(system, lc.parameters)
    x = lc.fixed_point
    n, npar = x.size, len(P.k.meta["params"])
    s = P.derivatives(x)[2]
    assert s.dx_dp.shape == (n, 0) and s.dt_dp.shape == (0,)
    full = P.derivatives(x, params=True)[2]
    assert full.dx_dp.shape == (n, npar) and full.dt_dp.shape == (npar,)
    assert np.array_equal(full.dx_dx0, s.dx_dx0)  # the state columns do not depend on carrying them
    # one parameter's column against differences of the map at moved parameters
    j = int(np.argmax(np.abs(full.dx_dp).sum(axis=0)))
    h = H * max(1.0, abs(P.p[j]))
    ends = []
    for c in (h, -h, h / 2, -h / 2):
        Q = ReturnMap(system, lc.parameters)
        Q.p = P.p.copy()
        Q.p[j] += c
        ends.append(Q(x)[0])
    d1, d2 = (ends[0] - ends[1]) / (2 * h), (ends[2] - ends[3]) / h
    assert np.max(np.abs(full.dx_dp[:, j] - (4 * d2 - d1) / 3)) < 1e-6 * max(1.0, np.max(np.abs(full.dx_dp[:, j])))


def test_kept_chart_coordinates_are_picked_again_where_they_chart_badly():
    system = load("compass-gait")
    lc = find_fixed_point(system)
    P = ReturnMap(system, lc.parameters)
    S, _ = P._chart(Section.of(P, lc.fixed_point))
    key = next(iter(P._charts))
    # coordinates kept from elsewhere that chart this section badly: the pivoting picks again
    worse = np.setdiff1d(np.arange(lc.fixed_point.size), S)[:1]
    bad = np.sort(np.r_[S[1:], worse])
    P._charts[key] = (bad, 1e-3)
    S2, E2 = P._chart(Section.of(P, lc.fixed_point))
    assert np.array_equal(S2, chart(Section.of(P, lc.fixed_point).tangent())[0])
    assert np.allclose(E2[S2], np.eye(len(S2)))


def test_only_long_derivative_kernels_are_compiled_unoptimised():
    short = "static void f(void) {}\n"
    assert _unoptimised(short) == short
    long = short + " " * OPTIMISE_LIMIT
    assert '#pragma GCC optimize ("O0")' in _unoptimised(long) and _unoptimised(long).count(long) == 1


@pytest.mark.parametrize("name", ["compass-gait", "simplest-walker", "rimless-wheel"])
def test_increments_are_the_chart_of_the_orthonormal_basis(name):
    """E without an SVD (compass gait, rimless wheel) and where the reset collapses directions of
    the guard surface (the simplest walker's massless swing leg): E of chart(tangent())."""
    system = load(name)
    lc = find_fixed_point(system)
    sec = Section.of(ReturnMap(system, lc.parameters), lc.fixed_point)
    S, E = chart(sec.tangent())
    assert np.max(np.abs(sec.increments(S) - E)) < 1e-12 * max(1.0, np.max(np.abs(E)))
