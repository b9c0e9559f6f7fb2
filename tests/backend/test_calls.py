"""Per-state kernel calls from Python: raw addresses handed to C, shapes checked first, batches.

The reference is the library's C entry points called through a ctypes handle of this test's own,
with typed pointers built per call (``ndarray.ctypes.data_as``) — the way the loader called them
before it handed raw addresses over. Results must agree bit for bit.
"""

import ctypes

import numpy as np
import pytest

from amble.backend.kernels import compiled
from amble.errors import ModelError, ParameterError, StateError

D = ctypes.POINTER(ctypes.c_double)


@pytest.fixture(scope="module")
def kp(compass):
    k = compiled(compass, derivatives=True)
    return k, np.array(k.meta["param_defaults"])


@pytest.fixture(scope="module")
def ref(kp):
    """The library's entry points through a handle of the test's own, with typed pointers."""
    k, _ = kp
    lib = ctypes.CDLL(str(k.path))
    for name, n in (("amble_rhs", 3), ("amble_guards", 3), ("amble_dynamics", 5), ("amble_rhs_jac", 4),
                    ("amble_rhs_jacp", 3), ("amble_surfaces_grad", 3), ("amble_reset_jac", 3)):
        getattr(lib, name).argtypes = [ctypes.c_int, ctypes.c_double] + [D] * n
    lib.amble_reset.argtypes = [ctypes.c_int, ctypes.c_double, D, D, D, ctypes.POINTER(ctypes.c_int)]
    return lib


def _p(a):
    return a.ctypes.data_as(D)


def _states(n=20, seed=3):
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (n, 4))


def test_single_calls_equal_the_typed_pointer_calls_bit_for_bit(kp, ref):
    k, p = kp
    nxm, sc, npar = k.nx_max, k.sc, len(p)
    for x in _states():
        t = float(x[0])
        dx = np.zeros(4)
        assert ref.amble_rhs(0, t, _p(x), _p(p), _p(dx)) == 0
        assert np.array_equal(k.rhs(0, t, x, p), dx)
        M, h, G = np.zeros((2, 2)), np.zeros(2), np.zeros(2)
        ref.amble_dynamics(0, t, _p(x), _p(p), _p(M), _p(h), _p(G))
        for a, b in zip(k.dynamics(0, t, x, p), (M, h, G)):
            assert np.array_equal(a, b)
        g = np.zeros(max(k.n_tr, 1))
        ref.amble_guards(0, t, _p(x), _p(p), _p(g))
        assert np.array_equal(k.guards(0, t, x, p), g[:2])
        J = np.zeros((4, sc))
        ref.amble_rhs_jac(0, t, _p(x), _p(p), _p(dx), _p(J))
        ref.amble_rhs_jacp(0, t, _p(x), _p(p), _p(J))
        f, Jx, Jp = k.rhs_jacobian(0, t, x, p)
        assert np.array_equal(f, dx) and np.array_equal(Jx, J[:, :4]) and np.array_equal(Jp, J[:, nxm:nxm + npar])
        S = np.zeros((max(k.n_tr, 1) + len(k.meta["switches"]), sc))
        ref.amble_surfaces_grad(0, t, _p(x), _p(p), _p(S))
        gx, gp = k.surface_gradients(0, t, x, p)
        assert np.array_equal(gx, S[:2, :4]) and np.array_equal(gp, S[:2, nxm:nxm + npar])
        post, target = np.zeros(nxm), ctypes.c_int(-1)
        assert ref.amble_reset(0, t, _p(x), _p(p), _p(post), ctypes.byref(target)) == 0
        mode, y = k.reset("heel_strike", t, x, p)
        assert mode == k.meta["modes"][target.value] and np.array_equal(y, post[:4])
        R = np.zeros((nxm, sc + 1))
        ref.amble_reset_jac(0, t, _p(x), _p(p), _p(R))
        Rx, Rp, Rt = k.reset_jacobian(0, t, x, p)
        assert np.array_equal(Rx, R[:4, :4]) and np.array_equal(Rp, R[:4, nxm:nxm + npar])
        assert np.array_equal(Rt, R[:4, sc])


def test_converted_inputs_give_the_same_bits(kp):
    k, p = kp
    x = _states(1)[0]
    want = k.rhs(0, 0.25, x, p)
    ro = x.copy()
    ro.flags.writeable = False
    strided = np.repeat(x, 2)[::2]  # not contiguous
    for given in (list(x), ro, strided, x[None, :], np.asfortranarray(x)):
        assert np.array_equal(k.rhs(0, 0.25, given, p), want)
    assert np.array_equal(k.rhs("compass-gait", np.float32(0.25), x, list(p)), want)
    assert np.array_equal(k.rhs(np.int64(0), 0.25, x, p.copy()), want)


def test_every_call_gives_the_same_bits_for_converted_states_and_names(kp):
    """Each per-state call on a state that takes the general way (read-only, strided, a list, a
    2-D row, another array of parameters) and on a mode or transition by name equals the call on
    a contiguous float64 state, bit for bit (every output array)."""
    k, p = kp
    mode, tr = k.meta["modes"][0], k.meta["transitions"][0]["name"]
    for x in _states(6, seed=11):
        ro = x.copy()
        ro.flags.writeable = False
        strided = np.repeat(x, 2)[::2]
        for call, key, name in ((k.rhs, 0, mode), (k.dynamics, 0, mode), (k.guards, 0, mode),
                                (k.rhs_jacobian, 0, mode), (k.surface_gradients, 0, mode),
                                (k.reset, 0, tr), (k.reset_jacobian, 0, tr)):
            want = call(key, 0.5, x, p)
            for got in (call(name, 0.5, x, p), call(key, np.float32(0.5), ro, p), call(key, 0.5, strided, p.copy()),
                        call(np.int64(key), 0.5, list(x), list(p)), call(key, 0.5, x[None, :], p)):
                as_tuple = (lambda r: r if isinstance(r, tuple) else (r,))  # noqa: E731
                for a, b in zip(as_tuple(got), as_tuple(want)):
                    assert (a == b) if isinstance(a, str) else (a.shape == b.shape and np.array_equal(a, b))


