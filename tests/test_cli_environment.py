"""Mistakes of the user and of the environment on the command line: huge counts, a full disk, a
closed pipe, damaged or foreign result files, a directory that cannot be written — each one line
on stderr and exit code 2 (a closed pipe: quiet, 141), never an internal error, never a partial
file. Every case once ended otherwise; the comment says how."""

from __future__ import annotations

import csv
import errno
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from amble.analysis.store import ResultStore
from amble.cli.main import main
from amble.errors import OutputError
from amble.simulation.trajectory import Trajectory

SWEEP = ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--scheduler", "synchronous", "--json"]


def _error(capsys, argv: list[str], needle: str) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("amble: error: ") and err.count("\n") == 1, err
    assert needle in err, err
    return err


@pytest.mark.parametrize("argv, needle", [
    (["simulate", "compass-gait", "--steps", "99999999999999999999999"], "at most"),  # OverflowError
    (["sweep", "compass-gait", "--param", "slope=0.01:0.05:99999999999999999999999"], "at most"),  # ValueError
    (["sweep", "compass-gait", "--param", "slope=0.01:0.05:9999999999999"], "at most"),  # MemoryError
    (["sweep", "compass-gait", "--param", "slope=0.01:0.05:1000", "--param", "mh=9:10:1001"], "1001000 points"),
    (["sweep", "compass-gait", "--kind", "basin", "--x", "stance=-0.3:0:2", "--x", "stance_dot=1:2:2",
      "--steps", "99999999999999999999"], "at most"),
    (["limit-cycle", "compass-gait", "--period", "99999999999999999999"], "at most"),
])
def test_huge_counts_are_refused_before_any_work(capsys, argv, needle):
    _error(capsys, argv, needle)


