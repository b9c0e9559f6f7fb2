"""The one table of the Python ↔ C interface of a compiled system.

Everything both languages must agree on is listed here once: the run status codes, the fields of
the resumable context array ``ctx``, of the real and integer option arrays ``opt`` and ``iopt``,
the layout of the sensitivity buffer, the integrators, and the integer width of counters. The C header the engine
includes is generated from these tables (:func:`c_header`), and a loaded library reports its
layout back, which is compared with :data:`LAYOUT` at load — a stale library is refused instead
of misread.
"""

from __future__ import annotations

from functools import lru_cache

from .digest import sha256

#: Run status codes: (code, C name, outcome name). Outcome ``None``: not an end of the run (the
#: loop returns to have its buffers grown); ``"terminal"`` is refined to the terminal
#: transition's own status (e.g. ``fell``).
STATUS: tuple[tuple[int, str, str | None], ...] = (
    (0, "BUFFER_FULL", None),
    (1, "END_TIME", "end_time"),
    (2, "STEPS_DONE", "completed"),
    (3, "TERMINAL", "terminal"),
    (4, "STEP_TIMEOUT", "fell"),
    (5, "ZENO", "zeno"),
    (6, "STEP_TOO_SMALL", "integrator_failure"),
    (7, "NONFINITE", "integrator_failure"),
    (8, "MAX_EVENTS", "max_events"),
    (9, "SINGULAR_MASS", "singular_mass"),
    (10, "RESET_FAILED", "reset_failed"),
    (11, "STALLED", "stalled"),                     # integrator steps between transitions exhausted
    (12, "MAX_ISTEPS", "max_integrator_steps"),     # integrator steps of the whole run exhausted
    (13, "YIELD", None),                            # periodic return to Python (signals), then resume
    (14, "SLIDING", "sliding"),                     # the flow points into a switching surface from both sides
    (15, "RECORD_LIMIT", "record_limit"),           # set by Python: the recording budget is spent
)

#: Fields of ``ctx`` (float64), the resumable state of a run, in index order; the state vector
#: follows from index :data:`CTX_X` on (``nx_max`` entries).
CTX_FIELDS: tuple[str, ...] = (
    "T",            # current time (s)
    "MODE",         # current mode index
    "H",            # next step size (s; 0: choose)
    "STEPS",        # step transitions so far
    "EVENTS",       # transitions so far
    "TLAST_STEP",   # time of the last step transition
    "TPREV_EVENT",  # time of the last transition (Zeno detection)
    "ZENO",         # consecutive transitions closer than zeno_dt
    "GRID_K",       # index of the next output-grid sample
    "GRID_T0",      # time of output-grid sample 0
    "INFO",         # transition index of a terminal or failed reset
    "FRESH",        # 1: the initial row is still to be recorded
    "ISTEPS",       # accepted integrator steps of the run
    "ISTEPS_EV",    # accepted integrator steps since the last transition
)
CTX_X = 16

#: Fields of ``opt`` (float64), in index order.
OPT_FIELDS: tuple[str, ...] = ("TEND", "RTOL", "ATOL", "MAXSTEP", "MAXSTEPTIME", "SAMPLEDT", "ZENODT")

#: Fields of ``iopt`` (int64), in index order.
IOPT_FIELDS: tuple[str, ...] = ("MAXSTEPS", "MAXEVENTS", "OUTCAP", "EVCAP", "ZENON", "NSUB",
                                "MAXISTEPS", "MAXISTEPS_EV", "YIELDN",
                                "METHOD")  # integrator: a code of METHODS

#: Integrators: (code, name, needs_jacobian, has_sensitivities). A row's C side is the stepper
#: ``<name>_stepper`` (``_c/stepper.h``) of the file ``_c/<name>.h``; the compiled loop reaches a
#: method only through its row of the table ``STEPPERS`` (:func:`c_steppers`), indexed by code.
#: needs_jacobian: the kernels must be built with their derivatives (an implicit method's Newton
#: matrix); has_sensitivities: the method gives its explicit tableau, on whose stages the
#: variational equations of ``_c/sensitivity.h`` ride.
METHODS: tuple[tuple[int, str, bool, bool], ...] = (
    (0, "dop853", False, True),   # explicit, 8th order, 7th-order dense output: the default
    (1, "radau", True, False),    # Radau IIA, implicit, 5th order: stiff runs
    (2, "tsit5", False, True),    # Tsitouras 5(4), explicit, free 4th-order dense output
)

#: What ``amble_rows`` evaluates at many states in one call: (code, name, what a row of its output
#: holds). ``nx``: the mode's state length, ``nq = nx / 2``, ``SC`` as below.
ROW_OPS: tuple[tuple[int, str, str], ...] = (
    (0, "RHS", "dx/dt (nx)"),
    (1, "DYNAMICS", "M (nq × nq, row-major), h (nq), Γ (nq)"),
    (2, "RHS_JAC", "dx/dt (nx), then [∂f/∂x, ∂f/∂p] (nx rows of SC columns)"),
    (3, "CONSTRAINT_FORCES", "λ of the mode's holonomic constraints (m; none for an unconstrained mode)"),
)

#: The sensitivity buffer (float64, ``_c/sensitivity.h``) of a run that carries ∂x/∂(x0, p), in
#: order: (name, size as coefficients (a, b, c) of ``a·NXMAX·SC + b·SC + c``). ``NXMAX`` is a
#: library's longest state, ``SC = NXMAX + NPARAM`` the columns of a sensitivity row (state
#: columns 0 … nx0−1, parameter j at NXMAX + j). Offsets are the sums of the sizes before.
SENS_FIELDS: tuple[tuple[str, tuple[int, int, int]], ...] = (
    ("S", (1, 0, 0)),    # ∂x/∂(x0, p): NXMAX rows of SC columns, row-major
    ("TAU", (0, 1, 0)),  # dτ of the last transition: one row of SC columns
    ("NCS", (0, 0, 1)),  # state columns carried (the initial state's size)
    ("NCP", (0, 0, 1)),  # parameter columns carried (0 or NPARAM)
)


