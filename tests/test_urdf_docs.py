"""The Python blocks of docs/guide/urdf.md run, in order, from the repository root. A block whose
first line is ``# slow`` (the 12-DOF biped's step, a build of minutes on a loaded machine) runs
only in the slow test; ``tests/test_tree_impact.py`` covers the same path on a small biped."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _blocks() -> list[str]:
    text = (ROOT / "docs" / "guide" / "urdf.md").read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_urdf_guide_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    code = "\n".join(b for b in _blocks() if not b.startswith("# slow"))
    exec(compile(code, "docs/guide/urdf.md", "exec"), {})


@pytest.mark.slow
def test_urdf_guide_runs_with_the_biped_step(monkeypatch):
    monkeypatch.chdir(ROOT)
    assert any(b.startswith("# slow") for b in _blocks())
    exec(compile("\n".join(_blocks()), "docs/guide/urdf.md", "exec"), {})
