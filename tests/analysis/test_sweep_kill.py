"""A sweep killed part-way loses nothing: ``amble sweep --out FILE`` is SIGKILLed (no chance to
clean up) while it writes its result file, run again, killed again, and run to the end; the final
file must equal, byte for byte, the file of an uninterrupted run — no point lost, none duplicated,
none recomputed differently.

Truth used here: the uninterrupted run's file, and the grid itself (every (slope, mh) point of the
requested grid exactly once). The grid starts on level ground (slope 0), where Newton's method
fails at some points: those are recorded ``failed`` with their reason and the sweep goes on.
"""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from amble.cli.main import main

#: 13 slopes × 8 hip masses; one Dask task (one journal append) per slope, continuation along mh.
GRID = ["--param", "slope=0:0.06:13", "--param", "mh=8:12:8"]
N_POINTS = 13 * 8


def _command(out: Path) -> list[str]:
    return ["sweep", "compass-gait", *GRID, "--scheduler", "synchronous", "--out", str(out), "--json"]


def _complete_lines(path: Path) -> int:
    """Newline-terminated lines in the file (the header included), 0 if it does not exist yet."""
    try:
        return path.read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


def _run_and_kill(out: Path, kill_after_lines: int, timeout: float = 60.0) -> None:
    """Start the sweep in a subprocess and SIGKILL it once ``out`` holds ``kill_after_lines`` lines."""
    proc = subprocess.Popen([sys.executable, "-m", "amble.cli", *_command(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=dict(os.environ))
    try:
        t0 = time.monotonic()
        while _complete_lines(out) < kill_after_lines:
            assert proc.poll() is None, f"the sweep ended (code {proc.returncode}) before it could be killed"
            assert time.monotonic() - t0 < timeout, "the sweep wrote nothing in time"
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == -signal.SIGKILL  # killed, not finished: the file is partial
    assert _complete_lines(out) - 1 < N_POINTS


def _keys(path: Path) -> list[tuple[str, str]]:
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    return [(r["slope"], r["mh"]) for r in rows]


def test_killed_sweep_resumes_to_the_uninterrupted_file(compass, tmp_path, capsys):
    from amble.backend.kernels import compiled

    compiled(compass)  # compile once here, so the subprocesses only load it from the cache
    ref = tmp_path / "uninterrupted.csv"
    assert main(_command(ref)) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["complete"] and summary["points"] == N_POINTS
    # the grid, each point exactly once, in key order
    want = [(repr(float(s)), repr(float(m))) for s in np.linspace(0, 0.06, 13) for m in np.linspace(8, 12, 8)]
    assert _keys(ref) == want
    # failing points are recorded with their reason, and the points after them are computed
    assert summary["failed"] >= 1 and summary["ok"] + summary["failed"] == N_POINTS
    assert all(f["reason"] for f in summary["failures"])

    out = tmp_path / "killed.csv"
    _run_and_kill(out, kill_after_lines=1 + 3 * 8)  # header + three slopes
    first = _complete_lines(out) - 1
    _run_and_kill(out, kill_after_lines=first + 1 + 3 * 8)  # the resumed run gets three slopes further
    second = _complete_lines(out) - 1
    assert first < second < N_POINTS

    done = subprocess.run([sys.executable, "-m", "amble.cli", *_command(out)], capture_output=True, text=True,
                          timeout=120, env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    last = json.loads(done.stdout)
    assert last["complete"] and last["reused"] + last["computed"] == N_POINTS
    assert last["reused"] >= second  # nothing already written was computed again
    assert out.read_bytes() == ref.read_bytes()


def test_killed_basin_resumes_to_the_uninterrupted_file(compass, tmp_path, capsys):
    """The same for a basin of attraction written to Parquet (journal beside the final file)."""
    from amble.backend.kernels import compiled

    compiled(compass)
    cmd = ["sweep", "compass-gait", "--kind", "basin", "--x", "stance=-0.3:-0.15:60", "--x",
           "stance_dot=0.9:1.3:60", "--steps", "60", "--scheduler", "synchronous", "--json"]
    ref = tmp_path / "uninterrupted.parquet"
    assert main([*cmd, "--out", str(ref)]) == 0
    capsys.readouterr()
    out = tmp_path / "killed.parquet"
    journal = out.with_name(out.name + ".journal.csv")
    proc = subprocess.Popen([sys.executable, "-m", "amble.cli", *cmd, "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        t0 = time.monotonic()
        while _complete_lines(journal) < 1 + 2 * 60:  # two grid rows: killed well before the end
            assert proc.poll() is None and time.monotonic() - t0 < 60
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == -signal.SIGKILL and not out.exists()
    finished = _complete_lines(journal) - 1  # cells written whole before the kill (a torn last line is not)
    assert main([*cmd, "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["reused"] == finished >= 2 * 60  # nothing finished is computed again
    assert summary["computed"] == 60 * 60 - finished
    assert not journal.exists()
    assert out.read_bytes() == ref.read_bytes()
