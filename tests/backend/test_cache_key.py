"""The cache key covers the toolchain and the generating sources, not parameter defaults, and is
computed once per system object."""

import copy
import dataclasses
import os
import stat
import sys

import pytest

from amble.backend import cache, kernels
from amble.models import load


def test_key_changes_with_cflags(compass, monkeypatch):
    monkeypatch.setenv("AMBLE_CFLAGS", "-O2")
    a = kernels.structure_key(compass)
    monkeypatch.setenv("AMBLE_CFLAGS", "-O3")
    assert kernels.structure_key(compass) != a


def _fake_cc(path, version):
    path.write_text(f"#!{sys.executable}\nprint({version!r})\n")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return str(path)


def test_key_changes_with_compiler_and_its_version(compass, monkeypatch, tmp_path):
    a = kernels.structure_key(compass)
    monkeypatch.setenv("CC", _fake_cc(tmp_path / "cc1", "fakecc 1.0"))
    b = kernels.structure_key(compass)
    assert b != a
    monkeypatch.setenv("CC", _fake_cc(tmp_path / "cc2", "fakecc 2.0"))
    assert cache.compiler_identity(os.environ["CC"]).strip() == "fakecc 2.0"
    assert kernels.structure_key(compass) not in (a, b)


def test_key_ignores_parameter_defaults():
    s1 = load("compass-gait")
    s2 = copy.deepcopy(s1)  # load() shares one system per process; change a copy
    model = next(iter(s2.modes.values()))
    sym = next(iter(model.params))
    model.params[sym] = model.params[sym] * 1.5 + 0.25
    assert s1.parameters != s2.parameters
    assert kernels.structure_key(s1) == kernels.structure_key(s2)
    k1, k2 = kernels.compiled(s1), kernels.compiled(s2)
    assert k1.path == k2.path
    assert k2.meta["param_defaults"] == [float(s2.parameters[p]) for p in k2.meta["params"]]


def test_key_covers_the_generating_sources():
    names = {str(f.relative_to(cache._PKG)) for f in cache.source_files()}
    for need in ("modelling/model.py", "modelling/hybrid.py", "modelling/walker.py", "modelling/contact/footfall.py",
                 "derivation/equations.py", "derivation/contact.py",
                 "derivation/impact.py", "backend/codegen.py", "backend/abi.py", "backend/cache.py",
                 "backend/_c/hybrid.c", "backend/_c/events.h", "backend/_c/dop853.h", "backend/_c/record.h"):
        assert need in names


def test_build_twice_computes_the_structure_once(monkeypatch):
    calls = []
    real = cache._structure_digest
    monkeypatch.setattr(cache, "_structure_digest", lambda s: calls.append(s) or real(s))
    s = copy.deepcopy(load("compass-gait"))  # a system object not built yet
    k1 = kernels.compiled(s)
    k2 = kernels.compiled(s)
    assert k1 is k2
    assert len(calls) == 1


def test_adding_a_transition_after_a_build_changes_the_key():
    s = copy.deepcopy(load("compass-gait"))
    a = kernels.structure_key(s)
    s.transitions.append(dataclasses.replace(s.transitions[0], name="again"))
    assert kernels.structure_key(s) != a


def test_cache_dir_order(monkeypatch, tmp_path):
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / "a"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert cache.cache_dir() == tmp_path / "a"
    monkeypatch.delenv("AMBLE_CACHE_DIR")
    assert cache.cache_dir() == tmp_path / "x" / "amble"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache.cache_dir() == tmp_path / "home" / ".cache" / "amble"


def test_missing_compiler_is_reported(compass, monkeypatch):
    from amble.errors import CompileError

    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.raises(CompileError, match="no C compiler"):
        kernels.structure_key(compass)
