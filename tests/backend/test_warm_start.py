"""The warm start: a model's compiled library found from its source without SymPy
(:mod:`amble.backend.index`), and the compiled system that runs and analyses use in its place
(:mod:`amble.backend.compiled`).

Truth is independent of the code under test: the fall time of a point mass, ``√(2 z₀ / g)``;
the fixed point of the compass gait found through the symbolic model in this process; SymPy's
absence from a child process's ``sys.modules``."""

from __future__ import annotations

import json
import math
import os
import pickle
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from amble.backend.cache import CacheWarning
from amble.backend.compiled import CompiledSystem
from amble.cli.args import load_model

ROOT = Path(__file__).resolve().parents[2]

BALL = """
from amble import POSITIVE, Guard, HybridSystem, Model

def build():
    ball = Model("ball")
    x, z = ball.coordinates("x z", unit="m")
    mass = ball.parameter("mass", 1.0, unit="kg", domain=POSITIVE)
    g = ball.parameter("g", {g})
    ball.point("p", (x, z), mass=mass)
    ball.gravity({gravity})
    s = HybridSystem("falling-ball", ball, default_start={{"ball": [0.0, {z0}, 0.0, 0.0]}})
    s.terminal("floor", "ball", Guard(z))
    return s
"""


def _ball(path: Path, g: float = 9.81, z0: float = 2.0, gravity: str = "g") -> str:
    path.write_text(BALL.format(g=g, z0=z0, gravity=gravity), encoding="utf-8")
    return str(path)


def _fall_time(system) -> float:
    from amble import simulate

    tr = simulate(system, t_end=10.0)
    assert tr.status == "fell"
    return tr.events[-1].t


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory):
    """One cache for the module: the ball is compiled once (each test's file has its own entry)."""
    return tmp_path_factory.mktemp("cache")


@pytest.fixture()
def cache(shared_cache, monkeypatch):
    from amble.backend import kernels

    d = shared_cache
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(d))
    monkeypatch.setattr(kernels, "_LOADED", {})  # libraries loaded from other tests' caches are not in this one
    return d


def test_second_load_is_the_compiled_system_and_falls_as_the_closed_form(cache, tmp_path):
    spec = _ball(tmp_path / "ball.py")
    first = load_model(spec, compiled=True)
    assert not isinstance(first, CompiledSystem)  # nothing indexed yet: the model is built
    assert math.isclose(_fall_time(first), math.sqrt(2 * 2.0 / 9.81), rel_tol=1e-9)
    warm = load_model(spec, compiled=True)
    assert isinstance(warm, CompiledSystem)
    assert math.isclose(_fall_time(warm), math.sqrt(2 * 2.0 / 9.81), rel_tol=1e-9)
    assert warm.unit("z") == "m" and warm.state_names() == ["x", "z", "x_dot", "z_dot"]


def test_an_edited_model_file_is_built_again(cache, tmp_path):
    f = tmp_path / "ball.py"
    _fall_time(load_model(_ball(f), compiled=True))
    assert isinstance(load_model(str(f), compiled=True), CompiledSystem)
    # a new default: the same library, a new description (the old one would fall at g = 9.81)
    edited = load_model(_ball(f, g=4.0), compiled=True)
    assert not isinstance(edited, CompiledSystem)
    assert math.isclose(_fall_time(edited), math.sqrt(2 * 2.0 / 4.0), rel_tol=1e-9)
    warm = load_model(str(f), compiled=True)
    assert isinstance(warm, CompiledSystem)
    assert math.isclose(_fall_time(warm), math.sqrt(2 * 2.0 / 4.0), rel_tol=1e-9)
    # a new structure (gravity 2 g): a new library
    doubled = load_model(_ball(f, g=4.0, gravity="2 * g"), compiled=True)
    assert not isinstance(doubled, CompiledSystem)
    assert math.isclose(_fall_time(doubled), math.sqrt(2 * 2.0 / 8.0), rel_tol=1e-9)
    assert math.isclose(_fall_time(load_model(str(f), compiled=True)), math.sqrt(2 * 2.0 / 8.0), rel_tol=1e-9)


def test_a_module_the_model_file_imports_is_watched(cache, tmp_path):
    (tmp_path / "ball_height.py").write_text("Z0 = 2.0\n", encoding="utf-8")
    f = tmp_path / "ball.py"
    src = BALL.format(g=9.81, z0="ball_height.Z0", gravity="g")
    f.write_text(f"import sys\nsys.path.insert(0, {str(tmp_path)!r})\nimport ball_height\n{src}", encoding="utf-8")
    _fall_time(load_model(str(f), compiled=True))
    assert isinstance(load_model(str(f), compiled=True), CompiledSystem)
    (tmp_path / "ball_height.py").write_text("Z0 = 8.0\n", encoding="utf-8")
    sys.modules.pop("ball_height", None)
    again = load_model(str(f), compiled=True)
    assert not isinstance(again, CompiledSystem)
    assert math.isclose(_fall_time(again), math.sqrt(2 * 8.0 / 9.81), rel_tol=1e-9)


