"""The model-independent runtime is compiled once per capacity and toolchain and linked into every
model's library: one object shared by different models, rebuilt when damaged, keyed by the flags,
and sized by buckets that serve models longer than the smallest."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest
from chains import pendulum_chain

import amble
from amble import Guard, HybridSystem
from amble.backend import cache, kernels, runtime
from amble.backend.kernels import Kernels
from amble.models import load


def _objects(d):
    return sorted(p.name for p in d.glob("runtime-*.o"))


def _fresh(system: HybridSystem, d, derivatives: bool = False) -> Kernels:
    """The system's library compiled now into ``d`` (not served by the in-process cache)."""
    key = cache.structure_key(system)
    so, meta = cache.rebuild(system, cache.derivatives_key(key) if derivatives else key, d, derivatives)
    return Kernels(so, meta)


def test_two_models_link_one_runtime_object(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    before = runtime.COMPILES
    walkers = [load("compass-gait"), load("kneed-biped")]
    libs = [_fresh(s, tmp_path) for s in walkers]
    assert runtime.COMPILES - before == 1  # the second model compiled its kernels only
    assert len(_objects(tmp_path)) == 1
    assert {k.nx_capacity for k in libs} == {runtime.MIN_CAPACITY}
    # a derivative library links the same object as the plain ones
    _fresh(walkers[0], tmp_path, derivatives=True)
    assert runtime.COMPILES - before == 1 and len(_objects(tmp_path)) == 1
    # each library is complete: it walks as the one the default cache builds
    for s, k in zip(walkers, libs):
        shared = amble.simulate(s, steps=2)
        assert shared.status == "completed"
        mi, x0 = 0, np.asarray(s.default_start[s.mode_names[0]], dtype=float)
        ref = kernels.compiled(s)
        assert np.array_equal(k.rhs(mi, 0.0, x0, np.asarray(ref.meta["param_defaults"])),
                              ref.rhs(mi, 0.0, x0, np.asarray(ref.meta["param_defaults"])))


def test_a_damaged_runtime_object_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    s = load("compass-gait")
    _fresh(s, tmp_path)
    (obj,) = (tmp_path / n for n in _objects(tmp_path))
    good = obj.read_bytes()
    obj.write_bytes(good[: len(good) // 2])  # truncated, as by a full disk or a killed copy
    assert runtime.cached_object(tmp_path, runtime.MIN_CAPACITY, cache.runtime_toolchain()) is None
    before = runtime.COMPILES
    k = _fresh(s, tmp_path)
    assert runtime.COMPILES - before == 1
    again = runtime.cached_object(tmp_path, runtime.MIN_CAPACITY, cache.runtime_toolchain())
    assert again is not None and again.read_bytes() != good[: len(good) // 2]
    assert k.n_modes == 1 and k.nx_max == 4


def test_other_flags_make_another_runtime_object(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    s = load("compass-gait")
    _fresh(s, tmp_path)
    first = _objects(tmp_path)
    monkeypatch.setenv("AMBLE_CFLAGS", "-O1")
    assert runtime.cached_object(tmp_path, runtime.MIN_CAPACITY, cache.runtime_toolchain()) is None
    _fresh(s, tmp_path)
    second = _objects(tmp_path)
    assert len(second) == 2 and set(first) < set(second)
    meta = [json.loads(p.read_text()) for p in tmp_path.glob("runtime-*.json")]
    assert sorted(m["object"] for m in meta) == second


def test_processes_building_at_once_each_end_with_a_valid_object(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    out, errors = [], []

    def build() -> None:
        try:
            out.append(runtime.build(tmp_path, runtime.MIN_CAPACITY, cache.runtime_toolchain()))
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=build) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and len(out) == 2
    assert runtime.cached_object(tmp_path, runtime.MIN_CAPACITY, cache.runtime_toolchain()) in out
    assert not list(tmp_path.glob("build-*")) and not list(tmp_path.glob(".*.tmp"))


@pytest.mark.parametrize("nx, cap", [(1, 8), (4, 8), (8, 8), (9, 16), (16, 16), (60, 64), (66, 128)])
def test_capacity_buckets(nx, cap):
    assert runtime.capacity(nx) == cap


def test_a_model_longer_than_the_smallest_bucket(tmp_path, monkeypatch):
    """A 5-link chain (10 states: capacity 16) swinging from rest: its energy, an invariant the
    integrator does not know of, is conserved by both integrators of the shared runtime."""
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    m = pendulum_chain(5, "chain5-runtime")
    s = HybridSystem("chain5-runtime", m)
    s.terminal("late", "chain5-runtime", Guard(m.q[0] - 10.0), status="late")  # never reached
    x0 = [0.4, -0.3, 0.2, 0.5, -0.1] + [0.0] * 5
    for method, tol in (("dop853", 1e-7), ("radau", 1e-4)):
        tr = amble.simulate(s, x0, t_end=2.0, rtol=1e-10, atol=1e-10, method=method)
        assert tr.kernels.nx_capacity == 16 and tr.kernels.nx_max == 10
        e = tr.energy().sum(axis=1)
        assert tr.status == "end_time" and len(e) > 100
        assert np.max(np.abs(e - e[0])) < tol * max(1.0, abs(e[0]))
    assert [runtime.capacity_of(p.with_suffix(".c").read_text()) for p in tmp_path.glob("*.so")] == [16] * 2
