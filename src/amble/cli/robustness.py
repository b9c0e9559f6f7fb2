"""``amble robustness``: the gait sensitivity norm of a walker's gait for a one-step disturbance,
and the size of its basin of attraction (distances to the boundary, share of a box)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..analysis.defaults import BASIN_STEPS, RESIDUAL_TOL
from .args import UsageError, _float, check_tol, load_model, parse_sets, parse_start

EXAMPLE = "amble robustness compass-gait --param slope --json"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    r = add("robustness", "gait sensitivity norm for a disturbance of one step, and the basin's size")
    model_arg(r)
    r.add_argument("--param", required=True, metavar="NAME",
                   help="the parameter disturbed for one step, e.g. slope (the ramp of one step)")
    r.add_argument("--guess", metavar="x0=V1,V2,...",
                   help="'x0=V1,V2,...' initial guess of the gait's post-impact state (default: the model's)")
    r.add_argument("--tol", type=float, default=RESIDUAL_TOL,
                   help=f"the gait's fixed-point tolerance |P(x) - x| (default {RESIDUAL_TOL:g})")
    b = r.add_argument_group("basin of attraction (JSON key 'basin')")
    b.add_argument("--direction", action="append", metavar="NAME=V[,NAME=V...]",
                   help="a direction on the section to measure the distance to the basin's boundary along "
                        "(repeatable; default: + and - each section coordinate)")
    b.add_argument("--steps", type=int, default=BASIN_STEPS,
                   help=f"footfalls a perturbed walk has to return to the gait (default {BASIN_STEPS})")
    b.add_argument("--criterion", choices=("converge", "walk"), default="converge",
                   help="inside the basin: the walk returns to the gait (converge, default) or just walks "
                        "--steps footfalls without falling (walk)")
    b.add_argument("--reach", type=float, default=1.0,
                   help="farthest distance sought along a direction, in state units (default 1)")
    b.add_argument("--samples", type=int, default=1000,
                   help="random states of a box around the gait walked for the basin's share (default 1000, 0: none)")
    b.add_argument("--box", default=None, metavar="H|NAME=H[,NAME=H...]",
                   help="half-width of that box: one for every section coordinate, or one per section "
                        "coordinate by name (default: the distances found)")
    b.add_argument("--seed", type=int, default=0, help="seed of the box's samples (default 0)")
    b.add_argument("--threads", type=int, default=1, help="threads the walks share (default 1)")
    b.add_argument("--no-basin", action="store_true", help="the gait sensitivity norm only")
    r.set_defaults(func=cmd_robustness)


def parse_direction(text: str, option: str = "--direction") -> dict[str, float]:
    """``NAME=V[,NAME=V...]`` → a direction (components read with ``float``, never evaluated)."""
    out: dict[str, float] = {}
    for item in text.split(","):
        name, eq, val = item.partition("=")
        if not eq or not name.strip():
            raise UsageError(f"{option} expects NAME=VALUE[,NAME=VALUE...], got {text!r}")
        out[name.strip()] = _float(val.strip(), f"{option} {name.strip()}")
    return out


def parse_box(text: str | None) -> float | dict[str, float] | None:
    """``H`` (every section coordinate) or ``NAME=H[,NAME=H...]`` (each by name)."""
    if text is None:
        return None
    if "=" in text:
        return parse_direction(text, "--box")
    return _float(text.strip(), "--box")


def cmd_robustness(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.basin_measures import basin_measures
    from ..analysis.poincare import find_fixed_point
    from ..analysis.robustness import gait_sensitivity

    dirs = None if args.direction is None else [parse_direction(t) for t in args.direction]
    box = parse_box(args.box)
    system = load_model(args.model, derivatives=True)
    params = parse_sets(args.set)
    guess = parse_start(system, args.guess, params, "--guess")
    lc = find_fixed_point(system, guess, params=params, tol=check_tol(args.tol))
    g = gait_sensitivity(lc, args.param)
    out = g.to_json()
    b = None if args.no_basin else basin_measures(
        lc, dirs, steps=args.steps, criterion=args.criterion, reach=args.reach, samples=args.samples, box=box,
        seed=args.seed, threads=args.threads)
    if b is not None:
        out["basin"] = b.to_json()
    if not args.json:
        print(f"{system.name}: gait sensitivity norm for one step's {args.param}: step time {g.step_time:.4g}, "
              f"post-impact state {g.state:.4g} (per unit of {args.param}; {g.steps} steps summed)")
        if b is not None:
            _print_basin(b)
    return out


def _print_basin(b: Any) -> None:
    for d in b.distances:
        far = f"{d['distance']:.6g} ({d['reason']})" if d["distance"] is not None else f"beyond {d['reach']:g}"
        print(f"  distance to the basin's boundary along {d['name']}: {far}")
    if b.size is not None:
        s = b.size
        print(f"  share of the box in the basin: {s['fraction']:.3f} ({s['ci_low']:.3f}-{s['ci_high']:.3f}, "
              f"{s['samples']} samples)")
