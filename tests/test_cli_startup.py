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

_MODULES = "import json, sys; {run}print(json.dumps(sorted(sys.modules)), file=sys.stderr)"


def _modules(run: str, env: dict[str, str]) -> set[str]:
    r = subprocess.run([sys.executable, "-c", _MODULES.format(run=run)], env=env, capture_output=True, text=True,
                       timeout=600)
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
