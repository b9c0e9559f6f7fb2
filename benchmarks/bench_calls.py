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
import subprocess
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

_TIMER_C = r"""
#include <time.h>
typedef void (*f1)(int, double, const double *, const double *, double *);
typedef void (*f2)(int, double, const double *, const double *, double *, double *);
typedef void (*f3)(int, double, const double *, const double *, double *, double *, double *);
/* Seconds per call of an entry point with nout output pointers (out, out + o1, out + o2), over
 * reps calls cycling through ns states of nx entries. */
double amble_bench_entry(void *f, int nout, int index, int nx, int ns, const double *xs, const double *p,
                         double *out, long o1, long o2, long reps) {
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (long r = 0; r < reps; ++r) {
        const double *x = xs + (r % ns) * nx;
        if (nout == 1) ((f1)f)(index, 0.0, x, p, out);
        else if (nout == 2) ((f2)f)(index, 0.0, x, p, out, out + o1);
        else ((f3)f)(index, 0.0, x, p, out, out + o1, out + o2);
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    return ((double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec)) / (double)reps;
}
"""


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


def _c_seconds(k, entries: dict[str, tuple[str, int, int, int]], xs: np.ndarray, p: np.ndarray,
               reps: int) -> dict[str, float]:
    """Seconds per call of each entry point (name → (C symbol, outputs, output offsets)) in a C
    loop over the rows of ``xs`` (median of 5)."""
    from amble.backend.cache import cflags, compiler

    flat, out = np.ascontiguousarray(xs), np.zeros(4096)
    a = lambda v: ctypes.c_void_p(v.ctypes.data)  # noqa: E731
    got = {}
    with tempfile.TemporaryDirectory() as tmp:
        src, so = Path(tmp) / "timer.c", Path(tmp) / "timer.so"
        src.write_text(_TIMER_C)
        subprocess.run([*compiler().split(), *cflags(), "-fPIC", "-shared", str(src), "-o", str(so)], check=True)
        timer = ctypes.CDLL(str(so)).amble_bench_entry
        timer.restype = ctypes.c_double
        for name, (sym, nout, o1, o2) in entries.items():
            f = ctypes.cast(getattr(k._lib, sym), ctypes.c_void_p)
            got[name] = statistics.median(
                timer(f, nout, 0, xs.shape[1], len(xs), a(flat), a(p), a(out), ctypes.c_long(o1), ctypes.c_long(o2),
                      ctypes.c_long(reps)) for _ in range(5))
    return got


def _compass(quick: bool) -> dict:
    from amble.backend.kernels import compiled
    from amble.models import load

    k = compiled(load("compass-gait"), derivatives=True)
    p = np.array(k.meta["param_defaults"])
    xs = np.random.default_rng(0).uniform(-0.5, 0.5, (STATES, 4))
    one = [(0, 0.0, x, p) for x in xs]
    nxm, sc = k.nx_max, k.sc
    # name: (the method, its C entry point, outputs, output offsets)
    calls = {"rhs": (k.rhs, "amble_rhs", 1, 0, 0),
             "dynamics": (k.dynamics, "amble_dynamics", 3, 4, 6),
             "guards": (k.guards, "amble_guards", 1, 0, 0),
             "reset": (k.reset, "amble_reset", 2, nxm, 0),
             "rhs_jacobian": (k.rhs_jacobian, "amble_rhs_jac_all", 2, 4, 0),
             "surface_gradients": (k.surface_gradients, "amble_surfaces_grad", 1, 0, 0),
             "reset_jacobian": (k.reset_jacobian, "amble_reset_jac", 1, 0, 0)}
    cands = {"rhs, typed pointers (before)": (_typed_pointer_rhs(k), one)}
    cands.update({name: (c[0], one) for name, c in calls.items()})
    got = _interleaved(cands, 5000 if quick else 20000, 3 if quick else REPEATS)
    c_s = _c_seconds(k, {name: c[1:] for name, c in calls.items()}, xs, p, 200000)
    c_s["rhs, typed pointers (before)"] = c_s["rhs"]
    assert 4 + 4 * sc <= 4096 and nxm * (sc + 1) <= 4096
    return {"calls": got, "c_s": c_s}


def _biped(quick: bool) -> dict:
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
    many = [_loop(lambda: k.rhs_many(0, 0.0, X, p), [()], 3 if quick else 20) / len(X)
            for _ in range(3 if quick else REPEATS)]
    got["amble Kernels.rhs_many, per state (1000 per call)"] = {"median": statistics.median(many), "min": min(many)}
    c_s = _c_seconds(k, {"rhs": ("amble_rhs", 1, 0, 0)}, xs, p, 20000)["rhs"]
    return {"calls": got, "rhs_c_s": c_s, "pin_version": getattr(pin, "__version__", None), "n": n}


