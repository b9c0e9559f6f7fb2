"""``amble gaits``: every gait of period up to K that a seeded, deflated search finds at one set of
parameters, stable and unstable."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..analysis.defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .args import UsageError, _float, load_model, parse_sets

EXAMPLE = "amble gaits simplest-walker --set slope=0.009 --json"
#: Largest ``--period``: each period is a search of its own from every seed.
MAX_PERIOD = 16


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    g = add("gaits", "every gait of period 1..K found at these parameters (stable and unstable): seeds on the "
                     "post-impact section, Newton with deflation of the gaits already found")
    model_arg(g)
    g.add_argument("--period", type=int, default=None,
                   help=f"K: search periods 1..K, in footfalls (default: the footfalls until the walker is back in "
                        f"its first mode, 1 for most walkers, 2 when its stance feet are modes; at most {MAX_PERIOD})")
    g.add_argument("--tol", type=float, default=RESIDUAL_TOL,
                   help=f"largest residual |P(x) - x| of a gait returned (default {RESIDUAL_TOL:g})")
    g.add_argument("--seeds", type=int, default=24, help="seeds around the model's gait besides it (default 24)")
    g.add_argument("--spread", type=float, default=0.3,
                   help="half-width of the seed box, relative to the section coordinates (default 0.3)")
    g.add_argument("--seed", type=int, default=0, help="seed of the seed set's random shift (default 0)")
    g.add_argument("--guess", action="append", metavar="x0=V1,V2,...",
                   help="a full post-impact state (state_names order) to try first (repeatable)")
    g.add_argument("--rtol", type=float, default=FIXED_POINT_TOL,
                   help=f"relative integration tolerance (default {FIXED_POINT_TOL:g})")
    g.add_argument("--atol", type=float, default=FIXED_POINT_TOL,
                   help=f"absolute integration tolerance (default {FIXED_POINT_TOL:g})")
    g.set_defaults(func=cmd_gaits)


def _guess(text: str) -> list[float]:
    if not text.startswith("x0="):
        raise UsageError(f"--guess expects 'x0=V1,V2,...', got {text!r}")
    vals = [v for v in text[3:].split(",")]
    if vals and not vals[-1].strip():
        vals = vals[:-1]
    if not vals or any(not v.strip() for v in vals):
        raise UsageError(f"--guess: an empty value in {text!r}")
    return [_float(v, "--guess") for v in vals]


def cmd_gaits(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.gaits import find_gaits

    if args.period is not None and not 1 <= args.period <= MAX_PERIOD:
        raise UsageError(f"--period must be at least 1 and at most {MAX_PERIOD}, got {args.period}")
    if not (args.tol > 0 and args.rtol > 0 and args.atol > 0):
        raise UsageError(f"--tol, --rtol and --atol must be positive, got {args.tol:g}, {args.rtol:g}, {args.atol:g}")
    if args.seeds < 0:
        raise UsageError(f"--seeds must be at least 0, got {args.seeds}")
    if not args.spread >= 0:
        raise UsageError(f"--spread must be at least 0, got {args.spread}")
    guesses = [_guess(t) for t in args.guess or []]
    system = load_model(args.model, compiled=True, derivatives=True)
    found = find_gaits(system, params=parse_sets(args.set), period=args.period, tol=args.tol, seeds=args.seeds,
                       guesses=guesses, spread=args.spread, seed=args.seed, rtol=args.rtol, atol=args.atol)
    if not args.json:
        unit = getattr(system, "time_unit", "s")
        print(f"{system.name}: {len(found)} gait{'' if len(found) == 1 else 's'} of period 1..{found.max_period} "
              f"({found.seeds} seeds; Newton runs: {found.fell} fell, {found.diverged} did not converge)")
        for i, g in enumerate(found, 1):
            times = ", ".join(f"{t:.6g}" for t in g.step_times) if g.period > 1 else f"{g.step_time:.6g}"
            print(f"{i}. {'stable' if g.stable else 'UNSTABLE'} period-{g.period} gait, step time {times} {unit}, "
                  f"max |multiplier| {max(abs(m) for m in g.multipliers):.5f}")
            print("   fixed point: " + ", ".join(f"{n}={v:.9g}" for n, v in zip(g.state_names, g.fixed_point)))
    return found.to_json()
