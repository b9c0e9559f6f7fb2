"""``amble mfpt``: how many steps a walker takes on rough terrain before it falls."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .args import UsageError, load_model, parse_sets, writable_path
from .output import write_output

EXAMPLE = "amble mfpt rimless-wheel --terrain 'slope~normal(0.08,0.03)' --runs 2000 --json"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    m = add("mfpt", "mean first-passage time to a fall on terrain drawn anew for every step "
                    "(Monte Carlo or a Markov chain)")
    model_arg(m)
    m.add_argument("--terrain", action="append", required=True, metavar="NAME~normal(MEAN,SD)",
                   help="a parameter drawn for every step: NAME~normal(MEAN,SD) or NAME~uniform(LOW,HIGH) "
                        "(repeatable); e.g. slope~normal(0.08,0.02): each step on its own ramp")
    m.add_argument("--runs", type=int, default=1000, help="montecarlo: walkers (default 1000)")
    m.add_argument("--max-steps", type=int, default=1000,
                   help="montecarlo: steps a walker walks at most (default 1000)")
    m.add_argument("--seed", type=int, default=0, help="montecarlo: seed of the terrain's draws (default 0)")
    m.add_argument("--threads", type=int, default=1, help="threads the walks share (default 1)")
    m.add_argument("--method", choices=("montecarlo", "markov"), default="montecarlo",
                   help="estimator: montecarlo (walkers, a confidence interval) or markov (a chain on a mesh of "
                        "the section, the value at each refinement level; default montecarlo)")
    m.add_argument("--nodes", type=int, default=32, help="markov: terrain nodes per drawn parameter (default 32)")
    m.add_argument("--spacing", type=float, default=0.05,
                   help="markov: finest mesh spacing, relative to the spread of the gait's images (default 0.05)")
    m.add_argument("--levels", type=int, default=3, help="markov: meshes, each spacing half the one before (default 3)")
    m.add_argument("--max-states", type=int, default=20_000, help="markov: mesh states at most (default 20000)")
    m.add_argument("--mesh", choices=("section", "state"), default="section",
                   help="markov: compare mesh states in the chart coordinates of each terrain node's own "
                        "post-impact section (section) or in every state coordinate (state; default section)")
    m.add_argument("--plot", help="markov: draw the metastable distribution on the section to FILE.png|.svg|.pdf")
    m.set_defaults(func=cmd_mfpt)


def cmd_mfpt(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.mfpt import Terrain

    for name in ("runs", "max_steps", "threads", "nodes", "levels"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")
    if args.max_states < 2:
        raise UsageError(f"--max-states must be at least 2, got {args.max_states}")
    if not (math.isfinite(args.spacing) and args.spacing > 0):
        raise UsageError(f"--spacing must be a number > 0, got {args.spacing}")
    if args.plot and args.method != "markov":
        raise UsageError("--plot draws the metastable distribution of --method markov")
    plot_p = writable_path(args.plot, (".png", ".svg", ".pdf"), "--plot")
    terrain = Terrain.parse(args.terrain)
    system = load_model(args.model)
    if args.method == "markov":
        return _markov(args, system, terrain, plot_p)
    from ..analysis.mfpt import mfpt

    r = mfpt(system, terrain, runs=args.runs, max_steps=args.max_steps, seed=args.seed,
             params=parse_sets(args.set), threads=args.threads)
    if not args.json:
        censored = f", {r.censored} still walking after {args.max_steps} steps" if r.censored else ""
        print(f"{system.name}: mean first-passage time {r.mfpt:.4g} steps "
              f"({r.confidence:.0%} interval {r.ci_low:.4g}–{r.ci_high:.4g}; {r.falls} falls in {r.steps} steps "
              f"of {r.runs} walkers{censored})")
    return r.to_json()


def _markov(args: argparse.Namespace, system: Any, terrain: Any, plot_p: Path | None) -> dict[str, Any]:
    from ..analysis.markov import markov_mfpt

    r = markov_mfpt(system, terrain, spacing=args.spacing, levels=args.levels, nodes=args.nodes,
                    max_states=args.max_states, mesh=args.mesh, params=parse_sets(args.set),
                    threads=args.threads)
    out = {**r.to_json(), "state_names": system.state_names()}
    if plot_p:
        from ..viz.metastable import plot_metastable

        write_output(plot_p, lambda part: plot_metastable(r, part, state_names=out["state_names"]), "--plot")
        out["plot"] = str(plot_p)
    if not args.json:
        steps = ", ".join(f"{lv['mfpt']:.4g} ({lv['states']} states{'' if lv['complete'] else ', cut'})"
                          for lv in r.levels)
        print(f"{system.name}: mean first-passage time {r.mfpt:.4g} steps (Markov chain; by refinement: {steps}; "
              f"from the metastable distribution {r.mfpt_eigen:.4g})")
    return out
