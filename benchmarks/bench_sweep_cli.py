"""Benchmark: ``amble sweep`` from the command line on 1 and 2 workers, on local worker processes
(the default) and on a local Dask cluster (``--scheduler dask``).

Each command is a fresh process (``python -m amble.cli sweep … --json``), so its wall time holds
everything a user waits for: the interpreter, the imports, loading the compiled model, the
workers' start (forks, or a Dask cluster), the sweep and its report. Beside the wall time, the CPU
time of the command and of every process it started and waited for (its workers), from
``resource.getrusage(RUSAGE_CHILDREN)`` around the call: on a shared, loaded machine the wall time
measures the machine as much as the code, the CPU time the work. *sweep s* is the command's own
timing of the sweep (``"seconds"`` of its JSON summary: workers started, tasks run, report
worked out), without the interpreter, imports and model load.

Commands (each with ``--workers 1`` and ``--workers 2``, and again with ``--scheduler dask``):

- a 200-point fixed-point branch, ``amble sweep compass-gait --param slope=0.01:0.08:200``
  (continuation inside chunks of consecutive values);
- a 100 × 100 basin, ``amble sweep compass-gait --kind basin --x stance=-0.35:-0.10:100
  --x stance_dot=0.8:1.4:100 --set slope=0.05`` (the grid of the other basin benchmarks);
- the start-up overhead: a 2-point branch, ``amble sweep compass-gait --param slope=0.01:0.08:2``.

All commands run interleaved (one of each per round, so a change in the machine's load hits every
configuration alike); medians of the rounds. The results of every configuration are checked
equal (the same rows whatever the workers and scheduler).
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Any

from benchmarks.common import Goal, child_env, table

GOAL_SCALING = 1.8

#: name → (command-line arguments after ``amble sweep``, what the table calls it)
COMMANDS: dict[str, tuple[list[str], str]] = {
    "branch": (["compass-gait", "--param", "slope=0.01:0.08:200"], "fixed-point branch, 200 points"),
    "basin": (["compass-gait", "--kind", "basin", "--x", "stance=-0.35:-0.10:100", "--x", "stance_dot=0.8:1.4:100",
               "--set", "slope=0.05"], "basin, 100 × 100"),
    "start": (["compass-gait", "--param", "slope=0.01:0.08:2"], "start-up: branch of 2 points"),
}
#: (scheduler arguments, label)
SCHEDULERS: dict[str, list[str]] = {"local processes (default)": [], "Dask (`--scheduler dask`)":
                                    ["--scheduler", "dask"]}


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_command(args: list[str], cwd: str) -> dict[str, Any]:
    """One ``amble sweep … --json`` in a fresh process: wall s, CPU s (with its workers), the
    summary it printed."""
    cmd = [sys.executable, "-m", "amble.cli", "sweep", *args, "--json"]
    c0, t0 = _cpu_children(), time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, env=child_env(), capture_output=True, text=True, timeout=900)
    wall, cpu = time.perf_counter() - t0, _cpu_children() - c0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    return {"wall": wall, "cpu": cpu, "summary": json.loads(proc.stdout)}


def _same(summary: dict[str, Any]) -> str:
    """The part of a summary that must not depend on the workers or the scheduler."""
    return json.dumps({k: v for k, v in summary.items() if k != "seconds"}, sort_keys=True)


def measure(reps: int) -> dict[tuple[str, str, int], list[dict[str, Any]]]:
    """Every command × scheduler × workers, ``reps`` interleaved rounds (after one warm-up round
    that also fills the model cache)."""
    configs = [(c, s, w) for c in COMMANDS for s in SCHEDULERS for w in (1, 2)]
    runs: dict[tuple[str, str, int], list[dict[str, Any]]] = {k: [] for k in configs}
    with tempfile.TemporaryDirectory(prefix="amble_bench_sweep_") as d:
        for c, s, w in configs:  # warm-up: compiled model in the cache, files in the page cache
            run_command([*COMMANDS[c][0], *SCHEDULERS[s], "--workers", str(w)], d)
        for _ in range(reps):
            for c, s, w in configs:
                runs[(c, s, w)].append(run_command([*COMMANDS[c][0], *SCHEDULERS[s], "--workers", str(w)], d))
    for c in COMMANDS:
        seen = {_same(r["summary"]) for s in SCHEDULERS for w in (1, 2) for r in runs[(c, s, w)]}
        if len(seen) != 1:
            raise RuntimeError(f"amble sweep {' '.join(COMMANDS[c][0])}: results differ across workers/schedulers")
    return runs


def _med(rs: list[dict[str, Any]], key: str) -> float:
    return statistics.median(r["summary"]["seconds"] if key == "sweep" else r[key] for r in rs)


def _task_times(kind: str, chunk: int | None = None, points: int = 200) -> list[float]:
    """CPU seconds of each task of the benchmark's branch (``kind="branch"``, slope 0.01…0.08 in
    ``points`` values, ``chunk`` values a task, default the sweep's) or basin, in submission
    order: the sweep run in this process with its task function timed (the thread's CPU time,
    which the machine's load does not inflate)."""
    import numpy as np

    import amble.analysis.basin as basin_mod
    import amble.analysis.fixed_points as fp_mod
    from amble.analysis.sweep import sweep
    from amble.cli.args import load_model

    system = load_model("compass-gait", compiled=True, derivatives=True)
    mod, name = (fp_mod, "_fp_task") if kind == "branch" else (basin_mod, "_basin_task")
    raw, times = getattr(mod, name), []

    def timed(*a: Any) -> Any:
        t0 = time.thread_time()
        out = raw(*a)
        times.append(time.thread_time() - t0)
        return out

    setattr(mod, name, timed)
    try:
        if kind == "branch":
            sweep(system, "fixed-point", {"slope": np.linspace(0.01, 0.08, points)}, scheduler="synchronous",
                  progress=False, **({} if chunk is None else {"chunk": chunk}))
        else:
            sweep(system, "basin", {"stance": np.linspace(-0.35, -0.10, 100), "stance_dot": np.linspace(0.8, 1.4, 100)},
                  params={"slope": 0.05}, scheduler="synchronous", progress=False)  # the CLI's defaults
    finally:
        setattr(mod, name, raw)
    return times


def _in_order(times: list[float], workers: int = 2) -> float:
    """The time to finish tasks of these durations taken in order by the first free of ``workers``
    (how a process pool or Dask hands them out)."""
    import heapq

    free = [0.0] * workers
    for t in times:
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def balance(reps: int) -> tuple[str, dict[str, Any]]:
    """How evenly the tasks of the benchmark's branch (former chunks of 32, and the default) and
    basin fill two workers: a table and its numbers (medians of ``reps``)."""
    from amble.analysis.fixed_points import default_chunk

    cases = {f"branch of {n}, chunks of {c or default_chunk(n)} ({'default' if c is None else 'before'})":
             ("branch", c, n) for n in (200, 100) for c in (32, None)}
    cases["basin 100 × 100, 5 rows a task (default)"] = ("basin", None, 0)
    got: dict[str, list[tuple[float, float, float, int]]] = {k: [] for k in cases}
    for _ in range(reps):
        for label, (kind, chunk, n) in cases.items():
            ts = _task_times(kind, chunk, n)
            got[label].append((sum(ts), max(ts), _in_order(ts), len(ts)))
    rows, data = [], {}
    for label, rs in got.items():
        total, big, span = (statistics.median(r[i] for r in rs) for i in range(3))
        bound = statistics.median(r[0] / r[2] for r in rs)
        data[label] = {"tasks": rs[0][3], "cpu_s": total, "largest_s": big, "two_workers_s": span, "bound": bound}
        rows.append([label, str(rs[0][3]), f"{total:.2f}", f"{big:.3f}", f"{span:.2f}", f"{bound:.2f}×"])
    md = (f"**Tasks and workers.** CPU seconds of every task (the sweep in this process, each task timed; "
          f"medians of {reps}) and the time two workers need taking them in order, the first free worker the "
          "next task, as the process pool and Dask do: the most two free workers can gain over one from how "
          "the sweep is cut, whatever the machine's load.\n\n"
          + table(["sweep", "tasks", "task CPU s, sum", "largest task s", "2 workers, in order, s",
                   "bound from the tasks"], rows))
    return md, data


def run(quick: bool = False) -> tuple[str, list[Goal], dict[str, Any]]:
    """The command-line table (Markdown), its goals and numbers."""
    reps = 3 if quick else 7
    load0 = os.getloadavg()
    runs = measure(reps)
    load1 = os.getloadavg()
    rows, data, goals = [], {}, []
    for c in COMMANDS:
        for s in SCHEDULERS:
            m = {w: {k: _med(runs[(c, s, w)], k) for k in ("wall", "cpu", "sweep")} for w in (1, 2)}
            for w in (1, 2):
                m[w]["best"] = min(r["wall"] for r in runs[(c, s, w)])
            data[f"{c} {s}"] = m
    for c, (_, label) in COMMANDS.items():
        for s in SCHEDULERS:
            m, start = data[f"{c} {s}"], data[f"start {s}"]
            # on two free cores: the 2-point command's CPU (interpreter, imports, model, workers'
            # start) runs as it did, the rest split evenly between the workers (an upper bound)
            bound = m[1]["cpu"] / (start[2]["cpu"] + max(0.0, m[2]["cpu"] - start[2]["cpu"]) / 2)
            m["bound"] = bound
            rows.append([label, s, f"{m[1]['wall']:.2f}", f"{m[2]['wall']:.2f}", f"{m[1]['cpu']:.2f}",
                         f"{m[2]['cpu']:.2f}", f"{m[1]['sweep']:.2f}", f"{m[2]['sweep']:.2f}",
                         f"**{m[1]['wall'] / m[2]['wall']:.2f}×**", f"{m[1]['best'] / m[2]['best']:.2f}×",
                         f"{m[1]['sweep'] / m[2]['sweep']:.2f}×", f"{m[2]['cpu'] / m[2]['wall']:.2f}",
                         "—" if c == "start" else f"{bound:.2f}×"])
    for c in ("branch", "basin"):
        for s in SCHEDULERS:
            m, start = data[f"{c} {s}"], data[f"start {s}"]
            # the part of the command beyond what a 2-point sweep costs on the same workers
            net = (m[1]["wall"] - start[1]["wall"]) / max(1e-9, m[2]["wall"] - start[2]["wall"])
            goals.append(Goal(f"`amble sweep`, {COMMANDS[c][1]}, {s}: 2 workers ÷ 1 (command's wall time)",
                              f"≥ {GOAL_SCALING:g}×" if s.startswith("local") else "(reported)",
                              f"{m[1]['wall'] / m[2]['wall']:.2f}× ({m[1]['wall']:.2f} → {m[2]['wall']:.2f} s; "
                              f"best runs {m[1]['best'] / m[2]['best']:.2f}×; "
                              f"sweep alone {m[1]['sweep'] / m[2]['sweep']:.2f}×; beyond a 2-point sweep "
                              f"({start[1]['wall']:.2f}, {start[2]['wall']:.2f} s) {net:.2f}×; CPU {m[1]['cpu']:.2f} → "
                              f"{m[2]['cpu']:.2f} s: ≤ {m['bound']:.2f}× on two free cores)",
                              m[1]["wall"] / m[2]["wall"] >= GOAL_SCALING if s.startswith("local") else None))
    md = (f"Fresh `python -m amble.cli sweep … --json` processes, medians of {reps} interleaved rounds; "
          f"load average (1 min) {load0[0]:.2f} before and {load1[0]:.2f} after the rounds on the 2 cores — "
          "the machine was shared and loaded, so each worker got a fraction of a core. *CPU* is of the "
          "command and the processes it started (workers), `getrusage(RUSAGE_CHILDREN)`; *sweep s* the "
          "command's own timing of the sweep (its JSON `seconds`: workers started, tasks, report), without "
          "interpreter, imports and model load; *cores used, 2 w.* = CPU ÷ wall of the 2-worker command "
          "(≤ 2; what the machine gave it); *best* the ratio of the fastest runs; *bound on 2 free cores*: "
          "C₁ ÷ (S₂ + (C₂ − S₂) ÷ 2) from the CPU medians C of the command and S of the 2-point command on "
          "the same scheduler and 2 workers — its start-up (interpreter, imports, model, workers) as it ran, "
          "the rest split evenly between two free cores: the most the command can gain, whatever the "
          "machine's load. The rows of every configuration were checked equal. "
          "One worker on local processes runs the tasks in the command's process (nothing forked).\n\n"
          + table(["command", "scheduler", "wall s, 1 w.", "wall s, 2 w.", "CPU s, 1 w.", "CPU s, 2 w.",
                   "sweep s, 1 w.", "sweep s, 2 w.", "wall 2 ÷ 1", "best 2 ÷ 1", "sweep 2 ÷ 1",
                   "cores used, 2 w.", "bound on 2 free cores"], rows))
    data["load_before"], data["load_after"] = load0, load1
    bal_md, data["balance"] = balance(3)
    return md + "\n\n" + bal_md, goals, data


if __name__ == "__main__":
    text, gs, _ = run(quick="--quick" in sys.argv)
    print(text)
    for g in gs:
        print(f"{g.name}: {g.measured} ({g.target})")
