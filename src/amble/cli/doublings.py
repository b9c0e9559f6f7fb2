"""``amble doublings``: a walker's period-doubling cascade, branch by branch, with its flips and
Feigenbaum's ratios."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..analysis.defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .args import UsageError, check_tol, load_model, parse_sets, writable_path
from .sweep import continuation_range

EXAMPLE = "amble doublings compass-gait --param slope=0.075:0.088 --levels 4 --plot cascade.png"
#: Deepest cascade asked for: the period-2^(L-1) branch lives in an interval δ^L times smaller.
MAX_LEVELS = 8


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    d = add("doublings", "the period-doubling cascade of the period-1 gait: each branch continued to its first "
                         "flip, then the period-doubled branch switched onto, with the flips and Feigenbaum's ratios")
    model_arg(d)
    d.add_argument("--param", required=True, metavar="NAME=START:STOP[:STEPS]",
                   help="the parameter and its range; STEPS (default 50) bounds the period-1 branch's step "
                        "to |STOP - START| / STEPS")
    d.add_argument("--levels", type=int, default=4,
                   help=f"branches to follow: periods 1, 2, ..., 2^(LEVELS-1) (default 4, at most {MAX_LEVELS})")
    d.add_argument("--tol", type=float, default=RESIDUAL_TOL,
                   help=f"largest residual |P(x) - x| of a gait on a branch (default {RESIDUAL_TOL:g})")
    d.add_argument("--rtol", type=float, default=FIXED_POINT_TOL,
                   help=f"relative integration tolerance (default {FIXED_POINT_TOL:g})")
    d.add_argument("--atol", type=float, default=FIXED_POINT_TOL,
                   help=f"absolute integration tolerance (default {FIXED_POINT_TOL:g})")
    d.add_argument("--coordinate", help="post-impact coordinate drawn by --plot (default: the one that varies most)")
    d.add_argument("--plot", help="write the cascade's diagram FILE.png|.svg|.pdf")
    d.set_defaults(func=cmd_doublings)


def cmd_doublings(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.doublings import period_doublings

    name, start, stop, steps = continuation_range(args.param, UsageError)
    if not 1 <= args.levels <= MAX_LEVELS:
        raise UsageError(f"--levels must be at least 1 and at most {MAX_LEVELS}, got {args.levels}")
    tol = check_tol(args.tol)
    if not (args.rtol > 0 and args.atol > 0):
        raise UsageError(f"--rtol and --atol must be positive, got {args.rtol:g}, {args.atol:g}")
    plot = writable_path(args.plot, (".png", ".svg", ".pdf"), "--plot")
    system = load_model(args.model, compiled=True, derivatives=True)
    params = parse_sets(args.set)
    if name not in system.parameters:
        raise UsageError(f"--param: {name!r} is not a parameter of {system.name} "
                         f"({', '.join(system.parameters)})")
    if name in params:
        raise UsageError(f"--param {name} is swept; do not also --set it")
    cascade = period_doublings(system, name, start, stop, levels=args.levels, params=params,
                               max_delta=abs(stop - start) / steps, rtol=args.rtol, atol=args.atol, tol=tol)
    out = {"model": system.name, **cascade.to_json()}
    if plot is not None:
        from ..viz.cascade_plot import plot_cascade

        out["plot"] = str(plot_cascade(cascade, plot, coordinate=args.coordinate,
                                       title=f"{system.name}: period-doubling cascade in {name}"))
    if not args.json:
        print(f"{system.name}: periods {', '.join(str(p) for p in out['periods'])} in {name} "
              f"from {start:g} to {stop:g} ({cascade.end})")
        for f in out["flips"]:
            located = "" if f["located"] else " (not located to tolerance)"
            print(f"  period {f['period']} doubles at {name} = {f['value']:.12g}{located}")
        for t in out["tori"]:
            res = f"; at the {t['resonance']} strong resonance" if t["resonance"] else ""
            print(f"  torus (Neimark–Sacker) on the period-{t['period']} branch at {name} = {t['value']:.12g}: "
                  f"θ = {t['angle']:.10g} rad (rotation number {t['rotation']:.8g}), {t['direction']}{res}")
        if out["ratios"]:
            print("  Feigenbaum ratios: " + ", ".join(f"{r:.4f}" for r in out["ratios"]) + " (δ → 4.6692)")
        if "plot" in out:
            print(f"  diagram: {out['plot']}")
    return out
