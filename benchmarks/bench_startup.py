"""Start-up cost of the command line: ``amble limit-cycle compass-gait`` in a fresh process.

* cold: every run gets a new ``AMBLE_CACHE_DIR`` with no model in it (seeded with the shared
  runtime, whose one-time compile is a row of its own: :mod:`benchmarks.runtime_seed`), so the
  model is derived, generated and compiled before the limit cycle is found;
* warm: the cache already holds the compiled model (one untimed priming run), so the run is
  interpreter start-up + imports + loading the shared library + the Newton search;
* the floor, measured in the same run and interleaved with the warm runs: ``python -c "pass"``
  (bare interpreter) and ``python -c "import numpy"`` (the one import a compiled run cannot do
  without), beside ``python -c "import amble"`` (which loads its names on first use);
* whether the warm run imported SymPy (it should not: the compiled model is found by the
  warm-start index, :mod:`amble.backend.index`).

Byte code of amble's sources is compiled before timing (``compileall``), as an installed package
has it: with ``PYTHONDONTWRITEBYTECODE`` set, every run would otherwise recompile ~60 modules.

The console script installed next to the running interpreter is executed directly (not through
a version-manager shim), so the timings are what a user's ``amble`` command costs. If the warm
start misses its goal, the run is profiled (``python -X importtime`` and ``cProfile``) and the
largest contributors are listed.
"""

from __future__ import annotations

import compileall
import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.common import Goal, Section, Stats, child_env, fresh_cache_dir, sec, table
from benchmarks.runtime_seed import SECTION_NOTE, compile_times, seeded_cache_dir

#: Goals (s): median wall time of the whole command.
GOAL_COLD_S = 3.0
GOAL_WARM_S = 0.15

COMMAND: tuple[str, ...] = ("limit-cycle", "compass-gait")


def amble_executable() -> list[str]:
    """The ``amble`` console script of this interpreter's environment."""
    here = Path(sys.executable).parent / "amble"
    if here.exists():
        return [str(here)]
    found = shutil.which("amble")
    if found:
        return [found]
    return [sys.executable, "-c", "import sys; from amble.cli.main import main; sys.exit(main())"]


def _wall(cmd: list[str], env: dict[str, str]) -> float:
    """Wall time (s) of one run of ``cmd``; raises if it fails."""
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}): {proc.stderr[-1000:]}")
    return wall


def _import_profile(cmd_args: list[str], env: dict[str, str], top: int = 12) -> list[tuple[str, float]]:
    """Largest cumulative import times (s) of a warm run, from ``python -X importtime``.

    Modules nested up to two levels deep are listed, so the heavy dependencies pulled in by
    ``amble`` show up beside ``amble`` itself.
    """
    code = "import sys; from amble.cli.main import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.run([sys.executable, "-X", "importtime", "-c", code, *cmd_args], env=env,
                          capture_output=True, text=True)
    rows = []
    for line in proc.stderr.splitlines():
        m = re.match(r"import time:\s+(\d+) \|\s+(\d+) \|( *)(\S+)", line)
        if m and len(m.group(3)) <= 5:  # one space plus two per nesting level: depth ≤ 2
            depth = (len(m.group(3)) - 1) // 2
            rows.append(("  " * depth + m.group(4), int(m.group(2)) / 1e6))
    return sorted(rows, key=lambda r: -r[1])[:top]


#: Profiles one whole warm run (imports included) in a child; the command's own output is dropped.
_PROFILE_CODE = """
import cProfile, contextlib, io, pstats, sys
prof = cProfile.Profile()
prof.enable()
from amble.cli.main import main
with contextlib.redirect_stdout(io.StringIO()):
    main(sys.argv[1:])
prof.disable()
pstats.Stats(prof).sort_stats("cumulative").print_stats(%d)
"""


def _cprofile(cmd_args: list[str], env: dict[str, str], top: int = 25) -> str:
    """cProfile (sorted by cumulative time) of one warm run in a fresh process, imports included."""
    proc = subprocess.run([sys.executable, "-c", _PROFILE_CODE % top, *cmd_args], env=env,
                          capture_output=True, text=True)
    text = proc.stdout.strip()
    # keep the table, shorten long site-packages paths
    return re.sub(r"\S*/site-packages/", "", text)


_SYMPY_CODE = ("import json, sys; from amble.cli import main; main(sys.argv[1:]); "
               "print(json.dumps(sorted(m for m in ('sympy', 'scipy', 'matplotlib', 'dask') if m in sys.modules)), "
               "file=sys.stderr)")


def _heavy_imports(cmd_args: list[str], env: dict[str, str]) -> list[str]:
    """The heavy libraries a warm run imports (SymPy, SciPy, Matplotlib, Dask)."""
    proc = subprocess.run([sys.executable, "-c", _SYMPY_CODE, *cmd_args], env=env, capture_output=True, text=True)
    lines = proc.stderr.strip().splitlines()
    return json.loads(lines[-1]) if lines else ["?"]


def _n_libraries(cache: str) -> int:
    return sum(1 for _ in Path(cache).glob("*.so"))


