"""The SymPy → CasADi translation against SymPy's own numeric evaluation and finite differences."""

import numpy as np
import pytest
import sympy as sp

ca = pytest.importorskip("casadi")

from amble.backend.casadi_export import CasadiTranslator, step_functions  # noqa: E402
from amble.errors import ModelError  # noqa: E402


def test_translation_matches_sympy_values_and_shares_nodes():
    x, y = sp.symbols("x y", real=True)
    shared = sp.sin(x * y) + 1
    e = (shared**2 / (y**2 + 1) + sp.sqrt(sp.Abs(x)) - sp.atan2(y, x) + sp.exp(-x) * sp.cos(y) ** 3
         + sp.Piecewise((x**2, x > 0.5), (y, True)) + sp.Max(x, y) + shared ** -2)
    X, Y = ca.SX.sym("x"), ca.SX.sym("y")
    f = ca.Function("f", [X, Y], [CasadiTranslator({x: X, y: Y})(e)])
    ref = sp.lambdify((x, y), e, "math")
    for xv, yv in [(0.3, -1.2), (0.9, 0.4), (-2.0, 3.0)]:
        assert float(f(xv, yv)) == pytest.approx(ref(xv, yv), rel=1e-14, abs=1e-14)


def test_unknown_symbol_is_a_model_error():
    x, z = sp.symbols("x z", real=True)
    with pytest.raises(ModelError, match="z"):
        CasadiTranslator({x: ca.SX.sym("x")})(x + z)


def test_compass_gait_dynamics_and_exact_derivatives(compass):
    """The exported residual M a + h − Γ against the equations of motion evaluated by SymPy, and
    its CasADi Jacobian against central differences."""
    from amble import derive

    m = compass.modes["compass-gait"]
    eq = derive(m)
    fns = step_functions(compass)
    p = np.array([compass.parameters[k] for k in fns.param_names])
    rng = np.random.default_rng(3)
    q, qd, a = rng.normal(size=2), rng.normal(size=2), rng.normal(size=2)
    subs = {**dict(zip(m.q, q)), **dict(zip(m.qd, qd)), **{s: v for s, v in m.params.items()}}
    M = np.array(eq.M.subs(subs), float)
    h = np.array(eq.h.subs(subs), float).ravel()
    G = np.array(eq.Gamma.subs(subs), float).ravel()
    r = np.asarray(fns.dynamics(q, qd, a, np.zeros(0), 0.0, p)).ravel()
    assert np.allclose(r, M @ a + h - G, rtol=1e-13, atol=1e-12)
    Q = ca.SX.sym("q", 2)
    jac = ca.Function("j", [Q], [ca.jacobian(fns.dynamics(Q, qd, a, ca.DM(0, 1), 0.0, p), Q)])
    fd = np.column_stack([(np.asarray(fns.dynamics(q + e, qd, a, np.zeros(0), 0.0, p))
                           - np.asarray(fns.dynamics(q - e, qd, a, np.zeros(0), 0.0, p))).ravel() / 2e-6
                          for e in np.eye(2) * 1e-6])
    assert np.allclose(np.asarray(jac(q)), fd, rtol=1e-6, atol=1e-6)


def test_import_amble_does_not_import_casadi():
    import subprocess
    import sys

    code = "import amble, amble.cli.main, amble.analysis.poincare, sys; print('casadi' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "False", out.stderr
