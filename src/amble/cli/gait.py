"""``amble optimize-gait``: one API call (:func:`amble.analysis.gait_optimisation.optimize_gait`)
plus input checks and the ``gait.json`` output. Solver progress goes to stderr."""

from __future__ import annotations

import argparse
from typing import Any

from .args import UsageError, _float, load_model, parse_sets, writable_path
from .output import write_output


def parse_bounds(items: list[str] | None) -> dict[str, tuple[float | None, float | None]]:
    """``NAME=LOW:HIGH`` (either side may be empty: unbounded) → ``{name: (low, high)}``."""
    out: dict[str, tuple[float | None, float | None]] = {}
    for item in items or []:
        name, eq, rng = item.partition("=")
        lo, colon, hi = rng.partition(":")
        if not eq or not colon or not name.strip():
            raise UsageError(f"--bound expects NAME=LOW:HIGH, got {item!r}")
        low = _float(lo, f"--bound {name} low") if lo.strip() else None
        high = _float(hi, f"--bound {name} high") if hi.strip() else None
        if low is not None and high is not None and low > high:
            raise UsageError(f"--bound {name}: low {low:g} is above high {high:g}")
        out[name.strip()] = (low, high)
    return out


def _guess(text: str | None) -> Any:
    if text is None or text in ("passive", "stand", "interpolate"):
        return text
    if text.startswith("x0="):
        vals = [v for v in text[3:].split(",")]
        if any(not v.strip() for v in vals):
            raise UsageError(f"--guess: empty value in {text!r}")
        return [_float(v, "--guess x0") for v in vals]
    raise UsageError(f"--guess expects 'passive', 'stand', 'interpolate' or 'x0=V1,V2,...', got {text!r}")


def parse_nodes(text: str) -> list[int]:
    """``N`` or ``N1,N2,...`` (a mesh refinement) → list of interval counts in [2, 2000]."""
    out = []
    for part in text.split(","):
        try:
            k = int(part)
        except ValueError:
            raise UsageError(f"--nodes expects N or N1,N2,... (integers), got {text!r}") from None
        if not 2 <= k <= 2000:
            raise UsageError(f"--nodes: each count must be in [2, 2000], got {k}")
        out.append(k)
    return out


