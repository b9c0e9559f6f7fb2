"""Seeing and clearing the compile cache: what the listing says is what the builds wrote, a clear
removes what it says and nothing else, a build in progress is not disturbed, bad requests are
typed errors.

Truth: the files the builds returned and the directory's own listing and sizes (``os.scandir``),
the cache's own loaders (:func:`cache.cached`, :func:`runtime.cached_object`), and a pendulum's
closed form θ̈ = −(g/l)·sin θ from a library compiled again after a clear."""

from __future__ import annotations

import math
import os
import shutil
import time

import numpy as np
import pytest
from chains import pendulum_chain

from amble import Guard, HybridSystem
from amble.backend import cache, cache_admin, cache_clear, files, index, runtime
from amble.backend.cache_admin import CacheRequestError
from amble.backend.kernels import Kernels

HOUR, DAY = 3600.0, 86400.0


def _pendulum(name: str) -> HybridSystem:
    s = HybridSystem(name, pendulum_chain(1, name))
    (q,) = s.modes[name].q
    s.terminal("far", name, Guard(5 - q), status="far")
    return s


def _p(meta: dict, l0: float) -> np.ndarray:
    """The parameter vector in the library's order: unit mass, length ``l0`` (m), g = 9.81 m/s²."""
    return np.array([{"m0": 1.0, "l0": l0, "g": 9.81}[n] for n in meta["params"]])


def _listing(d) -> dict[str, int]:
    """Every file of the directory (and of a build directory in it) → its size."""
    out = {}
    for e in os.scandir(d):
        if e.is_dir(follow_symlinks=False):
            out.update({f"{e.name}/{f.name}": f.stat().st_size for f in os.scandir(e.path)})
        else:
            out[e.name] = e.stat(follow_symlinks=False).st_size
    return out


def _age(paths, seconds: float, atime: float | None = None) -> None:
    t = time.time() - seconds
    for p in paths:
        os.utime(p, (t if atime is None else time.time() - atime, t), follow_symlinks=False)


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """A cache with pendulum ``pend-a`` (plain and with derivatives), ``pend-b`` (plain), their
    index entries and the runtime object, all written by the real builds; and the keys."""
    d = tmp_path_factory.mktemp("cache-template")
    d.chmod(0o700)
    keys = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("AMBLE_CACHE_DIR", str(d))
        mp.setenv("AMBLE_WARM_START", "1")
        for name, derivatives in (("pend-a", False), ("pend-a", True), ("pend-b", False)):
            s = _pendulum(name)
            plain = cache.structure_key(s)
            key = cache.derivatives_key(plain) if derivatives else plain
            cache.rebuild(s, key, d, derivatives)
            keys[name, derivatives] = key
            assert index.record(name, [], s) is not None
    return d, keys


@pytest.fixture
def cache_copy(template, tmp_path, monkeypatch):
    d = tmp_path / "cache"
    shutil.copytree(template[0], d)  # times kept (copy2): ages as they were built
    d.chmod(0o700)
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(d))
    return d, template[1]


def _key_files(d, key):
    return {n for n in _listing(d) if n.startswith(key)}


def test_the_listing_is_what_the_builds_wrote(cache_copy):
    d, keys = cache_copy
    c = cache_admin.scan(d)
    assert cache_admin.directory() == d
    by_key = {e.key: e for e in c.models}
    assert set(by_key) == set(keys.values())
    sizes = _listing(d)
    for (name, derivatives), key in keys.items():
        e = by_key[key]
        assert (e.name, e.derivatives, e.specs) == (name, derivatives, (name,))
        assert {p.name for p in e.files} == _key_files(d, key) == {f"{key}.json", *(
            cache.cached(d, key)[0].with_suffix(s).name for s in (".so", ".c"))}
        assert e.bytes == sum(sizes[p.name] for p in e.files)
    (rt,) = c.runtimes
    assert rt.capacity == runtime.MIN_CAPACITY  # a 2-state model links the smallest bucket
    tc = cache.runtime_toolchain()
    assert runtime.cached_object(d, rt.capacity, tc).name in {p.name for p in rt.files}
    assert {e.name for e in c.index} == {"pend-a", "pend-b"}
    info = cache_admin.info()
    assert (info["models"], info["runtimes"], info["index_entries"], info["builds_in_progress"]) == (3, 1, 2, 0)
    assert info["bytes"] == sum(sizes.values()) and info["directory"] == str(d)
    assert info["compiler"]["command"] == cache.compiler() and info["cflags"] == cache.cflags()


