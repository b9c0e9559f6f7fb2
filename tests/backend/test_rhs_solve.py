"""The generated right-hand side solves M q̈ = Γ − h: checked against LAPACK (numpy.linalg.solve)
on the kernel's own M, h, Γ, for the unrolled LDLᵀ (small systems) and the loop (large ones)."""

import numpy as np
import pytest
from chains import pendulum_chain

from amble import HybridSystem, Model
from amble.backend import codegen
from amble.backend.kernels import build
from amble.models import load


def _check(k, n: int, rng: np.random.Generator, states: int = 20) -> None:
    p = np.array(k.meta["param_defaults"], dtype=float)
    for _ in range(states):
        x = np.concatenate([rng.uniform(-1.5, 1.5, n), rng.uniform(-2, 2, n)])
        M, h, G = k.dynamics(0, 0.0, x, p)
        assert np.allclose(M, M.T, rtol=0, atol=0)  # both triangles filled from one
        qdd = np.linalg.solve(M, G - h)
        dx = k.rhs(0, 0.0, x, p)
        assert np.array_equal(dx[:n], x[n:])
        assert np.allclose(dx[n:], qdd, rtol=1e-11, atol=1e-11 * np.max(np.abs(qdd)))


@pytest.mark.parametrize("model", ["compass-gait", "kneed-biped"])
def test_unrolled_solve_matches_lapack(model):
    system = load(model)
    k = build(system)
    _check(k, k.meta["nx"][0] // 2, np.random.default_rng(1))


def test_loop_solve_matches_lapack():
    n = codegen.UNROLL_MAX + 2  # past the unrolled size: amble_ldl_solve in amble_core.h
    m = pendulum_chain(n, f"solve_chain{n}")
    k = build(HybridSystem(m.name, m))
    assert "amble_ldl_solve(" in k.path.with_suffix(".c").read_text()
    _check(k, n, np.random.default_rng(2), states=5)


def test_unrolled_code_has_no_square_root():
    src = codegen.ldl_solve_code(4, "M", "f")
    assert "sqrt" not in src and "for" not in src


@pytest.mark.parametrize("n", [2, codegen.UNROLL_MAX + 1])
def test_singular_mass_matrix_is_refused(n):
    # a chain whose last two links have no inertia of their own: M is singular everywhere
    m = Model(f"singular{n}")
    qs = m.coordinates([f"q{i}" for i in range(n)])
    m.point("p", (sum(qs), 0), mass=1)
    k = build(HybridSystem(m.name, m))
    with pytest.raises(Exception, match="singular"):
        k.rhs(0, 0.0, np.zeros(2 * n), np.zeros(1))
