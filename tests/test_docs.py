"""The documentation is current and builds: the CLI reference matches the parser, the site builds
with ``mkdocs build --strict``, and the Python examples on the guide pages run."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
# Pages whose ```python blocks form one runnable script each (```py blocks are illustrative only).
RUNNABLE = ["index.md", "guide/modeling.md", "guide/hybrid.md", "guide/simulation.md", "guide/analysis.md",
            "guide/visualisation.md", "guide/controlled-walking.md", "guide/gait-optimisation.md",
            "guide/performance.md", "guide/rough-terrain.md"]


def _generator():
    spec = importlib.util.spec_from_file_location("gen_cli_reference", ROOT / "scripts" / "gen_cli_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_cli_reference_is_current():
    gen = _generator()
    assert (DOCS / "cli.md").read_text(encoding="utf-8") == gen.render(), (
        "docs/cli.md is out of date: run python scripts/gen_cli_reference.py")


def test_cli_reference_lists_every_command_and_option():
    from amble.cli.main import build_parser

    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    for action in build_parser()._actions:
        for name, sub in getattr(action, "choices", None) and action.choices.items() or []:
            assert f"## amble {name}" in text
            for a in sub._actions:
                for opt in a.option_strings:
                    if opt not in ("-h", "--help"):
                        assert f"`{opt}" in text, f"{name}: {opt} missing"


def test_mkdocs_build_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install mkdocs pymdown-extensions)")
    pytest.importorskip("pymdownx", reason="pymdown-extensions is not installed")
    exe = [sys.executable, "-m", "mkdocs"]
    proc = subprocess.run([*exe, "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-3000:]
    tutorial = (tmp_path / "site" / "tutorial" / "index.html").read_text(encoding="utf-8")
    assert "NAME" in tutorial and "compass-gait" in tutorial  # model code was included from the package


@pytest.mark.parametrize("page", RUNNABLE)
def test_guide_code_runs(page, tmp_path, monkeypatch):
    text = (DOCS / page).read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, re.S | re.M)
    assert blocks, f"{page} has no runnable example"
    monkeypatch.chdir(tmp_path)
    ns: dict = {"__name__": "__main__"}
    for i, block in enumerate(blocks):
        exec(compile(block, f"{page} block {i + 1}", "exec"), ns)
