"""The compile cache touches only what it wrote: a folder that is not a cache is refused and left
byte for byte as it was, a user's ``build-*`` directory inside a cache survives builds and clears,
flags that would compile away the checks of a non-finite state are undone, and a damaged, foreign,
unwritable or relative cache location heals or falls back to one private directory per user.

Truth: the directories' own listings and bytes before and after, the sign of a square root's
argument (a run through √ of a negative number must end ``integrator_failure``), and which
directories exist in the temporary directory after two runs."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from amble import HybridSystem, Model, simulate
from amble.backend import cache, cache_home, host, index, kernels
from amble.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
OLD = time.time() - 3 * cache.ORPHAN_AGE  # older than any build in progress


def _tree(d: Path) -> dict[str, bytes | None]:
    """Every path under ``d`` → its bytes (``None`` for a directory)."""
    return {str(p.relative_to(d)): (None if p.is_dir() else p.read_bytes()) for p in sorted(d.rglob("*"))}


def _user_folder(d: Path) -> Path:
    """A folder of a user's: a release build, notes, a file named like a cache record; all old."""
    d.mkdir(parents=True, exist_ok=True)
    d.chmod(0o700)
    (d / "build-release").mkdir()
    (d / "build-release" / "app.bin").write_bytes(b"\x7fELF user's program")
    (d / "build-notes").mkdir()
    (d / "build-notes" / "todo.txt").write_text("ship it\n")
    (d / ("a" * 24 + ".json")).write_text('{"my": "notes"}')
    (d / ".draft.tmp").write_text("half a thought")
    for p in d.rglob("*"):
        os.utime(p, (OLD, OLD))
    return d


def _pendulum(name: str) -> HybridSystem:
    m = Model(name)
    (th,) = m.coordinates("theta")
    m.point("bob", (sp.sin(th), -sp.cos(th)), mass=1.0)
    return HybridSystem(name, m)


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """A temporary directory of the test's own, where a fallback cache would go."""
    t = tmp_path / "tmp"
    t.mkdir(mode=0o700)
    monkeypatch.setenv("TMPDIR", str(t))
    monkeypatch.setattr("tempfile.tempdir", str(t))
    monkeypatch.setattr(cache_home, "_FALLBACK", {})
    return t


def test_a_folder_that_is_not_a_cache_is_never_cleaned(tmp_path, monkeypatch, private_tmp, capsys):
    """``AMBLE_CACHE_DIR=.`` in a project: a compile falls back with one warning, ``cache clear
    --all`` is refused in one line with exit 2; the folder stays byte-identical."""
    folder = _user_folder(tmp_path / "project")
    before = _tree(folder)
    monkeypatch.chdir(folder)
    monkeypatch.setenv("AMBLE_CACHE_DIR", ".")
    with pytest.warns(cache_home.CacheWarning, match="not an amble cache"):
        k = kernels.compiled(_pendulum("not-a-cache"))
    assert k.path.parent == private_tmp / f"amble-cache-{os.getuid()}"
    assert main(["cache", "clear", "--all"]) == 2
    err = capsys.readouterr().err.strip()
    assert "not usable" in err and "not an amble cache" in err and len(err.splitlines()) == 1
    assert _tree(folder) == before


def test_inside_a_cache_only_amble_s_own_leftovers_go(tmp_path, monkeypatch, private_tmp):
    """A tagged cache holding a user's ``build-release`` and a killed compile's build directory:
    a build removes the killed one only; ``cache clear --all`` keeps the user's files."""
    d = tmp_path / "cache"
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(d))
    kernels.compiled(_pendulum("inside-a-cache"))
    assert (d / cache_home.TAG).read_text().startswith("Signature: 8a477f597d28d172789f06886806bc55")
    (d / "build-release").mkdir()
    (d / "build-release" / "app.bin").write_bytes(b"user's")
    killed = d / "build-abcd1234"  # what a compile killed an hour ago left: its marker first
    killed.mkdir()
    (killed / cache_home.BUILD_MARKER).write_bytes(b"")
    (killed / "model.c").write_text("/* half written */")
    for p in (d / "build-release", d / "build-release" / "app.bin", killed):
        os.utime(p, (OLD, OLD))
    cache.rebuild(_pendulum("inside-a-cache-2"), "f" * 24)
    assert not killed.exists() and (d / "build-release" / "app.bin").read_bytes() == b"user's"
    assert main(["cache", "clear", "--all"]) == 0
    assert sorted(p.name for p in d.iterdir()) == ["CACHEDIR.TAG", "build-release"]


