"""The README's example is code users copy first: it must run and walk."""

import re
from pathlib import Path


def test_readme_python_example_runs(capsys):
    text = (Path(__file__).parents[1] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "README has no python example"
    ns: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), ns)
    assert ns["walk"].status == "completed"
    assert ns["cycle"].stable
    code_lines = [ln for ln in blocks[0].splitlines() if ln.strip() and not ln.strip().startswith("#")]
    assert len(code_lines) <= 25