def _warm_runs(cmd: list[str], env: dict[str, str], cache: str, reps: int) -> tuple[list[float], int]:
    """``reps`` warm-cache wall times; a run that had to rebuild the model is dropped and redone.

    The cache key hashes amble's own code generator sources, so editing them between runs makes
    a "warm" run cold; such runs are counted (second value) and not used.
    """
    walls: list[float] = []
    rebuilt = 0
    while len(walls) < reps and rebuilt < 2 * reps:
        before = _n_libraries(cache)
        w = _wall(cmd, env)
        if _n_libraries(cache) == before:
            walls.append(w)
        else:
            rebuilt += 1
    if len(walls) < reps:
        raise RuntimeError("the compiled model was rebuilt in most warm runs; is amble's source changing?")
    return walls, rebuilt


def run(quick: bool = False) -> Section:
    """Time cold and warm starts (medians of ≥ 5 runs) and return the section."""
    reps = 5
    exe = amble_executable()
    import amble  # the package the children import (same environment): its byte code, as installed

    compileall.compile_dir(str(Path(amble.__file__).parent), quiet=1)
    cmd = [*exe, *COMMAND]
    print("startup: cold runs ...", flush=True)
    cold = []
    rt = compile_times()[8]  # the compass gait's capacity (4 states)
    for _ in range(reps):
        d = seeded_cache_dir()
        try:
            cold.append(_wall(cmd, child_env(d)))
        finally:
            shutil.rmtree(d, ignore_errors=True)
    print("startup: warm runs ...", flush=True)
    warm_dir = fresh_cache_dir()
    try:
        env = child_env(warm_dir)
        _wall(cmd, env)  # prime the cache
        # interleaved, so that the warm runs and their floor see the same load of the machine
        warm, bare, nump, imp, rebuilt = [], [], [], [], 0
        for _ in range(reps):
            w, r = _warm_runs(cmd, env, warm_dir, 1)
            warm += w
            rebuilt += r
            bare.append(_wall([sys.executable, "-c", "pass"], env))
            nump.append(_wall([sys.executable, "-c", "import numpy"], env))
            imp.append(_wall([sys.executable, "-c", "import amble"], env))
        heavy = _heavy_imports(list(COMMAND), env)
        s_cold, s_warm, s_bare, s_np, s_imp = (Stats.of(v) for v in (cold, warm, bare, nump, imp))
        profile_md: list[str] = []
        if s_warm.median > GOAL_WARM_S:
            print("startup: warm start misses its goal; profiling ...", flush=True)
            imports = _import_profile(list(COMMAND), env)
            profile_md += ["", "Warm start over its goal — largest imports, nested up to two levels "
                           "(`python -X importtime`, one run):", "",
                           table(["module", "cumulative s"], [[f"`{m}`", f"{s:.3f}"] for m, s in imports]), "",
                           "cProfile of one warm run, imports included (cumulative time):", "", "```",
                           _cprofile(list(COMMAND), env), "```"]
    finally:
        shutil.rmtree(warm_dir, ignore_errors=True)

    def cells(s: Stats) -> list[str]:
        return [sec(s.median, 2), sec(s.min, 2)]

    shown = " ".join(["amble", *COMMAND])
    rows = [
        [f"`{shown}`, cold cache", *cells(s_cold), f"≤ {GOAL_COLD_S:g}"],
        [f"`{shown}`, warm cache", *cells(s_warm), f"≤ {GOAL_WARM_S:g}"],
        ["runtime compile (capacity 8), once per machine", sec(rt, 2), "", ""],
        ['`python -c "import amble"`', *cells(s_imp), ""],
        ['`python -c "import numpy"` (floor)', *cells(s_np), ""],
        ['`python -c "pass"` (bare interpreter)', *cells(s_bare), ""],
    ]
    above = s_warm.median - s_np.median
    md = [
        f"Fresh process per run, wall time, median and min of {reps} runs. Cold: a new "
        "`AMBLE_CACHE_DIR` every run (derive + generate + compile the model, then find the limit cycle). "
        + SECTION_NOTE + " "
        f"warm: the compiled model already cached. Executable: `{exe[0]}`."
        + (f" {rebuilt} warm run(s) found the cache stale (amble's sources changed meanwhile) and were "
           "discarded and repeated." if rebuilt else ""),
        "",
        table(["command", "median s", "min s", "goal s"], rows),
        "",
        f"The warm run takes {above:.3f} s above the `import numpy` floor of the same run "
        f"({s_warm.median / s_np.median:.2f}× it); heavy libraries it imported: "
        f"{', '.join(heavy) if heavy else 'none (no SymPy, SciPy, Matplotlib or Dask)'}.",
        *profile_md,
    ]
    goals = [
        Goal("`amble limit-cycle compass-gait`, cold cache", f"≤ {GOAL_COLD_S:g} s",
             f"{s_cold.median:.2f} s (min {s_cold.min:.2f})", s_cold.median <= GOAL_COLD_S),
        Goal("`amble limit-cycle compass-gait`, warm cache", f"≤ {GOAL_WARM_S:g} s",
             f"{s_warm.median:.2f} s (min {s_warm.min:.2f})", s_warm.median <= GOAL_WARM_S),
    ]
    goals.append(Goal("warm `amble limit-cycle compass-gait` imports no SymPy", "none",
                      ", ".join(heavy) or "none", "sympy" not in heavy))
    data = {"cold": cold, "warm": warm, "import": imp, "numpy": nump, "bare": bare, "heavy_imports": heavy,
            "executable": exe}
    return Section("Start-up: command line", "\n".join(md), goals, data)
