"""What a warm start imports and does besides its work: nothing it does not need.

A warm ``amble limit-cycle compass-gait`` (the compiled model in the cache) must not import the
heavy libraries (SymPy, SciPy, Matplotlib, Dask), nor the modules only a build needs (OpenSSL's
hashlib, the compiler drivers, the runtime's builder, the derivation layer), nor those argparse
pulls in only to print help (shutil). Truth: a child process's ``sys.modules``, set against a
child that imports NumPy alone (the floor: whatever that imports is no cost of amble's). The
shortcuts keep their results: the built-in SHA-256 gives hashlib's digests, the help text is
argparse's own formatter's at any terminal width.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Modules a warm limit cycle must not import (unless importing NumPy alone already does).
NOT_ON_THE_WARM_PATH = (
    "sympy", "scipy", "matplotlib", "dask", "symengine",
    "_hashlib", "hashlib", "shutil", "subprocess", "tempfile", "pkgutil", "importlib.util",
    "amble.backend.runtime", "amble.backend.codegen", "amble.derivation", "amble.modelling.hybrid",
)

#: Python's start-up may already import some of them (a ``.pth`` file of the environment, e.g. one
#: that installs certificates imports ``tempfile``): the child forgets those first, so they count
#: only if the run imports them again.
_FORGET = ("hashlib", "shutil", "subprocess", "tempfile", "pkgutil")
_MODULES = ("import json, sys; [sys.modules.pop(m, None) for m in {forget!r}]; {run}"
            "print(json.dumps(sorted(sys.modules)), file=sys.stderr)")


def _modules(run: str, env: dict[str, str]) -> set[str]:
    code = _MODULES.format(forget=_FORGET, run=run)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return set(json.loads(r.stderr.strip().splitlines()[-1]))


def test_a_warm_limit_cycle_imports_nothing_heavy():
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "AMBLE_WARM_START": "1"}
    run = "from amble.cli import main; rc = main(['limit-cycle', 'compass-gait', '--json']); assert rc == 0; "
    _modules(run, env)  # primes the tests' cache and its index if they are cold
    warm = _modules(run, env)
    floor = _modules("import numpy; ", env)
    assert "amble.backend.compiled" in warm  # the warm path was taken (the compiled system)
    assert sorted(m for m in NOT_ON_THE_WARM_PATH if m in warm and m not in floor) == []


@pytest.mark.parametrize("data", [b"", b"abc", bytes(range(256)) * 1000])
def test_the_builtin_sha256_gives_hashlibs_digests(data):
    from amble.backend.digest import sha256

    h = sha256(data[:7])
    h.update(data[7:])
    assert h.hexdigest() == hashlib.sha256(data).hexdigest()
    if data == b"abc":  # FIPS 180-2, appendix B.1
        assert h.hexdigest() == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"


def test_the_cache_names_the_engine_sources_the_runtime_compiles():
    from amble.backend import cache, runtime

    assert cache.C_DIR == runtime.C_DIR and (cache.C_DIR / "runtime.c").is_file()


@pytest.mark.parametrize("columns", ["", "30", "80", "250"])
def test_the_help_is_argparses_own_at_any_width(monkeypatch, columns):
    from amble.cli.main import _HelpFormatter, build_parser

    monkeypatch.setenv("COLUMNS", columns)

    def helps(formatter: type) -> list[str]:
        p = build_parser()
        p.formatter_class = formatter
        subs = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
        for sp in subs.choices.values():
            sp.formatter_class = formatter
        return [p.format_help(), p.format_usage()] + [sp.format_help() for sp in subs.choices.values()]

    ours = helps(_HelpFormatter)
    assert ours == helps(argparse.RawDescriptionHelpFormatter)
    assert "--period" in "".join(ours)


def test_a_stamp_serves_the_digest_until_a_file_changes(tmp_path, monkeypatch):
    from amble.backend import stamps

    monkeypatch.setattr(stamps, "RACY_NS", 0)  # files written just now count as settled
    files = [tmp_path / "a.py", tmp_path / "b.c"]
    files[0].write_text("x = 1\n")
    files[1].write_text("int f;\n")
    calls = []

    def truth() -> str:  # the digest of the contents, computed afresh
        calls.append(1)
        return hashlib.sha256(b"".join(f.read_bytes() for f in files)).hexdigest()

    first = stamps.stamped_digest(tmp_path, "id", files, truth)
    assert first == truth() and len(calls) == 2
    assert stamps.stamped_digest(tmp_path, "id", files, truth) == first and len(calls) == 2  # from the stamp
    st = os.stat(files[0])
    files[0].write_text("x = 2\n")  # same size, and the old mtime put back: only ctime tells
    os.utime(files[0], ns=(st.st_atime_ns, st.st_mtime_ns))
    if os.stat(files[0]).st_ctime_ns == st.st_ctime_ns:
        pytest.skip("this file system's ctime did not move within the test")
    changed = stamps.stamped_digest(tmp_path, "id", files, truth)
    assert changed != first and changed == truth()
    assert stamps.stamped_digest(tmp_path, "other id", files, truth) == changed and len(calls) == 5


def test_a_file_changed_just_now_is_never_stamped(tmp_path):
    from amble.backend import stamps

    f = tmp_path / "fresh.py"
    f.write_text("y = 1\n")
    calls = []
    for _ in range(2):
        assert stamps.stamped_digest(tmp_path, "id", [f], lambda: calls.append(1) or "d") == "d"
    assert len(calls) == 2 and not list(tmp_path.glob("stamp-*.json"))


def test_the_warm_index_key_is_the_hash_of_the_sources(tmp_path, monkeypatch):
    from amble.backend import index
    from amble.models import source_files

    sources = source_files("compass-gait")
    path = index.entry_path("compass-gait", sources, tmp_path)
    assert path == tmp_path / f"index-{index.index_key('compass-gait', sources)}.json"
    assert index.entry_path("compass-gait", sources, tmp_path) == path  # again (from the stamp, if settled)
    monkeypatch.setenv("AMBLE_CFLAGS", "-O1")
    assert index.entry_path("compass-gait", sources, tmp_path) == tmp_path / (
        f"index-{index.index_key('compass-gait', sources)}.json") != path
