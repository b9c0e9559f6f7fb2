"""Shared helpers of the benchmark suite: timing statistics, fresh processes, machine info, tables.

Every benchmark module exposes ``run(quick: bool) -> Section``; :mod:`benchmarks.__main__`
prints the sections and writes them into ``BENCHMARKS.md``.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: Repository root (``benchmarks/common.py`` -> root).
REPO_ROOT: Path = Path(__file__).resolve().parents[1]

#: Marker that precedes the JSON result printed by a worker process.
RESULT_TAG = "AMBLE_BENCH_RESULT "


@dataclass
class Goal:
    """A stated performance goal and whether this run met it."""

    name: str
    target: str
    measured: str
    met: bool | None  # None: not measured (skipped)


@dataclass
class Section:
    """One benchmark's output: Markdown body (tables and notes), goals, raw numbers."""

    title: str
    markdown: str
    goals: list[Goal] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)


@dataclass
class Stats:
    """Median and minimum of repeated wall-clock measurements (seconds)."""

    median: float
    min: float
    n: int

    @classmethod
    def of(cls, samples: Sequence[float]) -> Stats:
        return cls(statistics.median(samples), min(samples), len(samples))


def time_calls(fn: Callable[[], Any], repeats: int) -> tuple[Stats, Any]:
    """Call ``fn`` ``repeats`` times; returns the wall-time statistics (s) and the last result."""
    walls = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return Stats.of(walls), out


def child_env(cache_dir: str | Path | None = None) -> dict[str, str]:
    """Environment for a child process: the repository on ``PYTHONPATH``, optionally a cache dir."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO_ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    if cache_dir is not None:
        env["AMBLE_CACHE_DIR"] = str(cache_dir)
    return env


def fresh_cache_dir(prefix: str = "amble_bench_cache_") -> str:
    """A new, empty directory for ``AMBLE_CACHE_DIR`` (a cold cache); the caller removes it."""
    return tempfile.mkdtemp(prefix=prefix)


def run_worker(module: str, args: Sequence[str], env: dict[str, str], timeout_s: float) -> dict[str, Any] | None:
    """Run ``python -m module args`` and parse the tagged JSON line it prints.

    Returns ``None`` if the child ran longer than ``timeout_s`` (it is killed); raises
    ``RuntimeError`` if it exited without a result.
    """
    cmd = [sys.executable, "-m", module, *args]
    try:
        proc = subprocess.run(cmd, cwd=REPO_ROOT, env=env, capture_output=True, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return None
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith(RESULT_TAG):
            return json.loads(line[len(RESULT_TAG):])
    raise RuntimeError(f"{module} {' '.join(args)} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")


def emit_result(result: dict[str, Any]) -> None:
    """Print a worker's result as the tagged JSON line :func:`run_worker` looks for."""
    print(RESULT_TAG + json.dumps(result), flush=True)


def _version(dist: str) -> str:
    try:
        from importlib.metadata import version

        return version(dist)
    except Exception:  # noqa: BLE001 - a missing package is reported, not fatal
        return "not installed"


def machine() -> dict[str, str]:
    """CPU model, core counts, OS and library versions of this machine."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        cpu = platform.processor() or "unknown"
    try:
        load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        load = "n/a"
    cc = "unknown"
    try:
        cc = subprocess.run(["cc", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        pass
    try:
        from amble.backend.cache import cflags

        flags = " ".join(cflags())
    except Exception as e:  # noqa: BLE001 - a machine table must not fail the run
        flags = f"unknown ({e})"
    return {
        "CPU": cpu,
        "cores (os.cpu_count)": str(os.cpu_count()),
        "cores usable (sched_getaffinity)": str(len(os.sched_getaffinity(0))) if hasattr(os, "sched_getaffinity")
        else "n/a",
        "load average at start (1, 5, 15 min)": load,
        "OS": f"{platform.system()} {platform.release()} ({platform.machine()})",
        "C compiler": cc,
        "C flags of amble's libraries": flags,
        "Python": platform.python_version(),
        "NumPy": _version("numpy"),
        "SymPy": _version("sympy"),
        "SciPy": _version("scipy"),
        "Drake (pip drake)": _version("drake"),
        "amble": _version("amble"),
    }


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A Markdown table (cells are already formatted strings or numbers)."""
    align = [":---"] + ["---:"] * (len(header) - 1)
    out = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def us(seconds: float | None) -> str:
    """Seconds → microseconds, formatted for a table."""
    return "—" if seconds is None else f"{seconds * 1e6:.1f}"


def sec(seconds: float | None, digits: int = 3) -> str:
    """Seconds, formatted for a table."""
    return "—" if seconds is None else f"{seconds:.{digits}f}"


def ratio(a: float | None, b: float | None) -> str:
    """``a / b`` formatted with an ×, or a dash when either is missing."""
    if a is None or b is None or b == 0:
        return "—"
    r = a / b
    return f"{r:.0f}×" if r >= 100 else f"{r:.1f}×" if r >= 10 else f"{r:.2f}×"


def sci(x: float | None) -> str:
    """Scientific notation with two digits, for errors."""
    return "—" if x is None else f"{x:.1e}"
