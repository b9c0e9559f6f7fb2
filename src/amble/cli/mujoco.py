"""``amble mujoco``: a planar biped's controlled gait replayed in MuJoCo on soft ground, with the drift
from amble's own run per step."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..analysis.defaults import MUJOCO_CONTACT_TIME as CONTACT_TIME
from ..analysis.defaults import MUJOCO_TIMESTEP as TIMESTEP
from .args import UsageError, _float, load_model, parse_sets, writable_path
from .output import write_output

EXAMPLE = "amble mujoco rabbit --steps 10 --mjcf rabbit.xml --json"


def add_parser(add: Callable[[str, str], argparse.ArgumentParser],
               model_arg: Callable[[argparse.ArgumentParser], None]) -> None:
    m = add("mujoco", "replay a planar biped's controlled gait in MuJoCo (soft contact) and report the drift from "
                      "amble's run per step: step time, step length, angle RMS (RABBIT's layout; needs 'mujoco')")
    model_arg(m)
    m.add_argument("--steps", type=int, default=10, help="footfalls to walk (default 10)")
    m.add_argument("--start", metavar="x0=V1,V2,...",
                   help="post-impact state, state_names order (default: the model's start)")
    m.add_argument("--timestep", type=float, default=TIMESTEP, help=f"MuJoCo's step in s (default {TIMESTEP:g})")
    m.add_argument("--contact-time", type=float, default=CONTACT_TIME,
                   help=f"time constant of the soft contact in s, at least two timesteps; smaller is stiffer "
                        f"(default {CONTACT_TIME:g})")
    m.add_argument("--friction", type=float, default=1.0, help="friction coefficient of foot and floor (default 1)")
    m.add_argument("--mjcf", metavar="FILE.xml", help="also write the exported MuJoCo model to FILE.xml")
    m.set_defaults(func=cmd_mujoco)


def _state(text: str) -> list[float]:
    if not text.startswith("x0="):
        raise UsageError(f"--start expects 'x0=V1,V2,...', got {text!r}")
    vals = text[3:].split(",")
    if vals and not vals[-1].strip():
        vals = vals[:-1]  # a trailing comma is harmless
    if not vals or any(not v.strip() for v in vals):
        raise UsageError(f"--start: an empty value in {text!r}")
    return [_float(v, "--start") for v in vals]


def cmd_mujoco(args: argparse.Namespace) -> dict[str, Any]:
    from ..analysis.mujoco_replay import replay_in_mujoco

    if not 1 <= args.steps <= 10000:
        raise UsageError(f"--steps must be at least 1 and at most 10000, got {args.steps}")
    x0 = None if args.start is None else _state(args.start)
    mjcf = writable_path(args.mjcf, (".xml",), "--mjcf")
    system = load_model(args.model)
    params = parse_sets(args.set)
    r = replay_in_mujoco(system, args.steps, params=params, x0=x0,
                         timestep=args.timestep, contact_time=args.contact_time, friction=args.friction)
    out = r.to_json()
    if mjcf:
        write_output(mjcf, lambda part: part.write_text(r.mjcf, encoding="utf-8"), "--mjcf")
        out["mjcf"] = str(mjcf)
    if not args.json:
        s = r.summary()
        print(f"{system.name} in MuJoCo: {r.status}, {r.steps} steps in {r.time:.4g} s")
        if s:
            print(f"  drift from amble, worst step: step time {s['max_step_time_error'] * 1e3:.3g} ms, step length "
                  f"{s['max_step_length_error'] * 1e3:.3g} mm, angle RMS {s['max_angle_rms']:.3g} rad")
            print(f"  stance foot: slip {s['max_stance_slip'] * 1e3:.3g} mm, sinks {s['max_penetration'] * 1e3:.3g} mm;"
                  f" inputs clipped {r.saturated_time * 1e3:.3g} ms (law's largest {r.max_input:.4g} N·m)")
        print("  step  time [s] (amble)   length [m] (amble)   angle RMS [rad]   max |y| [rad]")
        for d in r.drift:
            print(f"  {d.step:4d}  {d.step_time:.4f} ({d.amble_step_time:.4f})   {d.step_length:.4f} "
                  f"({d.amble_step_length:.4f})     {d.angle_rms:.4f}            {d.max_output:.4f}")
    return out
