"""Model files on the command line: ``path/to/file.py[:callable]`` wherever a model name goes,
errors in the file as one line with file and line number (exit 2), and the tutorial's section on
one's own model file run command by command."""

from __future__ import annotations

import json
import re
import shlex
import shutil
from pathlib import Path

import pytest

from amble.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
WALKER = ROOT / "examples" / "my_walker.py"


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_file_with_build(capsys):
    code, out, _ = run(capsys, "simulate", WALKER, "--steps", "3", "--json")
    assert code == 0
    assert json.loads(out)["steps"] == 3


def test_named_callable_and_module_level_system(capsys, tmp_path):
    src = WALKER.read_text(encoding="utf-8").replace('if __name__ == "__main__":', "lw = build()\n\nif False:")
    f = tmp_path / "lw.py"
    f.write_text(src.replace("def build()", "def make()").replace("lw = build()", "lw = make()"), encoding="utf-8")
    # a callable, a system, the single system of the module: the same model, found three ways
    found = []
    for spec in (f"{f}:make", f"{f}:lw", str(f), str(WALKER)):
        code, out, err = run(capsys, "limit-cycle", spec, "--json")
        assert code == 0, err
        found.append(json.loads(out))
    assert all(d["step_time"] == found[-1]["step_time"] and d["fixed_point"] == found[-1]["fixed_point"]
               for d in found)


def test_file_output_goes_to_stderr_so_json_parses(capsys, tmp_path):
    f = tmp_path / "loud.py"
    f.write_text(WALKER.read_text(encoding="utf-8") + "\nprint('hello from the model file')\n", encoding="utf-8")
    code, out, err = run(capsys, "simulate", f, "--steps", "2", "--json")
    assert code == 0 and json.loads(out)["steps"] == 2 and "hello" in err


@pytest.mark.parametrize("source, needle", [
    ("x = 1\ny = 1 / 0\n", ":2: ZeroDivisionError"),
    ("def f(:\n    pass\n", ":1: SyntaxError"),
    ("from amble import Model\nm = Model('m')\nm.coordinates('q')\nm.point('p', (0, 0, 0, 0))\n",
     ":4: model 'm': point 'p' has 4"),
    ("x = 1\n", "no build() and no HybridSystem"),
])
def test_errors_in_the_file_are_one_line_with_the_line_number(capsys, tmp_path, source, needle):
    f = tmp_path / "broken.py"
    f.write_text(source, encoding="utf-8")
    code, out, err = run(capsys, "simulate", f)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and str(f) in err and needle in err, err


def test_missing_file_and_missing_callable(capsys, tmp_path):
    code, _, err = run(capsys, "equations", tmp_path / "nope.py")
    assert code == 2 and "does not exist" in err
    code, _, err = run(capsys, "equations", f"{WALKER}:nope")
    assert code == 2 and "defines no 'nope'" in err


def test_tutorial_runs_own_model_file_end_to_end(capsys, tmp_path, monkeypatch):
    text = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")
    block = re.search(r"<!-- tutorial-cli -->\n```bash\n(.*?)```", text, re.S).group(1)
    commands = [shlex.split(line) for line in block.splitlines() if line.strip()]
    assert len(commands) == 4 and all(c[1] in {"equations", "simulate", "limit-cycle", "sweep"} for c in commands)
    shutil.copy(WALKER, tmp_path / "my_walker.py")
    monkeypatch.chdir(tmp_path)
    for cmd in commands:
        assert cmd[0] == "amble"
        code, out, err = run(capsys, *cmd[1:])
        assert code == 0, (cmd, err)
    for name in ("walk.csv", "walk.png", "walk.html", "cycle.png", "slopes.csv", "branch.png"):
        assert (tmp_path / name).stat().st_size > 0, name