def test_an_earlier_cache_is_adopted_and_the_default_place_always(tmp_path, monkeypatch, private_tmp):
    """A cache an earlier version wrote (no tag, only amble's files) is adopted and keeps serving
    its libraries; ``$XDG_CACHE_HOME/amble`` is amble's whatever it holds, and a clear there still
    removes only amble's files."""
    d = tmp_path / "earlier"
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(d))
    s = _pendulum("earlier-cache")
    so = kernels.compiled(s).path
    (d / cache_home.TAG).unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("error", cache_home.CacheWarning)
        assert cache.cache_dir() == d and (d / cache_home.TAG).is_file()
    assert cache.cached(d, cache.structure_key(s))[0] == so

    monkeypatch.delenv("AMBLE_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    default = _user_folder(tmp_path / "xdg" / "amble")
    before = _tree(default)
    kernels.compiled(_pendulum("default-place"))
    assert main(["cache", "clear", "--all"]) == 0
    assert _tree(default) == {**before, cache_home.TAG: cache_home.TAG_TEXT.encode()}


@pytest.mark.parametrize("flags", ["-O3 -ffast-math", "-Ofast", "-O2 -ffinite-math-only",
                                   "-O2 -funsafe-math-optimizations"])
def test_flags_that_assume_finite_values_are_undone(tmp_path, monkeypatch, flags):
    """A run through √ of a negative number ends ``integrator_failure`` whatever ``AMBLE_CFLAGS``
    says (it once ran on with NaNs to the end time), with one warning naming the flag; and the
    library does not set flush-to-zero for the process as it loads."""
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("AMBLE_CFLAGS", flags)
    m = Model("sqrt-of-negative")
    (q,) = m.coordinates("q")
    m.point("p", (q, 0), mass=1.0)
    m.force([-sp.sqrt(q)])  # q falls through 0 at t ≈ 0.3 s from q = 1, q̇ = −3 m/s
    with pytest.warns(host.FlagsWarning, match=flags.split()[-1]):
        tr = simulate(HybridSystem("sqrt-of-negative", m), x0=[1.0, -3.0], t_end=5.0)
    assert tr.status == "integrator_failure" and tr.t[-1] < 1.0
    # loading the library left the process's floating point alone: subnormals are not flushed
    tiny = np.array([sys.float_info.min])
    assert float(tiny[0] / 2.0) > 0.0 and np.nextafter(0.0, 1.0) > 0.0
    assert host.ieee(["-O2"]) == (["-O2"], [])


def test_a_damaged_index_entry_is_rebuilt_not_fatal(tmp_path, monkeypatch):
    """An index entry whose bytes are not UTF-8 reads as unreadable (a warning), and the next
    record heals it."""
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("AMBLE_WARM_START", "1")
    s = _pendulum("damaged-index")
    kernels.compiled(s)
    path = index.record("damaged-index", [], s)
    path.write_bytes(b"\xff\xfe\x00 not utf-8 \x80")
    with pytest.warns(cache_home.CacheWarning, match="unreadable"):
        assert index.lookup("damaged-index", [], lambda: s) is None
    index.record("damaged-index", [], s)
    assert index.lookup("damaged-index", [], lambda: s) is not None


def test_a_kernel_file_system_falls_back(monkeypatch, private_tmp):
    """``/sys/kernel`` looks writable to root; it is refused with a reason, not an internal error."""
    if not Path("/sys/kernel").is_dir():
        pytest.skip("no /sys/kernel on this system")
    monkeypatch.setenv("AMBLE_CACHE_DIR", "/sys/kernel")
    with pytest.warns(cache_home.CacheWarning, match="/sys/kernel is not usable"):
        d = cache.cache_dir()
    assert d == private_tmp / f"amble-cache-{os.getuid()}"
    assert cache_home.configured()[1] is not None


def test_a_relative_cache_directory_is_made_absolute(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("AMBLE_CACHE_DIR", "rel-cache")
    k = kernels.compiled(_pendulum("relative-cache"))
    assert cache.cache_dir() == tmp_path / "rel-cache" and k.path.is_absolute()
    assert simulate(_pendulum("relative-cache"), x0=[0.3, 0.0], t_end=0.1).status == "end_time"


_RUN = """
import warnings
from amble import HybridSystem, Model, simulate
from amble.backend import cache
m = Model("fallback-twice")
(q,) = m.coordinates("q")
m.point("p", (q, 0), mass=1.0)
simulate(HybridSystem("fallback-twice", m), x0=[0.0, 1.0], t_end=0.1)
print(cache.cache_dir())
"""


@pytest.mark.parametrize("mine", ["free", "a link to elsewhere"])
def test_an_unusable_cache_leaks_no_directory_per_run(tmp_path, mine):
    """Two runs with an unusable cache: both use one private directory per user (the second
    compiles nothing); if that name is a link someone planted, each run uses a directory of its
    own and removes it when it exits, and the link's target is untouched."""
    t = tmp_path / "tmp"
    t.mkdir(mode=0o700)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    if mine != "free":
        (t / f"amble-cache-{os.getuid()}").symlink_to(elsewhere)
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    env = {**os.environ, "AMBLE_CACHE_DIR": str(shared), "TMPDIR": str(t), "PYTHONPATH": str(ROOT / "src")}
    runs = [subprocess.run([sys.executable, "-c", _RUN], env=env, capture_output=True, text=True, timeout=300)
            for _ in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr
    assert all("other users may write to it" in r.stderr for r in runs)
    used = [Path(r.stdout.strip()) for r in runs]
    left = sorted(p.name for p in t.iterdir())
    if mine == "free":
        assert used[0] == used[1] == t / f"amble-cache-{os.getuid()}"
        assert left == [f"amble-cache-{os.getuid()}"]
        assert len(list(used[0].glob("*.so"))) == 1  # the second run loaded the first run's library
    else:
        assert used[0] != used[1] and not any(p.exists() for p in used)
        assert left == [f"amble-cache-{os.getuid()}"] and list(elsewhere.iterdir()) == []
    assert list(shared.iterdir()) == []


def test_the_cache_reference_says_what_a_cache_is():
    doc = (ROOT / "docs" / "guide" / "performance.md").read_text()
    assert "CACHEDIR.TAG" in doc and "-ffast-math" in doc
