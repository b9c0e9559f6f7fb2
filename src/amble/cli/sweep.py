"""``amble sweep``: the command-line glue between :mod:`amble.cli` and the sweep functions.

Turns the parsed options into one call of :func:`~amble.analysis.sweep.sweep` with the kind of
``--kind``, reads where the gait period-doubles with :func:`~amble.analysis.doubling.period_doubling`
and every fold, flip and torus point a branch crosses with
:func:`~amble.analysis.branch_bifurcations.bifurcations` (a map's curves with
:func:`~amble.analysis.map_bifurcations.map_crossings`), prints a short report (or returns it for
``--json``) and draws the plot. Bad input raises :class:`amble.cli.UsageError` (exit code 2) before any work starts.
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter
from typing import Any

import numpy as np

from ..analysis.basin import BASIN_LABELS, BasinResult
from ..analysis.branch_bifurcations import bifurcations
from ..analysis.continuation_sweep import bifurcation_rows
from ..analysis.defaults import BASIN_STEPS
from ..analysis.doubling import period_doubling
from ..analysis.map_bifurcations import MapCrossing, map_crossings
from ..analysis.sweep import sweep
from ..simulation.engine import Options
from .args import (
    UsageError,
    check_grid_size,
    check_tol,
    load_model,
    parse_range,
    parse_sets,
    robot_options,
    writable_path,
)
from .output import number, write_output


def sweep_cli(args: Any) -> dict[str, Any]:
    """``amble sweep``: fixed-point branch / map, bifurcation diagram or basin of attraction.

    ``args``: the parsed options of the ``sweep`` sub-command (:func:`amble.cli.build_parser`).
    Returns the JSON summary (also printed as text unless ``--json``).
    """
    sets = parse_sets(getattr(args, "set", None))
    basin_kind = args.kind == "basin"
    ranges = _check_grid(args, basin_kind, UsageError)
    for nm in ("rtol", "atol"):
        v = getattr(args, nm, None)
        if v is not None and not (v > 0 and math.isfinite(v)):
            raise UsageError(f"--{nm} must be a positive number, got {v}")
        if v is not None:
            Options(**{nm: v})  # the tolerances' domain, checked once before any work
    tol = getattr(args, "tol", None)
    if tol is not None and args.kind not in ("fixed-point", "continuation"):
        raise UsageError(f"--tol applies to --kind fixed-point and continuation, not {args.kind}")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, got {args.workers}")
    threads = getattr(args, "threads", None)
    if threads is not None and (threads < 1 or not basin_kind):
        raise UsageError(f"--threads must be at least 1, got {threads}" if threads < 1
                         else "--threads applies to --kind basin only")
    out = writable_path(args.out, (".csv", ".parquet"), "--out")
    plot = writable_path(args.plot, (".png", ".svg", ".pdf"), "--plot")
    # the compiled model when the index holds it: no SymPy here, nor in workers it is sent to
    system = load_model(args.model, compiled=True, derivatives=True, **robot_options(args))
    names = [r[0] for r in ranges]
    if basin_kind:
        known = list(system.state_names(system.mode_names[0]))
        for nm in names:
            if nm not in known:
                raise UsageError(f"--x: unknown coordinate {nm!r}; known: {', '.join(known)}")
    else:
        for nm in names:
            if nm in sets:
                raise UsageError(f"parameter {nm!r} is both swept and --set")
    common: dict[str, Any] = dict(params=sets, out=out, scheduler=args.scheduler, workers=args.workers,
                                  progress=not getattr(args, "json", False))
    # a tolerance not given is the kind's own default (amble.analysis.defaults), read by the API
    common.update({nm: getattr(args, nm) for nm in ("rtol", "atol") if getattr(args, nm, None) is not None})
    if tol is not None:
        common["tol"] = check_tol(tol)
    summary: dict[str, Any] = {"model": args.model, "kind": args.kind,
                               ("coordinates" if basin_kind else "parameters"): names,
                               "ranges": [list(r[1:]) for r in ranges], "set": sets, "file": str(out) if out else None}
    t0 = time.perf_counter()
    res = (_run_basin(system, ranges, args, common, summary) if basin_kind
           else _run_parameters(system, ranges, args, common, summary))
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    if common["progress"] and not sys.stderr.isatty():
        # a bar written to a pipe or file ends with a carriage return, not a newline: end its line
        print(file=sys.stderr, flush=True)
    if plot is not None:
        from ..viz import sweep_plots as sp

        draw = (sp.plot_basin if basin_kind else sp.plot_bifurcation if args.kind == "bifurcation"
                else sp.plot_continuation if args.kind == "continuation"
                else sp.plot_branch if len(names) == 1 else sp.plot_parameter_map)
        kw = {"crossings": [MapCrossing(**c) for c in summary["crossings"]]} if "crossings" in summary else {}
        write_output(plot, lambda part: draw(res, part, **kw), "--plot")
        summary["plot"] = str(plot)
    if not getattr(args, "json", False):
        _print(summary, out, plot)
    return summary


def _check_grid(args: Any, basin_kind: bool, usage: type[Exception]) -> list[tuple[str, float, float, int]]:
    """The grid options of the chosen kind, parsed: ``--param`` ranges, or the two ``--x`` ranges
    of a basin (with ``--steps``); options of the other kind are refused rather than ignored."""
    params, xs, steps = args.param or [], getattr(args, "x", None) or [], getattr(args, "steps", None)
    if basin_kind:
        if params:
            raise usage("--kind basin varies initial conditions (--x), not parameters; fix parameters with --set")
        if len(xs) != 2:
            raise usage(f"--kind basin needs exactly two --x NAME=START:STOP:COUNT (coordinates of the "
                        f"post-impact state), got {len(xs)}")
        most = Options().max_events  # a walk ends at this many events whatever --steps asks
        if steps is not None and not 1 <= steps <= most:
            raise usage(f"--steps must be at least 1 and at most {most}, got {steps}")
        ranges = []
        for text in xs:
            try:
                ranges.append(parse_range(text))
            except usage as e:  # the shared parser names --param; say which option was wrong
                raise usage(str(e).replace("--param", "--x")) from None
        if ranges[0][0] == ranges[1][0]:
            raise usage(f"--x: the two coordinates must differ, got {ranges[0][0]!r} twice")
        check_grid_size([r[3] for r in ranges], "--x")
        return ranges
    if xs or steps is not None:
        raise usage("--x and --steps apply to --kind basin only")
    if not params:
        raise usage(f"--kind {args.kind} needs --param NAME=START:STOP:COUNT (once, or twice for a 2D map)")
    ranges = [continuation_range(t, usage) if args.kind == "continuation" else parse_range(t) for t in params]
    if len(ranges) not in (1, 2):
        raise usage(f"--param: give one (branch) or two (map) parameters, got {len(ranges)}")
    if args.kind in ("bifurcation", "continuation") and len(ranges) != 1:
        raise usage(f"--kind {args.kind} sweeps exactly one --param")
    if len(ranges) == 2 and ranges[0][0] == ranges[1][0]:
        raise usage(f"--param: the two parameters must differ, got {ranges[0][0]!r} twice")
    check_grid_size([r[3] for r in ranges], "--param")
    return ranges


def continuation_range(text: str, usage: type[Exception]) -> tuple[str, float, float, int]:
    """``NAME=START:STOP[:STEPS]`` of ``--kind continuation``: STOP may lie below START (the branch
    is followed downwards); STEPS (default 50) bounds the parameter change per step by
    |STOP − START| / STEPS."""
    name, eq, rng = text.partition("=")
    parts = rng.split(":")
    if not eq or len(parts) not in (2, 3):
        raise usage(f"--kind continuation expects --param NAME=START:STOP[:STEPS], got {text!r}")
    name, a, b, n = parse_range(f"{name}=0:1:{parts[2] if len(parts) == 3 else 50}")
    start, stop = (parse_range(f"{name}={v}:{v}:1")[1] for v in parts[:2])
    if start == stop:
        raise usage(f"--kind continuation needs START ≠ STOP, got {start}:{stop}")
    return name, start, stop, n


def _run_parameters(system: Any, ranges: list[tuple[str, float, float, int]], args: Any, common: dict[str, Any],
                    summary: dict[str, Any]) -> Any:
    """Fixed-point branch, 2D map or bifurcation diagram; fills ``summary``, returns the result."""
    names = [r[0] for r in ranges]
    if args.kind == "continuation":
        kw = {k: v for k, v in common.items() if k not in ("scheduler", "workers")}  # sequential: this process
        res = sweep(system, "continuation", {names[0]: ranges[0][1:3]}, steps=ranges[0][3], **kw)
        summary["bifurcations"] = bifurcation_rows(res)
        pts = [r for r in res.rows if r["row"] == "point" and r["status"] == "ok"]
        summary["branches"] = [{"branch": b, "period": int(rs[0]["period"]), "points": len(rs),
                                "range": [float(rs[0][names[0]]), float(rs[-1][names[0]])],
                                "stable_points": sum(1 for r in rs if r["stable"] == "true"), "end": rs[-1]["reason"]}
                               for b in sorted({int(r["branch"]) for r in pts})
                               for rs in [[r for r in pts if int(r["branch"]) == b]]]
        summary.update(res.counts())
        return _point_summary(res, names, summary)
    res = sweep(system, args.kind, {r[0]: np.linspace(r[1], r[2], r[3]) for r in ranges}, **common)
    if args.kind == "bifurcation":
        summary["first_period_two"] = period_doubling(res)  # where the diagram shows period two
    elif len(names) == 1:
        # the flip located on the branch between the two points that bracket it
        summary["period_doubling"] = period_doubling(res, system, params=common["params"])
        # folds, flips and torus points crossed between neighbouring gaits, each located on the branch
        found = bifurcations(res, system, params=common["params"], **{k: common[k] for k in ("tol",) if k in common})
        summary["bifurcations"] = [{**b.to_json(), names[0]: b.value} for b in found]
        st = [r for r in res.rows if r["status"] == "ok" and r["stable"] == "true"]
        summary["stable_range"] = [float(st[0][names[0]]), float(st[-1][names[0]])] if st else None
    else:
        summary["stable"] = sum(1 for r in res.rows if r["stable"] == "true")
        # the map's bifurcation curves: sign changes between neighbouring cells of one branch
        found = (map_crossings(res, system, params=common["params"], **{k: common[k] for k in ("tol",) if k in common})
                 if res.kind == "fixed-point-map" else [])
        summary["crossings"] = [c._asdict() for c in found]
    summary.update(res.counts())
    return _point_summary(res, names, summary)


def _point_summary(res: Any, names: list[str], summary: dict[str, Any]) -> Any:
    """The counts and the first failures of a sweep over parameters, into ``summary``; returns ``res``."""
    summary.update(points=len(res.rows), computed=res.computed, reused=res.reused, complete=res.complete)
    summary["failures"] = [{**{nm: float(r[nm]) for nm in names}, "reason": r["reason"]}
                           for r in res.rows if r["status"] != "ok"][:20]
    return res


def _run_basin(system: Any, ranges: list[tuple[str, float, float, int]], args: Any, common: dict[str, Any],
               summary: dict[str, Any]) -> BasinResult:
    """Basin of attraction over the two ``--x`` coordinates; fills ``summary``, returns the result."""
    steps = BASIN_STEPS if args.steps is None else args.steps
    over = {r[0]: np.linspace(r[1], r[2], r[3]) for r in ranges}
    res = sweep(system, "basin", over, steps=steps, threads=getattr(args, "threads", None) or 1, **common)
    counts = res.counts()
    cells = res.outcome.size
    done = int(np.sum(res.outcome >= 0))
    summary.update(counts)  # per outcome; "ok" below: cells whose walk ran (converged, fell or not)
    summary.update(steps=steps, fixed_point=res.fixed_point.tolist(), state_names=res.state_names, points=cells,
                   computed=res.computed, reused=done - res.computed, complete=done == cells,
                   ok=done - counts["failed"], failed=counts["failed"])
    a, b = res.names
    bad = np.argwhere(res.outcome == BASIN_LABELS.index("failed"))[:20]
    summary["failures"] = [{a: float(res.a_values[i]), b: float(res.b_values[j]), "reason": str(res.reasons[i, j])}
                           for i, j in bad]
    return res


def _print(summary: dict[str, Any], out: Any, plot: Any) -> None:
    """The text report of a sweep (the ``--json`` summary in a few lines)."""
    if summary["kind"] == "basin":
        over = " × ".join(summary["coordinates"])
        tally = ", ".join(f"{summary[lab]} {lab}" for lab in BASIN_LABELS)
        print(f"{summary['model']}: basin over {over}: {summary['points']} initial states, {tally} "
              f"({summary['seconds']} s)")
    else:
        print(f"{summary['model']}: {summary['kind']} sweep over {' × '.join(summary['parameters'])}: "
              f"{summary['points']} points, {summary['ok']} ok, {summary['failed']} failed ({summary['seconds']} s)")
    p0 = summary["parameters"][0] if summary.get("parameters") else ""
    for key in ("period_doubling", "stable_range", "first_period_two"):
        v = summary.get(key)
        if v is None:  # absent or not found: a line saying "None" tells nothing
            continue
        shown = " → ".join(number(x, 6) for x in v) if isinstance(v, (list, tuple)) else number(v, 8)
        print(f"  {key.replace('_', ' ')}: {p0 + ' = ' if p0 else ''}{shown}")
    p = summary["parameters"][0] if summary.get("parameters") else ""
    for b in summary.get("branches", []):
        print(f"  branch {b['branch']}: period {b['period']}, {p} {b['range'][0]:.6g} → {b['range'][1]:.6g}, "
              f"{b['points']} points ({b['stable_points']} stable); {b['end']}")
    for b in summary.get("bifurcations", []):
        print(_bifurcation_line(b, p))
    if "crossings" in summary:
        tally = Counter(c["kind"] for c in summary["crossings"])
        print("  bifurcation curves: " + (", ".join(f"{k} between {n} pairs of cells" for k, n in sorted(tally.items()))
                                          or "none crossed between cells of one branch"))
    if out is not None:
        print(f"  results: {out}")
    if plot is not None:
        print(f"  plot: {plot}")


def _bifurcation_line(b: dict[str, Any], p: str) -> str:
    """One bifurcation of the report: kind, where, and for a torus point its pair's angle."""
    torus = b["kind"] == "torus"
    on = f" on branch {b['branch']}" if "branch" in b else ""
    line = f"  {'torus (Neimark–Sacker)' if torus else b['kind']}{on} (period {b['period']}) at {p} = {b[p]:.12g}"
    if b.get("located") is False:
        line += " (not located: the nearest point)"
    if torus and b.get("angle") is not None:
        line += (f": a complex pair crosses |μ| = 1 at θ = {b['angle']:.10g} rad (rotation number "
                 f"{b['rotation']:.8g}), {b['direction'] or 'direction unknown'}")
        line += f"; at the {b['resonance']} strong resonance" if b.get("resonance") else ""
    return line


__all__ = ["sweep_cli"]