def test_clearing_a_model_removes_its_libraries_and_index_entries_only(cache_copy):
    d, keys = cache_copy
    before = _listing(d)
    a = {n for key in (keys["pend-a", False], keys["pend-a", True]) for n in _key_files(d, key)}
    a_index = {e.files[0].name for e in cache_admin.scan(d).index if e.name == "pend-a"}
    r = cache_clear.clear(d, model="pend-a")
    after = _listing(d)
    assert set(before) - set(after) == a | a_index and len(a_index) == 1
    assert r.bytes_freed == sum(before[n] for n in a | a_index) and r.files_removed == len(a | a_index)
    assert r.kept == []
    assert cache.cached(d, keys["pend-a", False]) is None and cache.cached(d, keys["pend-b", False]) is not None
    # compiled again on next use, and right: θ̈ = −(g/l)·sin θ (g = 9.81, l = 1)
    s = _pendulum("pend-a")
    so, meta = cache.library(s, keys["pend-a", False])
    x = np.array([0.7, -0.3])
    assert np.allclose(Kernels(so, meta).rhs(0, 0.0, x, _p(meta, l0=1.0)), [-0.3, -9.81 * math.sin(0.7)],
                       rtol=1e-13, atol=0)


def test_older_than_goes_by_last_use(cache_copy):
    d, keys = cache_copy
    c = cache_admin.scan(d)
    old = [p for e in c.models if e.name == "pend-a" for p in e.files] + list(c.runtimes[0].files)
    _age(old, 10 * DAY)
    b_so = cache.cached(d, keys["pend-b", False])[0]
    _age([b_so], 10 * DAY, atime=1 * DAY)  # built long ago, loaded yesterday
    assert cache_clear.clear(d, older_than=20).removed == []
    plan = cache_clear.clear(d, older_than=5, dry_run=True)
    assert {(e.kind, e.name) for e in plan.removed} == {("model", "pend-a"), ("runtime", None), ("index", "pend-a")}
    r = cache_clear.clear(d, older_than=5)
    assert [e.to_json() for e in r.removed] == [e.to_json() for e in plan.removed]
    assert not list(d.glob("runtime-*")) and (d / f"{keys['pend-b', False]}.json").exists()  # not read: no use
    b_index = {e.key for e in cache_admin.scan(d).index}
    assert {e.key for e in cache_clear.clear(d, older_than=0.5).removed} == {keys["pend-b", False]} | b_index


def test_a_dry_run_removes_nothing(cache_copy):
    d, _ = cache_copy
    stat = {n: os.stat(d / n).st_mtime_ns for n in _listing(d)}
    plan = cache_clear.clear(d, everything=True, dry_run=True)
    assert {n: os.stat(d / n).st_mtime_ns for n in _listing(d)} == stat
    entries = {n: size for n, size in _listing(d).items() if n != "CACHEDIR.TAG"}  # the tag stays: still a cache
    assert plan.dry_run and plan.files_removed == len(entries) and plan.bytes_freed == sum(entries.values())
    done = cache_clear.clear(d, everything=True)
    assert (done.files_removed, done.bytes_freed) == (plan.files_removed, plan.bytes_freed)
    assert list(_listing(d)) == ["CACHEDIR.TAG"]


