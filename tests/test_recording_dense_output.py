"""The samples of a recorded run lie on the solution between integrator steps: DOP853's 7th-order
dense output, checked against SciPy's DOP853 at 1e-13 between events, for a model whose modes
have one state length (the integrator's loops of constant length) and one with two (rows of the
shorter mode padded with NaN). The dense output's sums are written out from the lists of the
tableau's non-zero terms in ``dop853_tableau.h``: those lists are SciPy's tableau, term for term."""

import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.integrate._ivp import dop853_coefficients as dc

import amble
from amble.backend.kernels import compiled
from amble.backend.runtime import C_DIR
from amble.models import load
from amble.simulation.simulate import parameter_vector

TOL = 1e-8


@pytest.mark.parametrize("name", ["compass-gait", "kneed-biped"])
def test_samples_between_events_are_the_solution(name):
    system = load(name)
    k = compiled(system)
    p = parameter_vector(k, None)
    tr = amble.simulate(system, steps=1, rtol=TOL, atol=TOL, sample_dt=0.002)
    x_start = tr.x[0][np.isfinite(tr.x[0])]
    starts = [(0.0, x_start, int(tr.mode[0]))] + [(e.t, e.x_post, k.meta["modes"].index(e.target)) for e in tr.events]
    ends = [e.t for e in tr.events] + [np.inf]
    checked = 0
    for (t0, x0, mode), t1 in zip(starts, ends):
        n = len(x0)
        rows = (tr.t > t0) & (tr.t < t1)
        if not rows.any():
            continue
        assert (tr.mode[rows] == mode).all()
        ts, xs = tr.t[rows], tr.x[rows]
        assert np.isnan(xs[:, n:]).all() and np.isfinite(xs[:, :n]).all()  # padded to the longest state
        ref = solve_ivp(lambda t, x, m=mode: k.rhs(m, t, x, p), (t0, ts[-1]), x0[:n], method="DOP853",
                        rtol=1e-13, atol=1e-13, t_eval=ts)
        # 7th order: within a few tolerances (a cubic through the step ends is 1e4 times further off)
        np.testing.assert_allclose(xs[:, :n], ref.y.T, rtol=0, atol=20 * TOL)
        checked += rows.sum()
    assert checked > 300  # most of a walking step, sampled every 2 ms across integrator steps of ~0.1 s


def _terms(header: str, name: str) -> list[tuple[int, list[float]]]:
    body = re.search(rf"^#define {name}\(T\) (.*)$", header, re.M)[1]
    return [(int(j), [float(c) for c in cs.split(",")]) for j, cs in re.findall(r"T\((\d+), ([^)]*)\)", body)]


def test_the_dense_output_terms_are_scipys_tableau():
    header = (C_DIR / "dop853_tableau.h").read_text()
    for st in range(dc.N_STAGES + 1, dc.N_STAGES_EXTENDED):  # the dense output's three extra stages
        got = _terms(header, f"DOP_A{st}_TERMS")
        assert [(j, c) for j, (c,) in got] == [(j, float(v)) for j, v in enumerate(dc.A[st]) if v != 0.0]
    got = _terms(header, "DOP_D_TERMS")
    want = [(j, [float(v) for v in dc.D[:, j]]) for j in range(dc.N_STAGES_EXTENDED) if dc.D[:, j].any()]
    assert got == want
    assert all(all(c != 0.0 for c in cs) for _, cs in got)  # no row has a zero where another has none
