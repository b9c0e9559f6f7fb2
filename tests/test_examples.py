"""Every script in examples/ and the tutorial notebook runs, and its results pass independent checks.

Each example runs in a temporary working directory (it writes its files there). Checks use facts
that do not come from the code under test: closed forms, geometry, the thesis' Eq. 17.
"""

from __future__ import annotations

import json
import math
import runpy
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def run_example(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    monkeypatch.chdir(tmp_path)
    return runpy.run_path(str(EXAMPLES / name), run_name="__main__")


def test_every_example_is_tested():
    tested = {"walk_compass_gait.py", "limit_cycle.py", "custom_model.py", "equations_latex.py", "tutorial.ipynb",
              "my_walker.py"}
    present = {p.name for p in EXAMPLES.iterdir() if p.suffix in (".py", ".ipynb")}
    assert present == tested


def test_walk_compass_gait(tmp_path, monkeypatch):
    ns = run_example("walk_compass_gait.py", tmp_path, monkeypatch)
    walk = ns["walk"]
    assert walk.status == "completed" and walk.steps == 10
    assert (tmp_path / "compass_walk.png").stat().st_size > 10_000
    html = (tmp_path / "compass_walk.html").read_text(encoding="utf-8")
    assert "amble.scene/1" in html and "<script" in html
    # Feet on the slope just after a footfall: stance + swing = 2·slope (the legs are symmetric about the normal).
    x = walk.final_post_impact_state
    assert x[0] + x[1] == pytest.approx(2 * 0.05, abs=1e-9)


def test_limit_cycle(tmp_path, monkeypatch, capsys):
    ns = run_example("limit_cycle.py", tmp_path, monkeypatch)
    out = capsys.readouterr().out
    assert out.count("stable") == 5 and "unstable" not in out
    cycle = ns["cycle"]  # the last slope, 0.07
    assert cycle.fixed_point[0] + cycle.fixed_point[1] == pytest.approx(2 * 0.07, abs=1e-9)
    # A period-1 gait of a planar walker has complex-conjugate or real multipliers: the set is closed
    # under conjugation.
    m = np.sort_complex(cycle.multipliers)
    assert np.allclose(np.sort_complex(m.conj()), m, atol=1e-9)


def test_custom_model_is_zeno_at_the_closed_form_time(tmp_path, monkeypatch):
    ns = run_example("custom_model.py", tmp_path, monkeypatch)
    run = ns["run"]
    assert run.status == "zeno"
    g, e, h = 9.81, 0.5, 1.0
    t_inf = math.sqrt(2 * h / g) * (1 + e) / (1 - e)  # sum of the geometric series of flight times
    assert run.events[-1].t == pytest.approx(t_inf, abs=1e-6)
    # bounce k happens at sqrt(2h/g)·(1 + 2e + ... + 2e^(k-1))
    t1 = math.sqrt(2 * h / g)
    assert run.events[1].t == pytest.approx(t1 * (1 + 2 * e), abs=1e-9)


def test_equations_latex_matches_thesis_eq17(tmp_path, monkeypatch):
    ns = run_example("equations_latex.py", tmp_path, monkeypatch)
    model, M = ns["model"], ns["M"]
    mh, m, a, b = (model.symbol(n) for n in ("mh", "m", "a", "b"))
    st, sw = model.q
    l = a + b
    # Thesis Eq. 17 (Goswami et al.) in this model's naming: b foot→leg mass, a leg mass→hip.
    expected = sp.Matrix([[(mh + m) * l**2 + m * b**2, -m * l * a * sp.cos(st - sw)],
                          [-m * l * a * sp.cos(st - sw), m * a**2]])
    assert sp.simplify(M - expected) == sp.zeros(2, 2)
    assert "\\begin{matrix}" in (tmp_path / "compass_gait_equations.tex").read_text(encoding="utf-8")


def _code_cells(path: Path) -> list[str]:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    return ["".join(c["source"]) for c in cells if c["cell_type"] == "code"]


def test_tutorial_notebook_code_runs(tmp_path, monkeypatch):
    """The notebook's code cells, in order, as one script (fast; no Jupyter kernel)."""
    path = EXAMPLES / "tutorial.ipynb"
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    for i, source in enumerate(_code_cells(path)):
        exec(compile(source, f"{path.name} cell {i + 1}", "exec"), ns)
    assert ns["cycle"].stable
    assert (tmp_path / "tutorial_walk.html").stat().st_size > 10_000


@pytest.mark.slow
def test_tutorial_notebook_executes_headless(tmp_path):
    """The notebook as a user runs it: a Jupyter kernel, every cell, no error output."""
    nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed")
    nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed")
    nb = nbformat.read(EXAMPLES / "tutorial.ipynb", as_version=4)
    nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.output_type == "error"]
    assert (tmp_path / "tutorial_walk.html").stat().st_size > 10_000


def test_my_walker_runs_as_a_script(tmp_path, monkeypatch, capsys):
    run_example("my_walker.py", tmp_path, monkeypatch)
    assert capsys.readouterr().out.startswith("completed: 10 steps")
