"""Calls from Python: the cost of one per-state kernel call (``Kernels.rhs`` and the others) beside
Pinocchio's ``pin.aba`` binding, and of a batch of states in one call.

Every time is a median over ``REPEATS`` repetitions of a tight Python loop over ``STATES`` random
states (per call: loop time / calls), the candidates interleaved within each repetition so that
load on the machine falls on all of them alike; minima beside. *Overhead* = the Python call −
the same kernel timed in a C loop over the same states (``benchmarks.bench_tree``'s timer,
compiled here), i.e. what the call from Python adds to the compiled work.

- Compass gait (4 states, 6 parameters): every per-state call; the kernels are a few dozen
  flops, so a call's time is nearly all overhead. *Typed pointers* is the loader's earlier
  way, reproduced here: ``np.ascontiguousarray`` of the state, a zeroed output, and three
  ``ndarray.ctypes.data_as`` pointers per call.
- 12-DOF biped (``tests/data/biped12.urdf``): ``Kernels.rhs`` (q̈ from M, h and a Cholesky
  solve) beside ``pin.aba`` on the same model and states, and the Pinocchio binding's own
  overhead (``aba`` of a 1-joint model), measured in the same run.
- Batched: ``Kernels.rhs_many`` over 1000 states in one call, per state.

Run alone: ``python -m benchmarks --only calls --no-write`` or ``python -m benchmarks.bench_calls``.
"""

from __future__ import annotations

import ctypes
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmarks.common import Goal, Section, table

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
STATES = 64
REPEATS = 7
GOAL_US = 3.0  # overhead of a per-state call from Python

_D = ctypes.POINTER(ctypes.c_double)


def _loop(fn: Callable, args: list, reps: int) -> float:
    """Seconds per call of ``fn(*a)`` in a tight loop cycling through ``args``."""
    k = len(args)
    t0 = time.perf_counter()
    for r in range(reps):
        fn(*args[r % k])
    return (time.perf_counter() - t0) / reps


def _interleaved(cands: dict[str, tuple[Callable, list]], reps: int, repeats: int) -> dict[str, dict[str, float]]:
    """Per candidate: median and minimum seconds per call, the candidates timed in turn in each
    repetition."""
    samples: dict[str, list[float]] = {name: [] for name in cands}
    for fn, args in cands.values():
        fn(*args[0])  # warm
    for _ in range(repeats):
        for name, (fn, args) in cands.items():
            samples[name].append(_loop(fn, args, reps))
    return {name: {"median": statistics.median(s), "min": min(s)} for name, s in samples.items()}


def _typed_pointer_rhs(k):
    """``Kernels.rhs`` as the loader called it before (typed pointers built per call)."""
    lib = ctypes.CDLL(str(k.path))
    f = lib.amble_rhs
    f.restype, f.argtypes = ctypes.c_int, [ctypes.c_int, ctypes.c_double, _D, _D, _D]
    nx = k.meta["nx"]

    def rhs(mode, t, x, p):
        x = np.ascontiguousarray(x, dtype=float).ravel()
        if x.shape != (nx[mode],):
            raise ValueError("state size")
        dx = np.zeros_like(x)
        if f(mode, float(t), x.ctypes.data_as(_D), p.ctypes.data_as(_D), dx.ctypes.data_as(_D)):
            raise ValueError("singular")
        return dx
    return rhs


def _c_rhs_seconds(k, xs: np.ndarray, p: np.ndarray) -> float:
    """Seconds per ``amble_rhs`` call in a C loop over the rows of ``xs`` (median of 5)."""
    from benchmarks.bench_tree import _timer

    n = xs.shape[1] // 2
    flat, dx, sink = np.ascontiguousarray(xs), np.zeros(2 * n), ctypes.c_double()
    with tempfile.TemporaryDirectory() as tmp:
        timer = _timer(Path(tmp))
        fptr = ctypes.cast(k._lib.amble_rhs, ctypes.c_void_p)
        a = lambda v: ctypes.c_void_p(v.ctypes.data)  # noqa: E731
        reps = max(20000, int(4e6 / (n * n)))
        return statistics.median(timer.amble_bench_rhs(fptr, 0, n, len(xs), a(flat), a(p), a(dx), ctypes.c_long(reps),
                                                       ctypes.byref(sink)) for _ in range(5))


def _compass(quick: bool) -> tuple[list[list[str]], dict]:
    from amble.backend.kernels import compiled
    from amble.models import load

    k = compiled(load("compass-gait"), derivatives=True)
    p = np.array(k.meta["param_defaults"])
    xs = np.random.default_rng(0).uniform(-0.5, 0.5, (STATES, 4))
    one = [(0, 0.0, x, p) for x in xs]
    cands = {
        "rhs, typed pointers (before)": (_typed_pointer_rhs(k), one),
        "rhs": (k.rhs, one),
        "dynamics (M, h, Γ)": (k.dynamics, one),
        "guards": (k.guards, one),
        "reset": (k.reset, one),
        "rhs_jacobian (f, ∂f/∂x, ∂f/∂p)": (k.rhs_jacobian, one),
        "surface_gradients": (k.surface_gradients, one),
        "reset_jacobian": (k.reset_jacobian, one),
    }
    got = _interleaved(cands, 5000 if quick else 20000, 3 if quick else REPEATS)
    c = _c_rhs_seconds(k, xs, p)
    rows = [[name, f"{s['median'] * 1e6:.2f}", f"{s['min'] * 1e6:.2f}"] for name, s in got.items()]
    return rows, {"calls": got, "rhs_c_s": c}