@lru_cache(maxsize=1)
def _sens_offsets() -> dict[str, tuple[int, int, int]]:
    """Offset of each sensitivity field, and ``SIZE`` (the whole buffer), as coefficients."""
    out, acc = {}, (0, 0, 0)
    for name, size in SENS_FIELDS:
        out[name] = acc
        acc = tuple(a + b for a, b in zip(acc, size))
    out["SIZE"] = acc
    return out


@lru_cache(maxsize=64)  # asked by every sensitivity run, with a library's one shape
def sens_layout(nx_max: int, sc: int) -> dict[str, int]:
    """Offsets (entries of float64) of the sensitivity fields in the buffer of a library with
    longest state ``nx_max`` and ``sc`` columns per sensitivity row, and ``SIZE``, its length."""
    return {name: a * nx_max * sc + b * sc + c for name, (a, b, c) in _sens_offsets().items()}


def _sens_c(coef: tuple[int, int, int]) -> str:
    """A C expression of ``a·NXMAX·SC + b·SC + c`` (macros of the generated unit)."""
    a, b, c = coef
    terms = [t for t in ((f"{a} * NXMAX * SC" if a != 1 else "NXMAX * SC") if a else "",
                         (f"{b} * SC" if b != 1 else "SC") if b else "", str(c) if c else "") if t]
    return f"({' + '.join(terms)})" if terms else "0"


CTX = {name: i for i, name in enumerate(CTX_FIELDS)}
OPT = {name: i for i, name in enumerate(OPT_FIELDS)}
IOPT = {name: i for i, name in enumerate(IOPT_FIELDS)}
CODE = {name: code for code, name, _ in STATUS}
METHOD = {name: code for code, name, _, _ in METHODS}
ROW_OP = {name: code for code, name, _ in ROW_OPS}
NEEDS_JACOBIAN = {name: jac for _, name, jac, _ in METHODS}
HAS_SENSITIVITIES = {name: sens for _, name, _, sens in METHODS}
OUTCOME = {code: outcome for code, _, outcome in STATUS}

assert len(CTX_FIELDS) <= CTX_X, "ctx fields overlap the state vector"
assert [m[0] for m in METHODS] == list(range(len(METHODS))), "method codes index the stepper table"


def _layout_text() -> str:
    parts = [f"ST_{n}={c}" for c, n, _ in STATUS] + [f"CX_{n}={i}" for n, i in CTX.items()] + [f"CX_X={CTX_X}"]
    parts += [f"OP_{n}={i}" for n, i in OPT.items()] + [f"IO_{n}={i}" for n, i in IOPT.items()]
    parts += [f"SENS_{n}={c}" for n, c in _sens_offsets().items()]
    parts += [f"MT_{n.upper()}={c}" for c, n, _, _ in METHODS]
    parts += [f"ROP_{n}={c}" for c, n, _ in ROW_OPS]
    return ";".join(parts)


#: A 60-bit fingerprint of the whole layout; the compiled library reports the one it was built with.
LAYOUT = int(sha256(_layout_text().encode()).hexdigest()[:15], 16)


def c_header(layout: int | None = None) -> str:
    """The C side of these tables: ``#define ST_*``, ``CX_*``, ``OP_*``, ``IO_*``, ``MT_*`` (method
    codes) and ``N_METHODS``, ``ROP_*`` (operations of ``amble_rows``), ``SENS_*`` (offsets in
    terms of the unit's ``NXMAX`` and ``SC``) and ``AMBLE_LAYOUT`` (default :data:`LAYOUT`), written
    into every generated translation unit before the engine is included.
    Integer arrays shared with NumPy int64 are ``int64_t``."""
    lines = ["/* Python <-> C interface, generated from amble/backend/abi.py; do not edit. */",
             "#include <stdint.h>"]
    lines += [f"#define ST_{name} {code}" for code, name, _ in STATUS]
    lines += [f"#define CX_{name} {i}" for name, i in CTX.items()] + [f"#define CX_X {CTX_X}"]
    lines += [f"#define OP_{name} {i}" for name, i in OPT.items()]
    lines += [f"#define IO_{name} {i}" for name, i in IOPT.items()] + [f"#define IOPT_LEN {len(IOPT)}"]
    lines += [f"#define MT_{name.upper()} {code}" for code, name, _, _ in METHODS]
    lines.append(f"#define N_METHODS {len(METHODS)}")
    lines += [f"#define ROP_{name} {code}" for code, name, _ in ROW_OPS]
    lines += [f"#define SENS_{name} {_sens_c(c)}" for name, c in _sens_offsets().items()]
    lines.append(f"#define AMBLE_LAYOUT {LAYOUT if layout is None else layout}LL")
    return "\n".join(lines) + "\n"


def c_steppers() -> str:
    """The runtime's table of integrators (``amble_steppers.h``): each method's file, then
    ``STEPPERS``, its stepper at its code. Included by the runtime after ``stepper.h``."""
    lines = ["/* The integrators, generated from amble/backend/abi.py; do not edit. */"]
    lines += [f'#include "{name}.h"' for _, name, _, _ in METHODS]
    lines.append("static const Stepper *const STEPPERS[N_METHODS] = {")
    lines += [f"    &{name}_stepper, /* MT_{name.upper()} */" for _, name, _, _ in METHODS]
    lines.append("};")
    return "\n".join(lines) + "\n"
