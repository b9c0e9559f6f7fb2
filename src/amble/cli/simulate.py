"""``amble simulate``: one run of a model (:func:`amble.simulation.simulate.simulate`) from its
start, for N footfalls or T seconds, plus its summary, samples file, plot and animation."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..models import LIMIT_ACTIONS
from ..simulation.engine import METHODS, NEEDS_JACOBIAN, Options
from .animation import SERIES_HELP, drawing_outputs, write_animation
from .args import UsageError, load_model, parse_sets, parse_start, robot_options, writable_path
from .gait_file import gait_start
from .output import write_output

EXAMPLE = "amble simulate compass-gait --steps 30 --set slope=0.06 --json --animate walk.html"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_args: Callable[[argparse.ArgumentParser, float | None], None]) -> None:
    s = add("simulate", "simulate a model for N steps or T seconds")
    model_args(s, Options().rtol)
    g = s.add_mutually_exclusive_group()
    g.add_argument("--steps", type=int, help="number of footfalls (default 20)")
    g.add_argument("--time", type=float, help="end time in seconds (default for a system without footfalls: 1)")
    s.add_argument("--start", help="'fixed-point' or 'x0=V1,V2,...' (full state, state_names order)")
    s.add_argument("--gait", metavar="FILE.json", help="start on a designed gait (amble optimize-gait --out): its "
                   "fixed point and parameters, its controller's included (--set overrides)")
    s.add_argument("--out", help="write samples to FILE.csv|.parquet|.npz")
    s.add_argument("--plot", help="write a time-series plot FILE.png|.svg|.pdf")
    s.add_argument("--animate", help="write an animation FILE.html (3D, offline)|.gif|.mp4")
    s.add_argument("--series", action="append", metavar="[TITLE=]NAME,...", help=SERIES_HELP)
    s.add_argument("--limits", choices=LIMIT_ACTIONS, default="ignore",
                   help="what a joint reaching a limit of its range (a URDF joint limit, an MJCF range) does: "
                        "ignore (default: it passes, as if unlimited) or stop (the run ends there, status "
                        "joint_limit, reporting the coordinate, the bound and the time; in --json the field 'limit'), "
                        "e.g. amble simulate tests/data/pendulum.urdf --fixed-base --limits stop")
    s.add_argument("--method", choices=METHODS, default="dop853",
                   help="integrator: dop853 (explicit, default), radau (implicit, for stiff models) or "
                        "tsit5 (explicit, 5th order)")
    s.set_defaults(func=cmd_simulate, plots_in_process=True)


def cmd_simulate(args: argparse.Namespace) -> dict[str, Any]:
    from ..simulation.simulate import simulate

    out_p = writable_path(args.out, (".csv", ".parquet", ".npz"), "--out")
    plot_p, anim_p, series = drawing_outputs(args)
    most = Options().max_events  # a run ends at this many events whatever --steps asks
    if args.steps is not None and not 1 <= args.steps <= most:
        raise UsageError(f"--steps must be at least 1 and at most {most}, got {args.steps}")
    if args.time is not None and not args.time > 0:
        raise UsageError(f"--time must be positive, got {args.time}")
    drawn = bool(plot_p or anim_p)
    derivatives = args.start == "fixed-point" or NEEDS_JACOBIAN[args.method]
    s = load_model(args.model, compiled=not drawn, derivatives=derivatives, limits=args.limits,
                   **robot_options(args))
    if out_p and (any(m.inputs for m in s.modes.values()) or getattr(s, "hip", None) is not None):
        s = s.symbolic()  # the inputs and the ground reaction written per sample come from the symbolic model
    if args.gait is not None and args.start is not None:
        raise UsageError("give --start or --gait, not both")
    params = parse_sets(args.set)
    x0 = parse_start(s, args.start, params, "--start")
    if args.gait is not None:
        x0, designed = gait_start(s, args.gait)
        params = {**designed, **params}
    t_end, steps = args.time, args.steps
    if steps is None and t_end is None:  # 20 footfalls; a system that makes none runs for a second
        walks = any(tr.step for tr in s.transitions)
        steps, t_end = (20, None) if walks else (None, 1.0)
    # samples are recorded only for an output that shows them: a summary needs the events alone
    tr = simulate(s, x0, params=params, steps=steps, t_end=t_end, rtol=args.rtol, atol=args.atol,
                  sample_dt=1.0 / 200, samples=bool(out_p or plot_p or anim_p), method=args.method)
    summary = tr.summary()
    if args.limits != "ignore":
        summary["limit"] = _limit_reached(tr)
    if out_p:
        from ..analysis.trajectory_physics import physics_columns

        # the file holds the physics as well as the states: ground reaction, friction ratio, work
        extra = physics_columns(tr)
        write_output(out_p, lambda part: tr.save(part, extra=extra), "--out")
        summary["out"] = str(out_p)
    if plot_p:
        from ..viz.plot import plot_trajectory

        write_output(plot_p, lambda part: plot_trajectory(tr, part), "--plot")
        summary["plot"] = str(plot_p)
    if anim_p:
        write_animation(tr, anim_p, series)
        summary["animation"] = str(anim_p)
    if not args.json:
        print(f"{args.model}: {tr.status} — {tr.message}")
        hit = summary.get("limit")
        if hit is not None:
            print(f"joint limit: {hit['coordinate']} reached its {hit['bound']} limit at t = {hit['t']:.12g} s "
                  f"({hit['coordinate']} = {hit['position']:.12g})")
        post = summary["final_post_impact_state"]
        if post is not None:
            print("post-impact state: " + ", ".join(f"{n}={v:.6g}" for n, v in zip(summary["state_names"], post)))
        for k in ("out", "plot", "animation"):
            if k in summary:
                print(f"wrote {summary[k]}")
    return summary



def _limit_reached(tr: Any) -> dict[str, Any] | None:
    """The joint limit a run ended at (``--limits stop``): the coordinate, the bound (``lower``
    or ``upper``), the event time ``t`` (s) and the coordinate's value there; ``None`` if the
    run ended otherwise."""
    from ..modelling.limits import STATUS, limit_of

    if tr.status != STATUS or not len(tr.events):
        return None
    event = tr.events[-1]
    hit = limit_of(event.name)
    if hit is None:
        return None
    coordinate, bound = hit
    position = float(event.x_pre[tr.state_names(event.source).index(coordinate)])
    return {"coordinate": coordinate, "bound": bound, "t": float(event.t), "position": position,
            "transition": event.name}