def test_a_build_in_progress_is_not_disturbed(cache_copy, monkeypatch):
    """A clear of everything while a model compiles (from inside its compile): the build directory
    and the runtime object it links are kept, and the build completes and loads."""
    d, keys = cache_copy
    _age([d / n for n in _listing(d)], HOUR)  # the others' entries: older than the build
    real, seen = cache.run_compilers, []

    def compile_during_a_clear(cmds, cc, **kw):
        seen.append(cache_clear.clear(d, everything=True))
        return real(cmds, cc, **kw)

    monkeypatch.setattr(cache, "run_compilers", compile_during_a_clear)
    s = _pendulum("pend-c")
    so, meta = cache.rebuild(s, cache.structure_key(s), d)  # links the runtime object: it must be there
    r = seen[0]
    kept = {p.name for p, _ in r.kept}
    assert any(n.startswith("build-") for n in kept) and any(n.startswith("runtime-") for n in kept)
    assert {e.key for e in r.removed if e.kind == "model"} == set(keys.values())
    x = np.array([-1.2, 0.4])
    assert np.allclose(Kernels(so, meta).rhs(0, 0.0, x, _p(meta, l0=2.0)), [0.4, -9.81 / 2 * math.sin(-1.2)],
                       rtol=1e-13, atol=0)


def test_a_half_written_file_marks_a_build_until_it_is_a_killed_ones(cache_copy, monkeypatch):
    d, keys = cache_copy
    _age([d / n for n in _listing(d)], HOUR)
    fresh_a = d / f"{keys['pend-a', False]}.json"
    _age([fresh_a], 0)  # rewritten by the build in progress
    def killed(*args):
        raise OSError("killed")

    with monkeypatch.context() as m:  # a write killed between writing and renaming
        m.setattr(os, "replace", killed)
        with pytest.raises(OSError, match="killed"):
            files.write_atomic(d / f"{keys['pend-b', False]}.json", b"{}")
    (tmp,) = d.glob(".*.tmp")
    r = cache_clear.clear(d, everything=True)
    kept = {p.name for p, _ in r.kept}
    assert {tmp.name, fresh_a.name} <= kept and any(n.startswith("runtime-") for n in kept)
    assert tmp.exists() and fresh_a.exists() and cache.cached(d, keys["pend-b", False]) is None
    _age([tmp], 2 * cache.ORPHAN_AGE)  # now a killed build's, as the cache's own rule says
    r = cache_clear.clear(d, everything=True)
    assert not tmp.exists() and not list(d.glob("runtime-*")) and tmp.name in {e.key for e in r.removed}


def test_a_library_not_yet_recorded_is_kept_while_young(cache_copy):
    d, keys = cache_copy
    so = cache.cached(d, keys["pend-b", False])[0]
    stray = d / f"{'f' * 24}-{'0' * 16}.so"  # renamed into place, its .json not yet written
    shutil.copy(so, stray)
    r = cache_clear.clear(d, older_than=0)
    assert stray.exists() and stray.name in {p.name for p, _ in r.kept}
    assert [e.recorded for e in cache_admin.scan(d).models] == [False]
    _age([stray], 2 * cache.ORPHAN_AGE)
    cache_clear.clear(d, older_than=0)
    assert not stray.exists()


@pytest.mark.parametrize("kw, said", [
    ({}, "exactly one"), ({"everything": True, "model": "pend-a"}, "exactly one"),
    ({"older_than": -1}, "at least 0"), ({"older_than": math.nan}, "at least 0"),
    ({"older_than": "3"}, "at least 0"), ({"model": "no-such-model"}, "no compiled model 'no-such-model'"),
])
def test_bad_requests_are_typed_errors(cache_copy, kw, said):
    d, _ = cache_copy
    before = _listing(d)
    with pytest.raises(CacheRequestError, match=said):
        cache_clear.clear(d, **kw)
    assert _listing(d) == before


def test_an_unusable_cache_is_said_not_used(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(shared))
    with pytest.raises(CacheRequestError, match="other users may write to it"):
        cache_clear.clear(everything=True)
    info = cache_admin.info()
    assert info["usable"] is False and info["models"] == 0 and "other users" in info["reason"]
