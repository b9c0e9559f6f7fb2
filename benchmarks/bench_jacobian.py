"""Cost of the return map's Jacobian in the section chart: exact (one run with the variational
equations of the state columns and the saltation matrices, which also records its last footfall
for the section's chart) against central differences (2d runs for a d-dimensional section, and
one for the chart), both in units of one plain return-map evaluation measured in the same run
(medians of interleaved repeats). Each includes the chart and the multipliers'
eigen-decomposition (d ≤ 13, microseconds). "∂P/∂x alone" is `ReturnMap.derivatives`: the
full-state derivative without the chart.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks.common import Goal, Section, Stats, table

MODELS = ("compass-gait", "kneed-biped", "humanoid-2d", "humanoid-3d")
#: exact Jacobian + multipliers per return-map evaluation (the issue's goal)
GOAL_RATIO = 3.0


def _median_interleaved(fns, repeats: int) -> list[Stats]:
    samples: list[list[float]] = [[] for _ in fns]
    for _ in range(repeats):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            samples[i].append(time.perf_counter() - t0)
    return [Stats.of(s) for s in samples]


def run(quick: bool = False) -> Section:
    from amble.analysis.poincare import ReturnMap, find_fixed_point
    from amble.models import load

    rows, goals, data = [], [], {}
    for name in MODELS[:2] if quick else MODELS:
        print(f"jacobian: {name} ...", flush=True)
        system = load(name)
        lc = find_fixed_point(system)
        P = ReturnMap(system)
        x = lc.fixed_point
        S, E = P.section_jacobian(x)[1:]
        d = len(S)
        reps = 5 if quick else 25
        plain, exact, fd, full = _median_interleaved(
            [lambda P=P, x=x: P(x),
             lambda P=P, x=x: np.linalg.eigvals(P.section_jacobian(x, "exact")[0]),
             lambda P=P, x=x: np.linalg.eigvals(P.section_jacobian(x, "fd")[0]),
             lambda P=P, x=x: P.derivatives(x)], reps)
        r_exact, r_fd, r_full = exact.median / plain.median, fd.median / plain.median, full.median / plain.median
        rows.append([name, d, f"{plain.median * 1e3:.3f}", f"{r_exact:.2f}", f"{r_full:.2f}", f"{r_fd:.2f}", 2 * d + 1,
                     f"{r_fd / r_exact:.1f}"])
        data[name] = {"section_dim": d, "plain_s": plain.median, "exact_ratio": r_exact, "fd_ratio": r_fd,
                      "derivatives_ratio": r_full}
        goals.append(Goal(f"exact Jacobian + multipliers, {name}", f"≤ {GOAL_RATIO:g}× one return map",
                          f"{r_exact:.2f}×", r_exact <= GOAL_RATIO))
        goals.append(Goal(f"exact Jacobian vs central differences, {name}", "≤ 1× central differences",
                          f"{r_exact / r_fd:.2f}×", r_exact <= r_fd))
    md = (__doc__ or "").strip() + "\n\n" + table(
        ["model", "section dim d", "return map (ms)", "exact Jacobian (÷ map)", "∂P/∂x alone (÷ map)",
         "central differences (÷ map)", "differences: runs", "exact is faster by"], rows)
    return Section("Return-map Jacobian: exact vs central differences", md, goals, data)


if __name__ == "__main__":
    sec = run()
    print(sec.markdown)
    for g in sec.goals:
        print(f"{g.name}: {g.measured} (target {g.target}) {'met' if g.met else 'MISSED'}")