def test_a_corrupt_index_warns_and_builds_again(cache, tmp_path):
    spec = _ball(tmp_path / "ball.py")
    _fall_time(load_model(spec, compiled=True))
    from amble.backend.index import entry_path
    from amble.models import source_files

    entry = entry_path(spec, source_files(spec))
    assert entry.is_file()
    entry.write_text('{"format": 1, "spec": ', encoding="utf-8")
    with pytest.warns(CacheWarning, match="unreadable"):
        again = load_model(spec, compiled=True)
    assert not isinstance(again, CompiledSystem)
    json.loads(entry.read_text())  # rewritten
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isinstance(load_model(spec, compiled=True), CompiledSystem)


def test_a_missing_library_is_built_again(cache, tmp_path, monkeypatch):
    cache = tmp_path / "own-cache"  # its libraries are removed
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(cache))
    spec = _ball(tmp_path / "ball.py")
    _fall_time(load_model(spec, compiled=True))
    for so in cache.glob("*.so"):
        so.unlink()
    again = load_model(spec, compiled=True)
    assert not isinstance(again, CompiledSystem)
    assert math.isclose(_fall_time(again), math.sqrt(2 * 2.0 / 9.81), rel_tol=1e-9)


def test_the_compiled_system_travels_to_workers_and_answers_like_the_model(cache, tmp_path):
    spec = _ball(tmp_path / "ball.py")
    full = load_model(spec, compiled=True)
    _fall_time(full)
    warm = pickle.loads(pickle.dumps(load_model(spec, compiled=True)))
    assert isinstance(warm, CompiledSystem)
    assert math.isclose(_fall_time(warm), math.sqrt(2 * 2.0 / 9.81), rel_tol=1e-9)
    # a worker that cannot open the library (another machine) builds the model
    state = warm.__getstate__()
    elsewhere = pickle.loads(pickle.dumps(warm))
    elsewhere.__setstate__((state[0], {True: (tmp_path / "nowhere.so", {})}, state[2]))
    assert elsewhere.compiled_kernels() is None
    assert math.isclose(_fall_time(elsewhere), math.sqrt(2 * 2.0 / 9.81), rel_tol=1e-9)
    # what it does not hold it does not pretend to hold: the declared system is asked for by name
    for holder, name in ((warm, "slope"), (warm.modes["ball"], "masses"), (warm.transitions[0], "guard")):
        with pytest.raises(AttributeError, match=rf"compiled numbers only, not '{name}': its .symbolic\(\)"):
            getattr(holder, name)
    assert set(warm.symbolic().modes["ball"].masses) == set(full.symbolic().modes["ball"].masses) == {"p"}
    assert full.symbolic() is full
    with pytest.warns(DeprecationWarning, match=r"symbolic\(\)"):
        assert warm.full() is warm.symbolic()
    from amble import ParameterError, simulate

    for system in (full, warm):
        with pytest.raises(ParameterError, match=r"'mass' = -1 kg is outside its domain \(0, ∞\)"):
            simulate(system, params={"mass": -1.0})


def test_models_load_returns_independent_systems():
    from amble.backend.cache import structure_key
    from amble.models import load

    a, b = load("compass-gait"), load("compass-gait")
    key = structure_key(b)
    mode = next(iter(a.modes.values()))
    stance = mode.q[0]
    mode.actuator("u_hip", on=stance)
    a.transitions.pop()
    assert next(iter(b.modes.values())).inputs == [] and len(b.transitions) == 2
    assert next(iter(load("compass-gait").modes.values())).inputs == []
    assert structure_key(load("compass-gait")) == key != structure_key(a)


def test_warm_limit_cycle_imports_no_sympy():
    """The commands in a child, twice: the second child finds the compiled model in the index,
    imports neither SymPy nor SciPy, and prints the fixed point the symbolic model gives."""
    code = ("import json, sys; from amble.cli import main; "
            "rc = main(['limit-cycle', 'compass-gait', '--json']) or main(['simulate', 'compass-gait', '--steps', "
            "'3', '--json']); print(json.dumps([m for m in ('sympy', 'scipy', 'matplotlib', 'dask') "
            "if m in sys.modules]), file=sys.stderr); sys.exit(rc)")
    # the tests' own cache (tests/conftest.py): usually warm already, primed by the first run if not
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "AMBLE_WARM_START": "1"}
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
            for _ in range(2)]
    for r in runs:
        assert r.returncode == 0, r.stderr
    assert json.loads(runs[1].stderr.strip().splitlines()[-1]) == []
    from amble import simulate
    from amble.analysis.poincare import find_fixed_point
    from amble.models import load

    truth = find_fixed_point(load("compass-gait"))
    cycle, walk = (json.loads(line) for line in runs[1].stdout.splitlines())
    assert max(abs(u - v) for u, v in zip(cycle["fixed_point"], truth.fixed_point)) < 1e-9
    assert cycle["multiplier_moduli"] == pytest.approx([abs(m) for m in truth.multipliers], abs=1e-9)
    assert walk["final_post_impact_state"] == pytest.approx(
        simulate(load("compass-gait"), steps=3).final_post_impact_state.tolist(), abs=1e-12)


def test_a_parameter_outside_its_domain_is_refused_on_the_warm_path(capsys):
    from amble.cli.main import main

    assert main(["limit-cycle", "compass-gait"]) == 0  # primes the index
    capsys.readouterr()
    assert isinstance(load_model("compass-gait", compiled=True, derivatives=True), CompiledSystem)
    assert main(["limit-cycle", "compass-gait", "--set", "m=-1"]) == 2
    assert capsys.readouterr().err.strip() == "amble: error: parameter 'm' = -1 is outside its domain (0, ∞)"
