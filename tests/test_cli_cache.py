"""``amble cache``: the compass gait built into an empty cache is listed, cleared by name, and
compiled again by the next run, which walks exactly as the first did; bad input is one line and
exit code 2; the reference documents every action's options.

Truth: the cache directory's own listing, and the first run's post-impact states (computed from a
library compiled independently of the one the second run compiles after the clear)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from amble.cli.main import build_parser, main

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def _simulate(cache_dir: Path) -> dict:
    env = {**os.environ, "AMBLE_CACHE_DIR": str(cache_dir), "PYTHONPATH": str(ROOT / "src"), "AMBLE_WARM_START": "1"}
    r = subprocess.run([sys.executable, "-m", "amble.cli", "simulate", "compass-gait", "--steps", "6", "--json"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("AMBLE_CACHE_DIR", str(d))
    return d


def test_a_cleared_model_is_listed_removed_and_compiled_again(empty_cache, capsys):
    d = empty_cache
    first = _simulate(d)
    code, out, _ = run(capsys, "cache", "list", "--json")
    assert code == 0
    listed = json.loads(out)
    (cg,) = [m for m in listed["models"] if m["name"] == "compass-gait"]
    assert cg["derivatives"] is False and cg["specs"] == ["compass-gait"]  # a plain run needs no derivatives
    on_disk = sorted(p.name for p in d.iterdir())
    assert set(cg["files"]) == {n for n in on_disk if n.startswith(cg["key"])} and len(cg["files"]) == 3
    assert cg["bytes"] == sum((d / n).stat().st_size for n in cg["files"])
    (rt,) = listed["runtimes"]
    code, text, _ = run(capsys, "cache", "list")
    assert code == 0 and any(line.split()[:2] == ["compass-gait", cg["key"]] for line in text.splitlines())

    code, out, _ = run(capsys, "cache", "clear", "--model", "compass-gait", "--json")
    assert code == 0
    cleared = json.loads(out)
    left = sorted(p.name for p in d.iterdir())
    assert set(on_disk) - set(left) == set(cg["files"]) | {n for n in on_disk if n.startswith("index-")}
    assert set(rt["files"]) <= set(left)  # runtime objects only go with --all or --older-than
    assert cleared["bytes_freed"] == sum(e["bytes"] for e in cleared["removed"]) > cg["bytes"]

    second = _simulate(d)  # compiled again (the library file was gone), same walk
    assert set(cg["files"]) <= {p.name for p in d.iterdir()}
    assert second["final_post_impact_state"] == first["final_post_impact_state"]
    assert second["steps"] == first["steps"] == 6 and second["time"] == first["time"]


def test_info_and_json_in_either_place(empty_cache, capsys):
    code, out, _ = run(capsys, "cache", "--json", "info")
    assert code == 0
    info = json.loads(out)
    assert info["directory"] == str(empty_cache) and info["models"] == 0 and info["usable"] is True
    code, again, _ = run(capsys, "cache", "info", "--json")
    assert code == 0 and json.loads(again)["directory"] == info["directory"]
    code, text, _ = run(capsys, "cache", "info")
    assert code == 0 and str(empty_cache) in text and "model libraries:" in text


def test_a_dry_run_says_what_would_go_and_removes_nothing(empty_cache, capsys):
    d = empty_cache
    d.mkdir(mode=0o700)
    stale = d / f"{'a' * 24}.json"  # a record of a library that is gone, from long ago
    stale.write_text(json.dumps({"name": "old-model", "library": f"{'a' * 24}-{'0' * 16}.so", "derivatives": True,
                                 "library_sha256": "0" * 64}))
    os.utime(stale, (1e9, 1e9))
    code, text, _ = run(capsys, "cache", "clear", "--older-than", "30", "--dry-run")
    assert code == 0 and stale.exists()
    assert "would remove old-model" in text and "dry run: nothing removed" in text
    code, text, _ = run(capsys, "cache", "clear", "--older-than", "30")
    assert code == 0 and not stale.exists() and "removed old-model" in text


@pytest.mark.parametrize("args, said", [
    (["cache"], "required"),
    (["cache", "frob"], "invalid choice"),
    (["cache", "clear"], "one of the arguments --all --older-than --model is required"),
    (["cache", "clear", "--older-than", "-1"], "--older-than must be a number of days, at least 0"),
    (["cache", "clear", "--older-than", "soon"], "is not a number"),
    (["cache", "clear", "--older-than", "nan"], "is not finite"),
    (["cache", "clear", "--all", "--model", "compass-gait"], "not allowed with"),
    (["cache", "clear", "--model", "no-such-model"], "no compiled model 'no-such-model'"),
])
def test_bad_input_is_one_line_and_exit_2(empty_cache, capsys, args, said):
    code, out, err = run(capsys, *args)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("amble: error: ") and said in err
    code, out, err = run(capsys, *args, "--json")
    assert code == 2 and said in json.loads(out)["error"]


def test_the_reference_documents_every_action():
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    sub = next(a for a in build_parser()._actions if getattr(a, "choices", None))
    cache = sub.choices["cache"]
    actions = next(a for a in cache._actions if getattr(a, "choices", None)).choices
    assert set(actions) == {"info", "list", "clear"}
    for name, parser in actions.items():
        assert f"### amble cache {name}" in text
        for opt in (o for a in parser._actions for o in a.option_strings if o not in ("-h", "--help")):
            assert f"`{opt}" in text.split(f"### amble cache {name}")[1].split("###")[0], (name, opt)
