"""The generated right-hand side solves M q̈ = Γ − h: checked against LAPACK (numpy.linalg.solve)
on the kernel's own M, h, Γ, for the unrolled LDLᵀ (small systems) and the loop (large ones)."""

import numpy as np
import pytest
from chains import pendulum_chain

from amble import HybridSystem, Model
from amble.backend import ldl
from amble.backend.kernels import compiled
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
    k = compiled(system)
    _check(k, k.meta["nx"][0] // 2, np.random.default_rng(1))


def test_loop_solve_matches_lapack():
    n = ldl.UNROLL_MAX + 2  # past the unrolled size: amble_ldl_solve in amble_core.h
    m = pendulum_chain(n, f"solve_chain{n}")
    k = compiled(HybridSystem(m.name, m))
    assert "amble_ldl_solve(" in k.path.with_suffix(".c").read_text()
    _check(k, n, np.random.default_rng(2), states=5)


def test_unrolled_code_has_no_square_root():
    src = ldl.ldl_solve_code(4, "M", "f")
    assert "sqrt" not in src and "for" not in src


@pytest.mark.parametrize("n", [2, ldl.UNROLL_MAX + 1])
def test_singular_mass_matrix_is_refused(n):
    # a chain whose last two links have no inertia of their own: M is singular everywhere
    m = Model(f"singular{n}")
    qs = m.coordinates([f"q{i}" for i in range(n)])
    m.point("p", (sum(qs), 0), mass=1)
    k = compiled(HybridSystem(m.name, m))
    with pytest.raises(Exception, match="singular"):
        k.rhs(0, 0.0, np.zeros(2 * n), np.zeros(1))


def _compiled_solve(n: int, code: str, tmp_path):
    """A C function ``solve(M, f)`` with the statements of ``code``, compiled and loaded."""
    import ctypes
    import subprocess

    from amble.backend.cache import compiler

    src = tmp_path / "solve.c"
    src.write_text(f"#define AMBLE_ERR_SINGULAR_MASS 1\nint solve(double *M, double *f) {{\n{code}    return 0;\n}}\n")
    so = tmp_path / "solve.so"
    subprocess.run([*compiler().split(), "-O2", "-shared", "-fPIC", str(src), "-o", str(so)], check=True)
    lib = ctypes.CDLL(str(so))
    lib.solve.restype = ctypes.c_int
    dp = ctypes.POINTER(ctypes.c_double)

    def solve(M: np.ndarray, f: np.ndarray) -> tuple[int, np.ndarray]:
        M, f = np.ascontiguousarray(M, dtype=float).copy(), np.ascontiguousarray(f, dtype=float).copy()
        return lib.solve(M.ctypes.data_as(dp), f.ctypes.data_as(dp)), f

    return solve


def test_sparse_reordered_solve_matches_lapack(tmp_path):
    # humanoid-3d's pattern: two coordinates coupled to the first two only; the minimum-degree
    # order eliminates them first, and the products with structural zeros are not written
    n = 7
    nonzero = {(i, j) for i in range(n) for j in range(i)} - {(1, 0), (5, 2), (5, 3), (5, 4), (6, 2), (6, 3),
                                                             (6, 4), (6, 5)}
    order = ldl.ldl_order(n, nonzero)
    assert order[:2] == [5, 6]
    code = ldl.ldl_solve_code(n, "M", "f", order=order, nonzero=nonzero)
    assert code.count("*") < ldl.ldl_solve_code(n, "M", "f").count("*")
    solve = _compiled_solve(n, code, tmp_path)
    zeros = {(i, j) for i in range(n) for j in range(i)} - nonzero
    rng = np.random.default_rng(3)
    for _ in range(20):
        B = rng.normal(size=(n, n))
        A = B @ B.T + n * np.eye(n)
        for i, j in zeros:
            A[i, j] = A[j, i] = 0.0
        A += np.diag(np.abs(A).sum(axis=1))  # diagonally dominant: still positive definite
        f = rng.normal(size=n)
        err, x = solve(np.tril(A), f)  # only the lower triangle is read
        assert err == 0
        assert np.allclose(x, np.linalg.solve(A, f), rtol=1e-12, atol=1e-12)
    A = np.eye(n)
    A[6, 6] = 0.0  # a zero pivot is refused
    assert solve(A, np.ones(n))[0] != 0