def test_every_call_returns_fresh_arrays(kp):
    k, p = kp
    x0, x1 = _states(2)
    a, b = k.rhs(0, 0.0, x0, p), k.rhs(0, 0.0, x1, p)
    assert not np.shares_memory(a, b) and not np.array_equal(a, b)
    a[:] = 0.0
    assert np.array_equal(k.rhs(0, 0.0, x1, p), b)
    M0, M1 = k.dynamics(0, 0.0, x0, p)[0], k.dynamics(0, 0.0, x1, p)[0]
    assert not np.shares_memory(M0, M1)


def test_the_same_parameter_array_edited_in_place_is_read_afresh(kp):
    k, p = kp
    q = p.copy()
    x = _states(1)[0]
    before = k.rhs(0, 0.0, x, q)
    q[list(k.meta["params"]).index("g")] *= 2.0  # gravity doubled: q̈ changes
    assert not np.array_equal(k.rhs(0, 0.0, x, q), before)
    assert np.array_equal(k.rhs(0, 0.0, x, q), k.rhs(0, 0.0, x, q.copy()))


def test_batched_calls_equal_the_calls_per_row(kp):
    k, p = kp
    X = _states(17)
    t = np.linspace(0.0, 1.0, len(X))
    P = np.tile(p, (len(X), 1))
    P[:, list(k.meta["params"]).index("g")] = np.linspace(5.0, 15.0, len(X))
    F = k.rhs_many(0, 0.5, X, p)
    Fp = k.rhs_many("compass-gait", t, X, P)
    M, h, G = k.dynamics_many(0, t, X, P)
    f, Jx, Jp = k.rhs_jacobian_many(0, t, X, P)
    for i, x in enumerate(X):
        assert np.array_equal(F[i], k.rhs(0, 0.5, x, p))
        assert np.array_equal(Fp[i], k.rhs(0, t[i], x, P[i]))
        for a, b in zip((M[i], h[i], G[i]), k.dynamics(0, t[i], x, P[i])):
            assert np.array_equal(a, b)
        for a, b in zip((f[i], Jx[i], Jp[i]), k.rhs_jacobian(0, t[i], x, P[i])):
            assert np.array_equal(a, b)
    assert k.rhs_many(0, 0.0, np.zeros((0, 4)), p).shape == (0, 4)


def test_wrong_shapes_and_types_raise_typed_errors_before_c(kp):
    k, p = kp
    x = np.zeros(4)
    for bad in (np.zeros(3), np.zeros(5), np.zeros((2, 4)), ["a", 1, 2, 3], None):
        with pytest.raises(StateError):
            k.rhs(0, 0.0, bad, p)
        with pytest.raises(StateError):
            k.rhs_jacobian(0, 0.0, bad, p)
        with pytest.raises(StateError):
            k.reset(0, 0.0, bad, p)
    for bad in (p[:-1], np.zeros(len(p) + 1), np.zeros(0), "g"):
        with pytest.raises(ParameterError):
            k.rhs(0, 0.0, x, bad)
        with pytest.raises(ParameterError):
            k.dynamics(0, 0.0, x, bad)
    for mode in (1, -1, "nope", 0.0, True):
        with pytest.raises(ModelError):
            k.rhs(mode, 0.0, x, p)
    for tr in (2, -1, "nope"):
        with pytest.raises(ModelError):
            k.reset_jacobian(tr, 0.0, x, p)
    with pytest.raises(StateError):
        k.rhs_many(0, 0.0, np.zeros((3, 5)), p)
    with pytest.raises(StateError):
        k.rhs_many(0, np.zeros(2), np.zeros((3, 4)), p)
    with pytest.raises(ParameterError):
        k.rhs_many(0, 0.0, np.zeros((3, 4)), np.zeros((2, len(p))))
    with pytest.raises(ParameterError):
        k.dynamics_many(0, 0.0, np.zeros((3, 4)), p[:-1])


def test_a_run_reads_read_only_parameters_and_refuses_strided_ones(compass):
    from amble.simulation import engine

    k = compiled(compass)
    p = np.array(k.meta["param_defaults"])
    x0 = np.array(compass.fixed_point_guess, dtype=float)
    want = engine.run(k, p, 0, x0, steps=1)
    ro = p.copy()
    ro.flags.writeable = False
    got = engine.run(k, ro, 0, x0, steps=1)
    assert got.status == want.status and np.array_equal(got.x, want.x) and got.t == want.t
    with pytest.raises(StateError):
        engine.run(k, np.repeat(p, 2)[::2], 0, x0, steps=1)


def test_a_state_is_read_at_its_data_field():
    """The per-state calls hand C a contiguous state through the data field of the array object
    (c_args._DATA): on CPython it is found, and it holds the address NumPy reports for any array."""
    import sys

    from amble.backend import c_args

    if sys.implementation.name != "cpython":
        assert c_args._STEP is None
        return
    assert c_args._DATA is not None and c_args._STEP == (8,)
    base = np.arange(40.0)
    for a in (base, base[3:9], base[::2], base.reshape(5, 8)[2], np.zeros(4), np.asfortranarray(base.reshape(5, 8))):
        assert c_args._DATA_AT(id(a) + c_args._DATA).value == a.ctypes.data
