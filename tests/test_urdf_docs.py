"""The Python blocks of docs/guide/urdf.md run, in order, as from the repository root — the 12-DOF
biped's step too (its walker builds cold in well under a minute: the only full test of a URDF
walker with a derived 3D impact)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _blocks() -> list[str]:
    text = (ROOT / "docs" / "guide" / "urdf.md").read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_urdf_guide_runs(monkeypatch, tmp_path):
    # run where the files it writes (bolt.html) may go; the repository's tests/data is reached
    # through a link, as the guide's paths name it from the repository root
    (tmp_path / "tests").symlink_to(ROOT / "tests", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    blocks = _blocks()
    assert any("stance_feet_walker(" in b for b in blocks)  # the biped's step is among them
    exec(compile("\n".join(blocks), "docs/guide/urdf.md", "exec"), {})
