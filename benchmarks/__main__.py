"""Run the benchmark suite, print the tables and write ``BENCHMARKS.md``.

Usage: ``python -m benchmarks [--quick] [--only derive,walk,startup,sweep,gaitopt,jacobian,tree,calls,movie,mfpt]
[--output PATH | --no-write]``.
``--quick`` shrinks every benchmark (fewer chain sizes, 20 walking steps) for a smoke run; the
published numbers come from a full run. With ``--only`` and an existing output file, only the
chosen sections and their rows of the goals table are replaced in it (:func:`splice`); the other
sections, and any text written by hand, are kept.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import os
import subprocess
import sys
import time
import traceback
from collections.abc import Callable, Sequence
from pathlib import Path

from benchmarks.common import REPO_ROOT, Section, child_env, machine, table

BENCHES: tuple[str, ...] = ("derive", "walk", "startup", "sweep", "gaitopt", "jacobian", "tree", "calls", "movie",
                             "mfpt", "thesis3d")


def _sweep(quick: bool) -> Section:
    """The sweep benchmark, maintained in ``benchmarks/bench_sweep.py``, if that module exists.

    With a ``run(quick)`` function it is called in-process; otherwise its command line
    (``python -m benchmarks.bench_sweep``) is run in a child and its output is quoted.
    """
    title = "Parameter sweep"
    try:
        mod = importlib.import_module("benchmarks.bench_sweep")
    except ModuleNotFoundError as e:
        if e.name != "benchmarks.bench_sweep":
            raise
        return Section(title, "Skipped: `benchmarks/bench_sweep.py` is not present.")
    if hasattr(mod, "run"):
        out = mod.run(quick=quick)
        if isinstance(out, Section):
            return out
        if isinstance(out, dict):
            return Section(out.get("title", title), str(out.get("markdown", out)), [], out)
        return Section(title, str(out))
    if quick:
        return Section(title, "Skipped in `--quick` mode (run `python -m benchmarks.bench_sweep`).")
    cmd = [sys.executable, "-m", "benchmarks.bench_sweep"]
    proc = subprocess.run(cmd, cwd=REPO_ROOT, env=child_env(), capture_output=True, text=True, timeout=1800)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmarks.bench_sweep failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    doc = (mod.__doc__ or "").strip()
    return Section(title, f"{doc}\n\nOutput of `python -m benchmarks.bench_sweep`:\n\n```\n{proc.stdout.strip()}\n```")


def _runner(name: str) -> Callable[[bool], Section]:
    if name == "sweep":
        return _sweep
    return importlib.import_module(f"benchmarks.bench_{name}").run


GOAL_HEADER = ("goal", "target", "measured (median)", "")


def _goals_table(sections: list[Section]) -> str:
    mark = {True: "met", False: "**missed**", None: "not measured"}
    rows = [[g.name, g.target, g.measured, mark[g.met]] for s in sections for g in s.goals]
    return table(GOAL_HEADER, rows) if rows else "No goals measured."


def render(sections: list[Section], command: str, info: dict[str, str], wall_s: float) -> str:
    """The whole ``BENCHMARKS.md`` text."""
    day = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    out = [
        "# amble benchmarks",
        "",
        "amble measured side by side with its peers in the same run on the same machine. Regenerate with:",
        "",
        "```",
        command,
        "```",
        "",
        f"Run {day}, {wall_s / 60:.1f} min in all. The suite is not part of the test run; it needs a C "
        "compiler, SciPy and SymPy, and uses Drake (`pip install drake`) when it is importable (skipped "
        "with the reason otherwise).",
        "",
        "**Noise.** This machine is a shared 2-core virtual machine with other work running at the same "
        "time, so single timings wander by tens of percent. Every time below is a median of at least 5 "
        "runs unless marked, with the minimum beside it (the minimum is the better estimate of the "
        "unloaded cost; the median is what the goals are judged on). Ratios are of medians taken in "
        "the same run.",
        "",
        "## Machine",
        "",
        table(["", ""], [[k, v] for k, v in info.items()]),
        "",
        "## Goals",
        "",
        _goals_table(sections),
        "",
    ]
    for s in sections:
        out += [f"## {s.title}", "", s.markdown.strip(), ""]
    return "\n".join(out)


def _blocks(text: str) -> list[list[str]]:
    """``text`` cut into blocks of lines, each (but the first) starting at a ``## `` heading."""
    blocks: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.startswith("## "):
            blocks.append([])
        blocks[-1].append(line)
    return blocks