def cmd_optimize_gait(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.gait_optimisation import optimize_gait

    out_p = writable_path(args.out, (".json",), "--out")
    for name in ("speed", "step_length", "mu", "step_time"):
        v = getattr(args, name)
        if v is not None and not v > 0:
            raise UsageError(f"--{name.replace('_', '-')} must be positive, got {v:g}")
    if args.clearance is not None and not args.clearance >= 0:
        raise UsageError(f"--clearance must be ≥ 0, got {args.clearance:g}")
    nodes = parse_nodes(args.nodes)
    if args.bezier_degree is not None and not 1 <= args.bezier_degree <= 20:
        raise UsageError(f"--bezier-degree must be in [1, 20], got {args.bezier_degree}")
    if args.max_iter < 1:
        raise UsageError(f"--max-iter must be at least 1, got {args.max_iter}")
    if args.steps is not None and not 1 <= args.steps <= 8:
        raise UsageError(f"--steps must be in [1, 8], got {args.steps}")
    if args.max_multiplier is not None and not 0 < args.max_multiplier < 1:
        raise UsageError(f"--max-multiplier must be in (0, 1), got {args.max_multiplier:g}")
    bounds = parse_bounds(args.bound)
    guess = _guess(args.guess)
    s = load_model(args.model)
    params = parse_sets(args.set)
    posture = None
    if args.posture is not None:
        vals = args.posture.split(",")
        if any(not v.strip() for v in vals):
            raise UsageError(f"--posture: empty value in {args.posture!r}")
        posture = [_float(v, "--posture") for v in vals]
    gait = optimize_gait(s, params=params, speed=args.speed, step_length=args.step_length, objective=args.objective,
                         nodes=nodes if len(nodes) > 1 else nodes[0], guess=guess, step_time=args.step_time,
                         posture=posture, mu=args.mu,
                         clearance=args.clearance, bounds=bounds, max_iter=args.max_iter, hzd=args.hzd,
                         bezier_degree=args.bezier_degree, progress=not args.quiet, steps=args.steps,
                         max_multiplier=args.max_multiplier)
    if args.max_multiplier is not None and gait.bezier and "params" in gait.bezier:
        from ..analysis.gait_stability import closed_loop_stability

        closed_loop_stability(s, gait)  # the closed loop's own multipliers, independent of the bound's formula
    out = gait.to_json()
    if out_p:
        write_output(out_p, gait.save, "--out")
        out["out"] = str(out_p)
    if not args.json:
        sv = gait.solver
        its, secs = sv.get("iterations_total", sv["iterations"]), sv.get("time_total_s", sv["time_s"])
        print(f"{args.model}: objective {gait.objective_name} {gait.objective:.6g}, step time {gait.step_time:.6g} s, "
              f"step length {gait.step_length:.6g} m, speed {gait.speed:.6g} m/s ({its} iterations, {secs:.2f} s "
              f"in the solver, max violation {gait.max_violation:.1e})")
        print("fixed point: " + ", ".join(f"{n}={v:.9g}" for n, v in zip(gait.state_names, gait.fixed_point)))
        for j, step in enumerate(gait.steps or []):
            print(f"step {j + 1}: step time {step.step_time:.6g} s, step length {step.step_length:.6g} m")
        _print_stability(gait.stability)
        active = [k for k, r in gait.constraints.items() if r["active"]]
        if active:
            print("active constraints: " + ", ".join(active))
        if out_p:
            print(f"wrote {out_p}")
    else:
        out.pop("trajectory")  # the trajectory goes to the file, the summary to stdout
    return out


def _print_stability(st: dict[str, Any] | None) -> None:
    if not st:
        return
    bound = f" (bound {st['max_multiplier']:g})" if st.get("max_multiplier") is not None else ""
    line = f"restricted Poincaré map multiplier δ_zero² {st['restricted_multiplier']:.6g}{bound}"
    cl = st.get("closed_loop")
    if cl and "error" in cl:
        line += f"; closed loop not found: {cl['error']}"
    elif cl:
        line += (f"; closed loop: spectral radius {cl['spectral_radius']:.6g}, next multiplier modulus "
                 f"{(abs(complex(*cl['multipliers'][1])) if len(cl['multipliers']) > 1 else 0.0):.3g}")
    print(line)


def add_parser(add: Any, model_arg: Any) -> None:
    """Register ``optimize-gait`` with the parser (``add(name, help)`` makes a subparser)."""
    o = add("optimize-gait", "design a periodic gait by optimisation (direct collocation through the derived "
                             "impact map; needs the 'optimise' extra, CasADi)")
    model_arg(o)
    pace = o.add_mutually_exclusive_group()
    pace.add_argument("--speed", type=float, help="average speed in m/s (default: free)")
    pace.add_argument("--step-length", type=float, dest="step_length", help="step length in m (default: free)")
    o.add_argument("--objective", default="effort",
                   help="'effort' (∫|u|² dt per m, default), 'cot' (cost of transport) or an integrand in the "
                        "coordinates, velocities, inputs and parameters, integrated per m")
    o.add_argument("--nodes", default="30",
                   help="collocation intervals (default 30), or N1,N2,... to refine the mesh (e.g. 20,60)")
    o.add_argument("--guess", help="'passive' (a passive step: the default without feedback), 'stand' (standing "
                                   "still: the default of a model under feedback), 'interpolate' "
                                   "(posture to relabelled posture) or 'x0=V1,V2,...' (a post-impact state "
                                   "walked one step)")
    o.add_argument("--step-time", type=float, dest="step_time",
                   help="step time in s of a 'stand' or 'interpolate' guess (default 0.5)")
    o.add_argument("--posture", metavar="Q1,Q2,...",
                   help="coordinates of a 'stand' or 'interpolate' guess (default: the model's guess)")
    o.add_argument("--mu", type=float, help="friction coefficient at the stance foot (default: no cone)")
    o.add_argument("--clearance", type=float, help="swing-foot clearance at mid-step in m (default: none)")
    o.add_argument("--bound", action="append", metavar="NAME=LOW:HIGH",
                   help="limits of a coordinate or velocity over the step (repeatable; a side may be empty)")
    o.add_argument("--no-hzd", action="store_false", dest="hzd",
                   help="no virtual constraints, even for a model that declares them")
    o.add_argument("--hzd", action="store_true", default=None,
                   help="make the gait satisfy Bézier virtual constraints (their α are optimised too), so "
                        "that an HZD controller with the exported α reproduces it (default: on for a model "
                        "that declares virtual constraints)")
    o.add_argument("--bezier-degree", type=int, default=None, dest="bezier_degree",
                   help="degree of the Bézier virtual constraints (default: the model's own, else 5)")
    o.add_argument("--max-multiplier", type=float, dest="max_multiplier", metavar="R",
                   help="bound the multiplier δ_zero² of the HZD gait's restricted Poincaré map by R in (0, 1) "
                        "(the closed loop's spectral radius under a fast output controller), then find the "
                        "closed loop's multipliers (a model with its own virtual constraints: its controller "
                        "is compiled once)")
    o.add_argument("--steps", type=int, default=None,
                   help="steps per period (default: one cycle of the walker's modes, 1 for a walker that relabels "
                        "its legs, 2 for one whose stance feet are modes; 2: a two-step gait, each step with its "
                        "own impact)")
    o.add_argument("--max-iter", type=int, default=500, dest="max_iter", help="solver iteration limit (default 500)")
    o.add_argument("--quiet", action="store_true", help="no solver progress on stderr")
    o.add_argument("--out", help="write the gait to FILE.json")
    o.set_defaults(func=cmd_optimize_gait, hzd=None)  # None: the model decides (see optimize_gait)
