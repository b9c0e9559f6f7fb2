"""``amble limit-cycle``: the periodic gait (:func:`amble.analysis.poincare.find_fixed_point`), its
step times and Floquet multipliers, the feasibility checks of an actuated gait, a plot and an
animation."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..analysis.defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .animation import SERIES_HELP, drawing_outputs, write_animation
from .args import UsageError, check_tol, load_model, parse_sets, parse_start, robot_options
from .gait_file import gait_start
from .output import gait_check_lines, write_output

EXAMPLE = "amble limit-cycle compass-gait --set slope=0.0525 --plot cycle.png"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_args: Callable[[argparse.ArgumentParser, float | None], None]) -> None:
    lc = add("limit-cycle", "find the periodic gait, its step time and Floquet multipliers")
    model_args(lc, FIXED_POINT_TOL)
    lc.add_argument("--period", type=int, default=None,
                    help="k for a gait of k footfalls (default: the footfalls until the walker is back in its "
                         "first mode, 1 for most walkers, 2 when its stance feet are modes); all k points and "
                         "step times are reported")
    lc.add_argument("--tol", type=float, default=RESIDUAL_TOL,
                    help=f"fixed-point tolerance: the largest residual |P(x) - x| of the gait (default "
                         f"{RESIDUAL_TOL:g}, so that the fixed point is within 1e-10 of the map's)")
    lc.add_argument("--guess", help="'x0=V1,V2,...' initial guess (default: the model's)")
    lc.add_argument("--gait", metavar="FILE.json", help="the limit cycle of a designed gait (amble optimize-gait "
                    "--out): its fixed point as the guess, its parameters, its controller's included (--set overrides)")
    lc.add_argument("--plot", help="write the limit-cycle phase portrait FILE.png|.svg|.pdf")
    lc.add_argument("--animate", help="write an animation of the gait FILE.html|.gif|.mp4")
    lc.add_argument("--series", action="append", metavar="[TITLE=]NAME,...", help=SERIES_HELP)
    lc.set_defaults(func=cmd_limit_cycle, plots_in_process=True)


def cmd_limit_cycle(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.poincare import find_fixed_point

    plot_p, anim_p, series = drawing_outputs(args)
    # the return map's own bound (a period-k search walks k steps per Newton iteration), checked
    # before the model is loaded
    from ..analysis.return_map import MAX_PERIOD

    if args.period is not None and not 1 <= args.period <= MAX_PERIOD:
        raise UsageError(f"--period must be at least 1 and at most {MAX_PERIOD}, got {args.period}")
    # the warm start: the compiled model without SymPy, unless drawing needs the symbolic one
    s = load_model(args.model, compiled=not (plot_p or anim_p), derivatives=True, **robot_options(args))
    if args.gait is not None and args.guess is not None:
        raise UsageError("give --guess or --gait, not both")
    params = parse_sets(args.set)
    guess = parse_start(s, args.guess, params, "--guess") if args.guess else None
    if args.gait is not None:
        guess, designed = gait_start(s, args.gait)
        params = {**designed, **params}
    lc = find_fixed_point(s, guess, params=params, period=args.period, rtol=args.rtol, atol=args.atol,
                          tol=check_tol(args.tol))
    out = lc.to_json()
    if any(getattr(m, "inputs", None) for m in s.modes.values()) and getattr(s, "hip", None) is not None:
        from ..analysis.gait_check import check_gait

        lc.hybrid_system = s.symbolic()  # the checks read the symbolic model (contact forces, the control law)

        # an actuated gait: is it physically feasible (ground reaction, friction, clearance, limits)?
        gait = lc.trajectory(steps=lc.period)
        out["checks"] = check_gait(gait).to_json()
        out["work_per_step"] = {k: float(v.sum()) for k, v in gait.work_per_step().items()}  # J per period
        out["cost_of_transport"] = gait.cost_of_transport()
    if plot_p or anim_p:
        from ..simulation.simulate import simulate

        tr = simulate(s, lc.fixed_point, params=params, steps=max(lc.period, 2) if plot_p and not anim_p else 12,
                      rtol=args.rtol, atol=args.atol, sample_dt=1.0 / 200)
        if plot_p:
            from ..viz.plot import plot_limit_cycle

            write_output(plot_p, lambda part: plot_limit_cycle(tr, part, cycle=lc), "--plot")
            out["plot"] = str(plot_p)
        if anim_p:
            write_animation(tr, anim_p, series)
            out["animation"] = str(anim_p)
    if not args.json:
        unit = s.time_unit
        if lc.requested_period and lc.requested_period != lc.period:
            print(f"{args.model}: the period-{lc.requested_period} search converged to a period-{lc.period} gait")
        print(f"{args.model}: {'stable' if lc.stable else 'UNSTABLE'} period-{lc.period} gait, "
              f"{'mean ' if lc.period > 1 else ''}step time {lc.step_time:.6g} {unit} "
              f"(residual {lc.residual:.1e}, {lc.iterations} iterations)")
        if lc.found_by == "continuation":
            print("found by following the model's gait from its default parameters")
        elif lc.found_by == "collocation":  # not connected to the model's gait: say why the other searches failed
            print(f"found by collocation (Newton from a periodic step solved by the gait optimiser), as the other "
                  f"searches failed: {lc.search_note}")
        if lc.period == 1:
            print("fixed point: " + ", ".join(f"{n}={v:.9g}" for n, v in zip(lc.state_names, lc.fixed_point)))
        else:  # every point of the orbit and the time of every step: the mean alone hides the alternation
            for i, (point, dt) in enumerate(zip(lc.orbit, lc.step_times), 1):
                print(f"point {i}/{lc.period} (step time {dt:.6g} {unit}): "
                      + ", ".join(f"{n}={v:.9g}" for n, v in zip(lc.state_names, point)))
        print("multipliers: " + ", ".join(f"{m.real:+.5f}{m.imag:+.5f}i (|{abs(m):.5f}|)" for m in lc.multipliers))
        if "checks" in out:
            print("\n".join(gait_check_lines(out["checks"], si=unit == "s")))
        for k in ("plot", "animation"):
            if k in out:
                print(f"wrote {out[k]}")
    return out