def _biped(quick: bool) -> tuple[list[list[str]], dict]:
    from amble import HybridSystem, Model
    from amble.backend.kernels import compiled

    m = Model.from_urdf(DATA / "biped12.urdf")
    k = compiled(HybridSystem(m.name, m))
    n = len(m.q)
    rng = np.random.default_rng(1)
    xs = rng.uniform(-1.0, 1.0, (STATES, 2 * n))
    p = np.zeros(max(len(k.meta["params"]), 1))
    cands = {"amble Kernels.rhs": (k.rhs, [(0, 0.0, x, p) for x in xs])}
    X = rng.uniform(-1.0, 1.0, (1000, 2 * n))
    many = lambda X: k.rhs_many(0, 0.0, X, p)  # noqa: E731
    try:
        import pinocchio as pin
    except ImportError:
        pin = None
    if pin is not None:
        pm = pin.buildModelFromUrdf(str(DATA / "biped12.urdf"))
        pd, tau = pm.createData(), np.zeros(n)
        cands["Pinocchio pin.aba"] = (lambda q, v: pin.aba(pm, pd, q, v, tau),
                                      [(x[:n].copy(), x[n:].copy()) for x in xs])
        one = pin.Model()
        one.appendBodyToJoint(one.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "j"),
                              pin.Inertia.Random(), pin.SE3.Identity())
        od, z = one.createData(), np.zeros(1)
        cands["Pinocchio binding (1-joint aba)"] = (lambda: pin.aba(one, od, z, z, z), [()])
    got = _interleaved(cands, 3000 if quick else 20000, 3 if quick else REPEATS)
    batch = [_loop(many, [(X,)], 3 if quick else 20) / len(X) for _ in range(3 if quick else REPEATS)]
    got["amble Kernels.rhs_many, per state (1000 per call)"] = {"median": statistics.median(batch), "min": min(batch)}
    c = _c_rhs_seconds(k, xs, p)
    rows = [[name, f"{s['median'] * 1e6:.2f}", f"{s['min'] * 1e6:.2f}"] for name, s in got.items()]
    return rows, {"calls": got, "rhs_c_s": c, "pin_version": getattr(pin, "__version__", None), "n": n}


def run(quick: bool = False) -> Section:
    crow, cdata = _compass(quick)
    brow, bdata = _biped(quick)
    cc, bc = cdata["calls"], bdata["calls"]
    over = {name: s["median"] - cdata["rhs_c_s"] for name, s in cc.items()}
    b_over = bc["amble Kernels.rhs"]["median"] - bdata["rhs_c_s"]
    pin_bind = bc.get("Pinocchio binding (1-joint aba)")
    md = ["Compass gait (4 states), µs per call from Python; the kernels themselves take "
          f"{cdata['rhs_c_s'] * 1e6:.3f} µs (`amble_rhs` in a C loop):", "",
          table(["call", "median µs", "min µs"], crow), "",
          f"12-DOF biped (URDF), µs per call; amble's `amble_rhs` in a C loop: {bdata['rhs_c_s'] * 1e6:.2f} µs, "
          f"so the call from Python adds {b_over * 1e6:.2f} µs"
          + (f" (Pinocchio's binding: {pin_bind['median'] * 1e6:.2f} µs, measured in the same run)" if pin_bind
             else "") + ":", "",
          table(["call", "median µs", "min µs"], brow)]
    if "Pinocchio pin.aba" in bc:
        r = bc["amble Kernels.rhs"]["median"] / bc["Pinocchio pin.aba"]["median"]
        md += ["", f"amble `Kernels.rhs` / `pin.aba` from Python, same states, same run: {r:.2f}×"
                   + (f" (Pinocchio {bdata['pin_version']})." if bdata["pin_version"] else ".")]
    goals = [Goal(f"per-state call overhead from Python, {name.split(' (')[0]} (compass gait)", f"≤ {GOAL_US:g} µs",
                  f"{over[name] * 1e6:.2f} µs", over[name] * 1e6 <= GOAL_US)
             for name in cc if "before" not in name]
    goals.append(Goal("per-state call overhead from Python, rhs (12-DOF biped)", f"≤ {GOAL_US:g} µs",
                      f"{b_over * 1e6:.2f} µs", b_over * 1e6 <= GOAL_US))
    return Section("Calls from Python", "\n".join(md), goals, {"compass": cdata, "biped12": bdata})


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    s = run(quick=ap.parse_args().quick)
    print(s.markdown)
    for g in s.goals:
        print(f"{g.name}: {g.measured} ({g.target}) {'met' if g.met else 'MISSED'}")


if __name__ == "__main__":
    main()
