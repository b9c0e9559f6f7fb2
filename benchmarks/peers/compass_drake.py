"""Compass-gait walker simulated by Drake (``pydrake.examples.CompassGait``).

Drake's own hybrid system is used unchanged: its witness function isolates the
foot collision and its unrestricted-update event applies the impact reset.  Two
runs are made per configuration:

* an *accuracy* run with a monitor that stops ``AdvanceTo`` right after each
  isolated foot collision (witness value <= 0); the pending reset is then
  applied with ``Simulator.AdvancePendingEvents`` so the exact pre- and
  post-impact states are recorded,
* *timing* runs without any monitor: one ``AdvanceTo`` call up to just past
  the N-th collision time of the accuracy run; the number of walking steps is
  checked with the simulator's count of unrestricted updates.

If ``pydrake`` cannot be imported every public function returns a dict with
``available = False`` and a ``skip_reason`` instead of raising.

Run ``python -m benchmarks.peers.compass_drake`` for a small table.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from benchmarks.peers.compass_scipy import (
    DEFAULT_PARAMS,
    LIMIT_CYCLE_X0,
    collision_dynamics,
    make_dynamics,
    reference,
    state_error,
)

try:  # pragma: no cover - depends on the installation
    from pydrake.examples import CompassGait
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator
    from pydrake.systems.framework import EventStatus

    _IMPORT_ERROR: str | None = None
except Exception as exc:  # noqa: BLE001 - any import failure means "skip"
    _IMPORT_ERROR = f"pydrake not importable: {type(exc).__name__}: {exc}"

#: Integration schemes benchmarked by :func:`main` (Drake's default is
#: ``runge_kutta3``; ``runge_kutta5`` is its highest-order explicit scheme).
SCHEMES: tuple[str, ...] = ("runge_kutta3", "runge_kutta5")

#: Drake's ``SimulatorConfig`` default maximum step size.
DEFAULT_MAX_STEP: float = 0.1

#: Drake's ``SimulatorConfig`` default target accuracy.
DEFAULT_ACCURACY: float = 1e-4


def available() -> tuple[bool, str | None]:
    """Return ``(True, None)`` if pydrake works, else ``(False, reason)``."""
    return _IMPORT_ERROR is None, _IMPORT_ERROR


def drake_version() -> str | None:
    """Installed ``drake`` distribution version, if any."""
    try:
        from importlib.metadata import version

        return version("drake")
    except Exception:  # noqa: BLE001
        return None


def _make_simulator(
    x0: Sequence[float], accuracy: float | None, integrator: str, max_step_size: float
) -> tuple[Any, Any]:
    """Build a fresh ``Simulator`` for ``CompassGait`` starting at ``x0``.

    ``accuracy=None`` uses Drake's ``SimulatorConfig`` default accuracy (1e-4).
    Returns ``(simulator, plant)``.
    """
    plant = CompassGait()
    sim = Simulator(plant)
    ResetIntegratorFromFlags(sim, integrator, max_step_size)
    ctx = sim.get_mutable_context()
    ctx.SetContinuousState(np.asarray(x0, dtype=float))
    accuracy = DEFAULT_ACCURACY if accuracy is None else accuracy
    ctx.SetAccuracy(accuracy)
    sim.get_mutable_integrator().set_target_accuracy(accuracy)
    sim.Initialize()
    return sim, plant


def _skip(reason: str | None, **extra: Any) -> dict[str, Any]:
    """Result dict for an unavailable or failed Drake run."""
    return {"available": False, "skip_reason": reason, **extra}


def simulate(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    accuracy: float | None = 1e-10,
    integrator: str = "runge_kutta3",
    max_step_size: float = DEFAULT_MAX_STEP,
) -> dict[str, Any]:
    """Walk ``steps`` steps with Drake, stopping at every impact to record it.

    Returns a dict with ``available`` (bool), ``skip_reason`` (None),
    ``post_impact_states`` and ``pre_impact_states`` (``steps x 4``, Drake
    state order), ``impact_times`` and ``step_durations`` (``steps``), ``nfev``
    (derivative evaluations) and ``integrator_steps``; or ``available=False``
    with ``skip_reason``.
    """
    ok, reason = available()
    if not ok:
        return _skip(reason)
    x0 = LIMIT_CYCLE_X0 if x0 is None else x0
    sim, plant = _make_simulator(x0, accuracy, integrator, max_step_size)
    slope = DEFAULT_PARAMS["slope"]

    def monitor(context: Any) -> Any:
        """Stop the simulator as soon as the foot-collision witness triggered."""
        x = context.get_continuous_state_vector().CopyToVector()
        if max(2.0 * slope - x[0] - x[1], x[1] - x[0]) <= 0.0:
            return EventStatus.ReachedTermination(plant, "foot collision")
        return EventStatus.Succeeded()

    sim.set_monitor(monitor)
    pre = np.empty((steps, 4))
    post = np.empty((steps, 4))
    times = np.empty(steps)
    for k in range(steps):
        sim.AdvanceTo(times[k - 1] + 10.0 if k else 10.0)
        ctx = sim.get_context()
        if sim.get_num_unrestricted_updates() != k:
            raise RuntimeError(f"step {k}: unexpected number of impacts")
        times[k] = ctx.get_time()
        pre[k] = ctx.get_continuous_state_vector().CopyToVector()
        sim.AdvancePendingEvents()
        if sim.get_num_unrestricted_updates() != k + 1:
            raise RuntimeError(f"step {k}: monitor stopped without a pending impact")
        post[k] = sim.get_context().get_continuous_state_vector().CopyToVector()
    integ = sim.get_integrator()
    return {
        "available": True,
        "skip_reason": None,
        "post_impact_states": post,
        "pre_impact_states": pre,
        "impact_times": times,
        "step_durations": np.diff(times, prepend=0.0),
        "nfev": integ.get_num_derivative_evaluations(),
        "integrator_steps": integ.get_num_steps_taken(),
    }


def walk(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    accuracy: float | None = 1e-10,
    integrator: str = "runge_kutta3",
    max_step_size: float = DEFAULT_MAX_STEP,
    repeats: int = 5,
) -> dict[str, Any]:
    """Time Drake walking ``steps`` steps at target ``accuracy``.

    ``accuracy=None`` uses Drake's default accuracy (1e-4, integrator
    ``runge_kutta3``, max step 0.1: ``SimulatorConfig()``).

    Returns a dict with keys

    * ``available`` (bool) and ``skip_reason`` (str or None),
    * ``time_per_step_s``: median over ``repeats`` (>= 5) of the wall time of a
      monitor-free ``AdvanceTo`` covering ``steps`` impacts, divided by ``steps``,
    * ``min_time_per_step_s``: fastest repeat divided by ``steps``,
    * ``wall_times_s``: every repeat's wall time,
    * ``post_impact_states``, ``pre_impact_states``, ``impact_times``,
      ``step_durations``: from the instrumented run (see :func:`simulate`),
    * ``nfev_per_step``, ``integrator_steps_per_step``: from a timing run,
    * ``steps``, ``accuracy``, ``integrator``, ``max_step_size``, ``repeats``,
      ``drake_version``.
    """
    ok, reason = available()
    if not ok:
        return _skip(reason, integrator=integrator, accuracy=accuracy)
    x0 = LIMIT_CYCLE_X0 if x0 is None else x0
    repeats = max(int(repeats), 5)
    try:
        inst = simulate(x0, steps, accuracy, integrator, max_step_size)
        t_end = inst["impact_times"][-1] + 0.01 * inst["step_durations"][-1]
        walls: list[float] = []
        nfev = nsteps = 0
        for _ in range(repeats):
            sim, _plant = _make_simulator(x0, accuracy, integrator, max_step_size)
            t0 = time.perf_counter()
            sim.AdvanceTo(t_end)
            walls.append(time.perf_counter() - t0)
            if sim.get_num_unrestricted_updates() != steps:
                raise RuntimeError(
                    f"timing run saw {sim.get_num_unrestricted_updates()} impacts, expected {steps}"
                )
            nfev = sim.get_integrator().get_num_derivative_evaluations()
            nsteps = sim.get_integrator().get_num_steps_taken()
    except Exception as exc:  # noqa: BLE001 - report, do not crash the suite
        return _skip(
            f"Drake run failed: {type(exc).__name__}: {exc}",
            integrator=integrator,
            accuracy=accuracy,
        )
    return {
        "available": True,
        "skip_reason": None,
        "time_per_step_s": statistics.median(walls) / steps,
        "min_time_per_step_s": min(walls) / steps,
        "wall_times_s": walls,
        "post_impact_states": inst["post_impact_states"],
        "pre_impact_states": inst["pre_impact_states"],
        "impact_times": inst["impact_times"],
        "step_durations": inst["step_durations"],
        "nfev_per_step": nfev / steps,
        "integrator_steps_per_step": nsteps / steps,
        "steps": steps,
        "accuracy": accuracy,
        "integrator": integrator,
        "max_step_size": max_step_size,
        "repeats": repeats,
        "drake_version": drake_version(),
    }


def consistency(samples: int = 100, seed: int = 0) -> dict[str, Any]:
    """Check that :mod:`compass_scipy` implements Drake's model.

    Compares Drake's ``EvalTimeDerivatives`` with the SciPy peer's vector
    field at random states, and Drake's impact reset (from an instrumented
    walk) with :func:`compass_scipy.collision_dynamics`.  Returns
    ``available``, ``max_xdot_diff`` and ``max_reset_diff`` (max-abs).
    """
    ok, reason = available()
    if not ok:
        return _skip(reason)
    rng = np.random.default_rng(seed)
    plant = CompassGait()
    ctx = plant.CreateDefaultContext()
    fun = make_dynamics()
    dx = 0.0
    for _ in range(samples):
        x = rng.uniform(-1.0, 1.0, 4) * np.array([0.5, 0.5, 3.0, 3.0])
        ctx.SetContinuousState(x)
        xdot = plant.EvalTimeDerivatives(ctx).CopyToVector()
        dx = max(dx, float(np.max(np.abs(xdot - np.asarray(fun(0.0, x))))))
    inst = simulate(LIMIT_CYCLE_X0, 3, 1e-10, "runge_kutta3")
    dr = max(
        float(np.max(np.abs(collision_dynamics(pre) - post)))
        for pre, post in zip(inst["pre_impact_states"], inst["post_impact_states"], strict=True)
    )
    return {"available": True, "skip_reason": None, "max_xdot_diff": dx, "max_reset_diff": dr}


def main(argv: Sequence[str] | None = None) -> None:
    """Print Drake timing and accuracy at the benchmark accuracies."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20, help="walking steps per walk")
    ap.add_argument("--repeats", type=int, default=5, help="timing repeats (>= 5)")
    args = ap.parse_args(argv)

    ok, reason = available()
    if not ok:
        print(f"SKIP compass_drake: {reason}")
        return
    print(f"drake {drake_version()}, {args.steps} steps from the limit cycle")
    cons = consistency()
    print(
        f"model check vs compass_scipy: max |xdot diff| {cons['max_xdot_diff']:.1e}, "
        f"max |reset diff| {cons['max_reset_diff']:.1e}"
    )
    ref = reference(LIMIT_CYCLE_X0, args.steps)
    print(
        f"{'integrator':>13} {'accuracy':>9} {'us/step':>10} {'nfev/step':>10} "
        f"{'final err':>10} {'max err':>10}"
    )
    configs: list[tuple[str, float | None]] = [("runge_kutta3", None)]
    configs += [(s, a) for s in SCHEMES for a in (1e-8, 1e-10)]
    for scheme, acc in configs:
        res = walk(LIMIT_CYCLE_X0, args.steps, acc, scheme, repeats=args.repeats)
        acc_s = "default" if acc is None else f"{acc:.0e}"
        if not res["available"]:
            print(f"{scheme:>13} {acc_s:>9}  SKIP: {res['skip_reason']}")
            continue
        err = state_error(res["post_impact_states"], ref["post_impact_states"])
        print(
            f"{scheme:>13} {acc_s:>9} {res['time_per_step_s'] * 1e6:>10.1f} "
            f"{res['nfev_per_step']:>10.1f} {err['final_error']:>10.2e} "
            f"{err['max_error']:>10.2e}"
        )


if __name__ == "__main__":
    main()
