"""``amble robustness``: the gait sensitivity norm of a walker's gait for a one-step disturbance."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from .args import load_model, parse_sets

EXAMPLE = "amble robustness compass-gait --param slope --json"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    r = add("robustness", "gait sensitivity norm for a disturbance of one step (exact return-map derivatives)")
    model_arg(r)
    r.add_argument("--param", required=True, metavar="NAME",
                   help="the parameter disturbed for one step, e.g. slope (the ramp of one step)")
    r.set_defaults(func=cmd_robustness)


def cmd_robustness(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.poincare import find_fixed_point
    from ..analysis.robustness import gait_sensitivity

    system = load_model(args.model, derivatives=True)
    lc = find_fixed_point(system, params=parse_sets(args.set))
    g = gait_sensitivity(lc, args.param)
    if not args.json:
        print(f"{system.name}: gait sensitivity norm for one step's {args.param}: step time {g.step_time:.4g}, "
              f"post-impact state {g.state:.4g} (per unit of {args.param}; {g.steps} steps summed)")
    return g.to_json()
