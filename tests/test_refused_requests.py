"""A refused request changes nothing, an interrupt says so in one line, and a request for more
worker processes than cores neither hangs nor leaks."""

import os
import re
import signal
import subprocess
import sys
import threading
import time
import warnings

import pytest

from amble.analysis.runner import cores, open_client, workers_for
from amble.cli.main import main


@pytest.mark.parametrize("content", [b"name,age\nbob,3", bytes(range(256)) * 8], ids=["csv-of-another-kind", "binary"])
def test_a_refused_sweep_file_stays_byte_identical(tmp_path, monkeypatch, content):
    """A file that is not this sweep's is refused (exit 2); its last line once went missing."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f.csv").write_bytes(content)
    code = main(["sweep", "compass-gait", "--param", "slope=0.04:0.06:3", "--out", "f.csv", "--scheduler",
                 "synchronous"])
    assert code == 2
    assert (tmp_path / "f.csv").read_bytes() == content
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.csv"]  # not even a lock file is left


def test_a_sweep_leaves_its_results_and_no_lock_file(tmp_path):
    """The lock of a result file is removed by its holder; while it is held a second sweep is
    refused, and once released (and its file gone) a third takes it again."""
    from amble.analysis.store import ResultStore
    from amble.errors import OutputError

    out = tmp_path / "r.csv"
    with ResultStore(out, ["slope", "period"], ["slope"]):
        assert (tmp_path / ".r.csv.lock").read_text() == str(os.getpid())
        with pytest.raises(OutputError, match="in use by another sweep"):
            ResultStore(out, ["slope", "period"], ["slope"])
    assert not (tmp_path / ".r.csv.lock").exists()
    with ResultStore(out, ["slope", "period"], ["slope"]):
        assert (tmp_path / ".r.csv.lock").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_more_workers_than_cores_are_capped_with_a_warning():
    with pytest.warns(UserWarning, match="more than the"):
        assert workers_for(64) == cores()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert workers_for(1) == 1 and workers_for(None) == cores()
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError):
            workers_for(bad)


def test_a_cluster_asked_for_64_workers_starts_one_per_core():
    """64 worker processes on two cores took minutes to start and leaked their semaphores."""
    with pytest.warns(UserWarning, match="more than the"):
        client, close = open_client("dask", 64)
    try:
        assert len(client.scheduler_info()["workers"]) == cores()
    finally:
        close()
    with pytest.warns(UserWarning, match="more than the"):
        local, close = open_client(None, 64)  # local processes: as many as cores, or this process
    close()
    assert getattr(local, "workers", 1) == cores()


def _interrupt_when(cmd: list[str], ready: str, env: dict[str, str], timeout: float = 600) -> tuple[int, list[str]]:
    """Run ``amble cmd`` in its own process group, send SIGINT to the whole group (as Ctrl-C in a
    terminal does) once its stderr matches the pattern ``ready``; return the exit code and stderr lines."""
    p = subprocess.Popen([sys.executable, "-m", "amble.cli", *cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         env=env, preexec_fn=lambda: (os.setpgid(0, 0), signal.signal(signal.SIGINT, signal.SIG_DFL)))
    seen, lines = threading.Event(), []

    def read() -> None:
        buf = b""
        while chunk := p.stderr.read1(4096):
            buf += chunk
            if re.search(ready.encode(), buf):
                seen.set()
        lines.extend(buf.decode(errors="replace").replace("\r", "\n").splitlines())
        seen.set()

    t = threading.Thread(target=read, daemon=True)
    t.start()
    assert seen.wait(timeout), "the command never got going"
    assert p.poll() is None, "the command ended before it could be interrupted"
    os.killpg(p.pid, signal.SIGINT)
    code = p.wait(timeout=120)
    t.join(30)
    return code, lines


def test_ctrl_c_during_a_gait_optimisation_is_an_interrupt_not_a_solver_failure(tmp_path):
    """IPOPT's iterations are running (its iteration table is on stderr) when Ctrl-C comes."""
    env = {**os.environ, "AMBLE_CACHE_DIR": str(tmp_path / "cache")}
    code, lines = _interrupt_when(["optimize-gait", "rabbit", "--nodes", "20"], r"iter +objective", env)
    assert code == 130
    assert lines[-1] == "amble: interrupted"
    assert not any("failed" in ln or "Traceback" in ln for ln in lines)


@pytest.mark.parametrize("scheduler", [[], ["--scheduler", "dask"]], ids=["local-processes", "dask"])
def test_ctrl_c_on_a_sweep_on_workers_prints_one_line(tmp_path, scheduler):
    """Once ≈150 lines of distributed's warnings and tracebacks, from the client and each worker."""
    env = {**os.environ, "AMBLE_CACHE_DIR": str(tmp_path / "cache")}
    cmd = ["sweep", "compass-gait", "--param", "slope=0.01:0.08:400", "--param", "mh=5:15:40", "--workers", "2",
           *scheduler]
    code, lines = _interrupt_when(cmd, r"\| *[1-9][0-9]*/16000", env)  # the workers are at work
    time.sleep(0.5)
    assert code == 130
    said = [ln for ln in lines if ln.strip() and "fixed-point-map" not in ln]  # the progress bar aside
    assert said == ["amble: interrupted"]