def _no_space(path: Path) -> None:
    """A writer that fills the disk: some bytes land, then ENOSPC."""
    with open(path, "w") as f:
        f.write("t,stance\n0.0,")
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_a_full_disk_is_one_line_and_leaves_no_partial_file(capsys, tmp_path, monkeypatch):
    # once an internal error (OSError 28) with the truncated file left behind
    monkeypatch.setattr(Trajectory, "save", lambda self, path, **kw: _no_space(Path(path)))
    out = tmp_path / "walk.csv"
    _error(capsys, ["simulate", "compass-gait", "--steps", "2", "--out", str(out)], "No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_while_plotting_leaves_the_old_plot(capsys, tmp_path, monkeypatch):
    import amble.viz.plot

    plot = tmp_path / "walk.png"
    plot.write_bytes(b"an older plot")
    monkeypatch.setattr(amble.viz.plot, "plot_trajectory", lambda tr, path, **kw: _no_space(Path(path)))
    _error(capsys, ["simulate", "compass-gait", "--steps", "2", "--plot", str(plot)], "No space left on device")
    assert plot.read_bytes() == b"an older plot" and [p.name for p in tmp_path.iterdir()] == ["walk.png"]


def test_a_closed_pipe_ends_quietly(tmp_path):
    # `amble models | head -1` once printed "internal error: BrokenPipeError" and exited 1
    proc = subprocess.Popen([sys.executable, "-m", "amble.cli", "models"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    proc.stdout.close()  # the reader goes away before the first line, as head does after its last
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 141 and err == "", err


def test_a_sweep_file_in_an_unwritable_directory_is_refused_before_the_work(capsys, tmp_path, monkeypatch):
    # once a PermissionError at compaction, after every point had been computed
    import tempfile

    import amble.analysis.fixed_points as fp

    def refuse(*a, **kw):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    def no_work(*a, **kw):
        raise AssertionError("a point was computed")

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    monkeypatch.setattr(fp, "_fp_task", no_work)
    _error(capsys, [*SWEEP, "--out", str(tmp_path / "s.csv")], "Permission denied")


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root writes read-only directories")
def test_a_read_only_directory_is_refused_before_the_work(capsys, tmp_path):
    out = tmp_path / "ro" / "s.csv"
    out.parent.mkdir()
    out.write_text("")  # the file itself writable, its directory not: compaction could not replace it
    out.parent.chmod(0o500)
    try:
        _error(capsys, [*SWEEP, "--out", str(out)], "cannot")
    finally:
        out.parent.chmod(0o700)


def _read_only_mounts_work() -> bool:
    """Whether this process may make a private read-only bind mount (root with unshare)."""
    if not sys.platform.startswith("linux") or os.geteuid() != 0 or shutil.which("unshare") is None:
        return False
    probe = subprocess.run(["unshare", "-m", "sh", "-c", "mount --bind /tmp /tmp && mount -o remount,bind,ro /tmp"],
                           capture_output=True, timeout=30)
    return probe.returncode == 0


@pytest.mark.skipif(not _read_only_mounts_work(), reason="needs root and unshare for a read-only bind mount")
def test_a_writable_file_in_a_read_only_directory_is_refused_before_the_work(tmp_path):
    # the file itself writable (bind-mounted read-write), its directory read-only: compaction,
    # which replaces the file through a temporary one beside it, once failed after all the work
    # with an untyped "OSError: [Errno 30] Read-only file system"
    ro = tmp_path / "ro"
    ro.mkdir()
    for name in ("s.csv", ".s.csv.lock"):
        (ro / name).write_text("")
        (tmp_path / name).write_text("")
    script = ("from amble.analysis.sweep import sweep; from amble.models import load; "
              f"sweep(load('compass-gait'), 'fixed-point', {{'slope': [0.04, 0.05]}}, out={str(ro / 's.csv')!r}, "
              "scheduler='synchronous', progress=False)")
    mounts = (f"mount --bind {ro} {ro} && mount -o remount,bind,ro {ro} && "
              f"mount --bind {tmp_path / 's.csv'} {ro / 's.csv'} && "
              f"mount --bind {tmp_path / '.s.csv.lock'} {ro / '.s.csv.lock'}")
    proc = subprocess.run(["unshare", "-m", "sh", "-c", f'{mounts} && exec "$0" -c "$1"', sys.executable, script],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("amble.errors.OutputError: cannot write result file") and "Read-only" in last, last
    assert (tmp_path / "s.csv").read_text() == ""  # nothing was computed, nothing written


@pytest.mark.skipif(not _read_only_mounts_work(), reason="needs root and unshare for a private small tmpfs")
def test_a_really_full_disk_is_one_line_and_leaves_no_file(tmp_path):
    # a 64 KiB file system: the samples of 10 steps do not fit
    full = tmp_path / "full"
    full.mkdir()
    outs = ["w.csv", "w.parquet", "w.npz"]
    runs = "; ".join(f'"$0" -m amble.cli simulate compass-gait --steps 10 --out {full / o} 2>&1; echo "rc=$?"'
                     for o in outs)
    shell = f"mount -t tmpfs -o size=64k tmpfs {full} && {runs}; ls -A {full}"
    proc = subprocess.run(["unshare", "-m", "sh", "-c", shell, sys.executable], capture_output=True, text=True,
                          timeout=300)
    lines = proc.stdout.strip().splitlines()
    for o, (err, rc) in zip(outs, zip(lines[0:6:2], lines[1:6:2])):
        assert rc == "rc=2" and err.startswith(f"amble: error: --out: cannot write '{full / o}'"), (err, rc)
        assert "No space left on device" in err
    assert len(lines) == 6, lines  # and `ls -A` listed nothing: no partial or part files


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_failed_compaction_keeps_the_journal_and_the_rerun_finishes(capsys, tmp_path, monkeypatch, suffix):
    ref = tmp_path / f"ref{suffix}"
    assert main([*SWEEP, "--out", str(ref)]) == 0
    out = tmp_path / f"s{suffix}"
    journal = out if suffix == ".csv" else out.with_name(out.name + ".journal.csv")
    original = ResultStore._write_compacted
    monkeypatch.setattr(ResultStore, "_write_compacted", lambda self, rows, tmp: _no_space(tmp))
    capsys.readouterr()
    _error(capsys, [*SWEEP, "--out", str(out)], "no space left on device")
    assert journal.exists() and len(list(csv.reader(journal.open()))) == 3  # header and both points
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())
    monkeypatch.setattr(ResultStore, "_write_compacted", original)
    assert main([*SWEEP, "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["complete"] and summary["computed"] == 0  # nothing was lost, nothing recomputed
    assert out.read_bytes() == ref.read_bytes()


def test_a_failed_append_leaves_the_journal_as_it_was(tmp_path, monkeypatch):
    path = tmp_path / "s.csv"
    with ResultStore(path, {"i": "int", "v": "float"}, ["i"]) as store:
        store.append([{"i": 0, "v": 0.5}])
        before = path.read_bytes()
        monkeypatch.setattr(os, "fsync", lambda fd: _no_space(tmp_path / "ignored"))
        with pytest.raises(OutputError, match="no space left on device"):
            store.append([{"i": 1, "v": 1.5}])
        assert path.read_bytes() == before and not store.has(("1",))  # the point is still pending


def test_a_corrupt_parquet_file_is_refused_and_kept(capsys, tmp_path):
    # once an internal error: ArrowInvalid
    out = tmp_path / "s.parquet"
    out.write_bytes(b"not parquet at all")
    _error(capsys, [*SWEEP, "--out", str(out)], "not a readable Parquet file")
    assert out.read_bytes() == b"not parquet at all"


def test_a_journal_with_a_byte_that_is_not_utf8_is_refused_and_kept(capsys, tmp_path):
    # once an internal error: UnicodeDecodeError
    ref = tmp_path / "ref.csv"
    assert main([*SWEEP, "--out", str(ref)]) == 0
    data = ref.read_bytes().replace(b",ok,", b",o\xff,", 1)
    out = tmp_path / "s.csv"
    out.write_bytes(data)
    _error(capsys, [*SWEEP, "--out", str(out)], "line 2 is not UTF-8")
    assert out.read_bytes() == data


def test_a_damaged_row_is_not_counted_ok_but_computed_again(capsys, tmp_path):
    # a row with step_time=abc was once counted as "ok"
    ref = tmp_path / "ref.csv"
    assert main([*SWEEP, "--out", str(ref)]) == 0
    rows = list(csv.reader(ref.open()))
    rows[1][rows[0].index("step_time")] = "abc"
    out = tmp_path / "s.csv"
    with out.open("w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)
    capsys.readouterr()
    assert main([*SWEEP, "--out", str(out)]) == 0
    cap = capsys.readouterr()
    summary = json.loads(cap.out)
    assert summary["computed"] == 1 and summary["reused"] == 1 and summary["ok"] == 2
    assert cap.err.count("\n") == 1 and "amble: warning:" in cap.err and "step_time" in cap.err
    assert out.read_bytes() == ref.read_bytes()  # healed: the file an undamaged run wrote