def _fixed(quick: bool) -> dict:
    """Fixed cost per call of ``engine.run`` and ``simulate``: a one-step compass-gait walk from its
    fixed-point guess, minus the compiled call of the same run (context reset from a template
    and ``amble_simulate`` called on ready addresses; recording on the 0.01 s grid into ready
    buffers for ``simulate``)."""
    import math

    from amble import simulate
    from amble.backend.abi import CODE, CTX, CTX_X, IOPT, OPT
    from amble.backend.kernels import compiled
    from amble.models import load
    from amble.simulation import engine

    system = load("compass-gait")
    k = compiled(system)
    p = np.array(k.meta["param_defaults"])
    x0 = np.array(system.fixed_point_guess, dtype=float)
    opts = engine.Options()
    start = np.zeros(CTX_X + k.nx_max)
    start[CTX["TPREV_EVENT"]], start[CTX["FRESH"]], start[CTX_X : CTX_X + 4] = -math.inf, 1.0, x0
    ctx = start.copy()
    STEPS_DONE = CODE["STEPS_DONE"]  # noqa: N806

    def compiled_call(sample_dt: float):
        opt, iopt = opts._opt.copy(), opts._iopt.copy()
        opt[OPT["TEND"]], opt[OPT["SAMPLEDT"]], iopt[IOPT["MAXSTEPS"]] = math.inf, sample_dt, 1
        buf = engine._Buffers(engine._first_rows(k.nx_max, engine.RECORD_BUDGET), engine._FIRST_EVENTS, k.nx_max) \
            if sample_dt else engine._NO_RECORDING
        iopt[IOPT["OUTCAP"]], iopt[IOPT["EVCAP"]] = buf.cap, buf.ecap
        addrs = (p.ctypes.data, ctx.ctypes.data, opt.ctypes.data, iopt.ctypes.data, *buf._addresses, None)
        n, ne = buf._counts

        def call(keep=(opt, iopt, buf)):  # the arrays behind the addresses stay alive with the closure
            ctx[:] = start
            n[0] = ne[0] = 0
            code = k.simulate_raw(*addrs)
            assert code == STEPS_DONE, code
        return call

    cands = {"engine.run, 1 step": (lambda: engine.run(k, p, 0, x0, steps=1, opts=opts), [()]),
             "compiled call of that run": (compiled_call(0.0), [()]),
             "simulate, 1 step": (lambda: simulate(system, x0=x0, steps=1), [()]),
             "compiled call of that simulate": (compiled_call(0.01), [()])}
    return _interleaved(cands, 200 if quick else 1000, 3 if quick else REPEATS)


def _cell(s: float) -> str:
    return f"{s * 1e6:.2f}"


def run(quick: bool = False) -> Section:
    cd, bd, fd = _compass(quick), _biped(quick), _fixed(quick)
    cc, bc = cd["calls"], bd["calls"]
    over = {name: s["median"] - cd["c_s"][name] for name, s in cc.items()}
    pin_bind = bc.get("Pinocchio binding (1-joint aba)")
    # the overhead in units of Pinocchio's binding (another run's): load on the machine slows both alike
    per_bind = (lambda v: f"{v / pin_bind['median']:.1f}×") if pin_bind else (lambda v: "—")
    crow = [[name, _cell(s["median"]), _cell(s["min"]), _cell(cd["c_s"][name]), _cell(over[name]),
             per_bind(over[name])] for name, s in cc.items()]
    b_over = bc["amble Kernels.rhs"]["median"] - bd["rhs_c_s"]
    brow = [[name, _cell(s["median"]), _cell(s["min"])] for name, s in bc.items()]
    md = ["Compass gait (4 states, 6 parameters), µs per call from Python; *C* is the same entry point "
          "in a C loop over the same states, *overhead* = median − C, beside the Pinocchio binding's own "
          "cost (the 1-joint `aba` of the biped table):", "",
          table(["call", "median µs", "min µs", "C µs", "overhead µs", "overhead / Pinocchio binding"], crow), "",
          f"12-DOF biped (URDF), µs per call; `amble_rhs` in a C loop takes {_cell(bd['rhs_c_s'])} µs, so "
          f"the call from Python adds {_cell(b_over)} µs"
          + (f" (Pinocchio's binding: {_cell(pin_bind['median'])} µs in the same run)" if pin_bind else "") + ":",
          "", table(["call", "median µs", "min µs"], brow)]
    if "Pinocchio pin.aba" in bc:
        r = bc["amble Kernels.rhs"]["median"] / bc["Pinocchio pin.aba"]["median"]
        md += ["", f"amble `Kernels.rhs` / Pinocchio `pin.aba` from Python, same states, same run: {r:.2f}×"
                   + (f" (Pinocchio {bd['pin_version']})." if bd["pin_version"] else ".")]
    fixed = {"run": fd["engine.run, 1 step"]["median"] - fd["compiled call of that run"]["median"],
             "simulate": fd["simulate, 1 step"]["median"] - fd["compiled call of that simulate"]["median"]}
    md += ["", "Fixed cost per call: a one-step compass-gait walk, µs; *fixed* = the call − its compiled "
               "part (the same run's `amble_simulate` call on ready arrays):", "",
           table(["call", "median µs", "min µs"], [[name, _cell(v["median"]), _cell(v["min"])]
                                                    for name, v in fd.items()]),
           "", f"Fixed cost: `engine.run` {_cell(fixed['run'])} µs, `simulate` {_cell(fixed['simulate'])} µs."]
    goals = [Goal(f"per-state call overhead from Python, {name} (compass gait)", f"≤ {GOAL_US:g} µs",
                  f"{over[name] * 1e6:.2f} µs", over[name] * 1e6 <= GOAL_US) for name in cc if "before" not in name]
    goals.append(Goal("per-state call overhead from Python, rhs (12-DOF biped)", f"≤ {GOAL_US:g} µs",
                      f"{b_over * 1e6:.2f} µs", b_over * 1e6 <= GOAL_US))
    goals += [Goal(f"fixed cost per call, {name}", f"≤ {limit} µs", f"{fixed[name] * 1e6:.1f} µs",
                   fixed[name] * 1e6 <= limit) for name, limit in (("run", 20), ("simulate", 40))]
    return Section("Calls from Python", "\n".join(md), goals, {"compass": cd, "biped12": bd, "fixed": fd})


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
