"""The compile cache heals and cannot be steered: damaged or planted entries are never loaded,
file names come from hashes, killed builds leave nothing for long, unusable directories fall back."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import warnings

import pytest

from amble import Guard, HybridSystem, Model
from amble.backend import cache, cache_home, kernels
from amble.errors import CompileError

_WALK = """
import amble
from amble.models import load
tr = amble.simulate(load("rimless-wheel"), steps=3)
print(tr.status)
"""


def _run(cache_dir):
    env = {**os.environ, "AMBLE_CACHE_DIR": str(cache_dir)}
    return subprocess.run([sys.executable, "-c", _WALK], capture_output=True, text=True, env=env, timeout=300)


def _pendulum(name: str) -> HybridSystem:
    m = Model(name)
    (th,) = m.coordinates("theta")
    m.point("bob", (th, 0), mass=1.0)
    s = HybridSystem(name, m)
    s.terminal("far", name, Guard(5 - th), status="far")
    return s


def test_a_truncated_or_garbage_library_is_rebuilt_not_loaded(tmp_path):
    first = _run(tmp_path)
    assert first.returncode == 0 and first.stdout.strip() == "completed"
    (so,) = tmp_path.glob("*.so")
    intact = so.read_bytes()
    so.write_bytes(intact[: len(intact) // 3])  # truncated: dlopen of it would crash the process
    again = _run(tmp_path)
    assert again.returncode == 0 and again.stdout.strip() == "completed", again.stderr
    assert so.read_bytes() == intact  # rebuilt in place (same content, same name)
    so.write_bytes(b"\x7fELF garbage")
    assert _run(tmp_path).stdout.strip() == "completed"


def test_metadata_that_does_not_match_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    s = _pendulum("meta-check")
    key = kernels.structure_key(s)
    so, meta = cache.library(s, key)
    (tmp_path / f"{key}.json").write_text(json.dumps({**meta, "library_sha256": "0" * 64}))
    assert cache.cached(tmp_path, key) is None  # the recorded hash must be the library's
    (tmp_path / f"{key}.json").write_text("{}")
    assert cache.cached(tmp_path, key) is None
    so2, meta2 = cache.library(s, key)
    assert cache.cached(tmp_path, key) == (so2, meta2)


def test_the_model_name_is_never_a_path(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / "cache"))
    s = _pendulum("../../outside-cache")
    k = kernels.compiled(s)
    assert k.path.parent == tmp_path / "cache"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache"]
    assert all("outside" not in p.name for p in (tmp_path / "cache").iterdir())


def test_builds_a_killed_compile_left_are_removed(tmp_path, monkeypatch):
    """A killed compile's build directory (marked amble's before anything was written into it)
    goes once it is old; a running one's stays, and so does a user's ``build-release``."""
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    assert cache.cache_dir() == tmp_path  # an empty directory: tagged a cache
    old, fresh, user = tmp_path / "build-old_1234", tmp_path / "build-fresh123", tmp_path / "build-release"
    for d in (old, fresh, user):
        d.mkdir()
        (d / "model.c").write_text("/* half written */")
    for d in (old, fresh):
        (d / cache_home.BUILD_MARKER).write_bytes(b"")
    past = time.time() - 2 * cache.ORPHAN_AGE
    for d in (old, user):
        os.utime(d, (past, past))
    s = _pendulum("orphans")
    cache.rebuild(s, kernels.structure_key(s))
    assert not old.exists() and fresh.exists()  # a build still running elsewhere is left alone
    assert (user / "model.c").read_text() == "/* half written */"


@pytest.mark.parametrize("why", ["world-writable", "a file"])
def test_an_unusable_cache_falls_back_to_a_private_one(tmp_path, monkeypatch, why):
    bad = tmp_path / "shared"
    if why == "a file":
        bad.write_text("not a directory")
    else:
        bad.mkdir()
        bad.chmod(0o777)
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(bad))
    monkeypatch.setattr(cache_home, "_FALLBACK", {})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = cache.cache_dir()
    assert d != bad and d.is_dir() and (d.stat().st_mode & 0o077) == 0
    assert any(issubclass(w.category, cache.CacheWarning) and str(bad) in str(w.message) for w in caught)


def test_a_new_cache_directory_is_private(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / "new"))
    assert (cache.cache_dir().stat().st_mode & 0o777) == 0o700


@pytest.mark.parametrize("cc, said", [("false", "exit 1"), ("true", "wrote no library")])
def test_compiler_failures_say_what_happened(tmp_path, monkeypatch, cc, said):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", cc)
    s = _pendulum(f"cc-{cc}")
    with pytest.raises(CompileError, match=said):
        cache.rebuild(s, kernels.structure_key(s))


def test_a_blank_cc_means_find_a_compiler(tmp_path, monkeypatch):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", "   ")  # was an IndexError
    s = _pendulum("cc-blank")
    so, _ = cache.rebuild(s, kernels.structure_key(s))
    assert so.is_file()
