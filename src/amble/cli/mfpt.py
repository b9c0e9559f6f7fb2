"""``amble mfpt``: how many steps a walker takes on rough terrain before it falls."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from .args import UsageError, load_model, parse_sets

EXAMPLE = "amble mfpt rimless-wheel --terrain 'slope~normal(0.08,0.03)' --runs 2000 --json"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    m = add("mfpt", "mean first-passage time to a fall on terrain drawn anew for every step (Monte Carlo)")
    model_arg(m)
    m.add_argument("--terrain", action="append", required=True, metavar="NAME~normal(MEAN,SD)",
                   help="a parameter drawn for every step: NAME~normal(MEAN,SD) or NAME~uniform(LOW,HIGH) "
                        "(repeatable); e.g. slope~normal(0.08,0.02): each step on its own ramp")
    m.add_argument("--runs", type=int, default=1000, help="walkers (default 1000)")
    m.add_argument("--max-steps", type=int, default=1000, help="steps a walker walks at most (default 1000)")
    m.add_argument("--seed", type=int, default=0, help="seed of the terrain's draws (default 0)")
    m.add_argument("--threads", type=int, default=1, help="threads the walkers share (default 1)")
    m.add_argument("--method", choices=("montecarlo",), default="montecarlo", help="estimator (default montecarlo)")
    m.set_defaults(func=cmd_mfpt)


def cmd_mfpt(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.mfpt import Terrain, mfpt

    for name in ("runs", "max_steps", "threads"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")
    terrain = Terrain.parse(args.terrain)
    system = load_model(args.model)
    r = mfpt(system, terrain, runs=args.runs, max_steps=args.max_steps, seed=args.seed,
             params=parse_sets(args.set), threads=args.threads)
    if not args.json:
        censored = f", {r.censored} still walking after {args.max_steps} steps" if r.censored else ""
        print(f"{system.name}: mean first-passage time {r.mfpt:.4g} steps "
              f"({r.confidence:.0%} interval {r.ci_low:.4g}–{r.ci_high:.4g}; {r.falls} falls in {r.steps} steps "
              f"of {r.runs} walkers{censored})")
    return r.to_json()