def _goal_name(row: str) -> str:
    return row[2:].split(" | ", 1)[0].strip()


def _splice_goals(block: list[str], sections: list[Section]) -> list[str]:
    """The goals block with each section's rows in place of the old rows of the same names (at
    the first one's position; appended when none was there)."""
    rows = [ln for ln in block if ln.startswith("| ")][1:]  # the first is the header
    if not rows:
        return ["## Goals", "", _goals_table(sections), ""]
    for s in sections:
        new = _goals_table([s]).splitlines()[2:] if s.goals else []
        names = {_goal_name(r) for r in new}
        first = next((i for i, r in enumerate(rows) if _goal_name(r) in names), len(rows))
        at = sum(1 for r in rows[:first] if _goal_name(r) not in names)  # its place among the rows kept
        kept = [r for r in rows if _goal_name(r) not in names]
        rows = kept[:at] + new + kept[at:]
    return ["## Goals", "", *table(GOAL_HEADER, []).splitlines(), *rows, ""]


def splice(old: str, sections: list[Section], command: str, info: dict[str, str], wall_s: float) -> str:
    """``old`` (a ``BENCHMARKS.md``) with the given sections replaced (or appended) and their goal
    rows updated; a line under the run's date says which sections were run again, when and how."""
    blocks = _blocks(old)
    day = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    titles = ", ".join(f"*{s.title}*" for s in sections)
    load = info.get("load average at start (1, 5, 15 min)", "?")
    note = (f"Re-run {day}: {titles} only (`{command}`, {wall_s / 60:.1f} min; load average at start "
            f"{load}, at end {info.get('load average at end (1, 5, 15 min)', '?')}); the other sections "
            "are from the run above.")
    head: list[str] = []
    for ln in blocks[0]:  # the note of an earlier re-run of the same sections goes (and its blank line)
        if not (ln.startswith("Re-run ") and all(f"*{s.title}*" in ln for s in sections)) and (ln or head[-1:] != [""]):
            head.append(ln)
    at = next((i + 1 for i, ln in enumerate(head) if ln.startswith("Run ")), len(head))
    out = [*head[:at], "", note, *head[at:]]
    done = set()
    for b in blocks[1:]:
        title = b[0][3:].strip()
        if title == "Goals":
            b = _splice_goals(b, sections)
        for s in sections:
            if s.title == title:
                b, done = [f"## {s.title}", "", s.markdown.strip(), ""], done | {s.title}
        out += b
    for s in sections:
        if s.title not in done:
            out += [f"## {s.title}", "", s.markdown.strip(), ""]
    return "\n".join(out).rstrip("\n") + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small, fast versions of every benchmark")
    ap.add_argument("--only", default=",".join(BENCHES), help=f"comma-separated subset of {','.join(BENCHES)}")
    ap.add_argument("--output", default=str(REPO_ROOT / "BENCHMARKS.md"), help="Markdown file to write")
    ap.add_argument("--no-write", action="store_true", help="print only; do not write the Markdown file")
    args = ap.parse_args(argv)
    chosen = [b.strip() for b in args.only.split(",") if b.strip()]
    unknown = [b for b in chosen if b not in BENCHES]
    if unknown:
        ap.error(f"unknown benchmark(s) {', '.join(unknown)}; choose from {', '.join(BENCHES)}")
    command = " ".join(["python -m benchmarks", *(sys.argv[1:] if argv is None else argv)])
    info = machine()
    for k, v in info.items():
        print(f"{k}: {v}")
    t0 = time.perf_counter()
    sections: list[Section] = []
    for name in chosen:
        print(f"\n=== {name} ===", flush=True)
        try:
            sec = _runner(name)(args.quick)
        except Exception:  # noqa: BLE001 - one failing benchmark must not lose the others' numbers
            tb = traceback.format_exc()
            print(tb, file=sys.stderr)
            sec = Section(name, f"Failed:\n\n```\n{tb.strip()}\n```")
        sections.append(sec)
        print(f"\n## {sec.title}\n\n{sec.markdown}\n", flush=True)
    wall = time.perf_counter() - t0
    info["load average at end (1, 5, 15 min)"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
    print("## Goals\n\n" + _goals_table(sections))
    if not args.no_write:
        path = Path(args.output)
        partial = set(chosen) != set(BENCHES) and path.exists()
        path.write_text(splice(path.read_text(), sections, command, info, wall) if partial
                        else render(sections, command, info, wall))
        print(f"\nwrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
