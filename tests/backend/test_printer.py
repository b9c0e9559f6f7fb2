"""The C text of expressions and the common subexpressions of shared graphs: values checked
against sympy's own evaluation of the same expressions (compiled C for the printer)."""

import ctypes
import math
import random
import subprocess

import sympy as sp

from amble.backend.cache import compiler
from amble.backend.codegen_support import SHARED_MIN_NODES, Printer, is_shared_graph, shared_cse
from amble.modelling.dag import fold, free_symbols

x, y, z = sp.symbols("x y z", real=True)
NAMES = {x: "v[0]", y: "v[1]", z: "v[2]"}

CASES = [
    x + y, x - y, -x * y, x / y, -2 * x / (y**2 * z), sp.Rational(1, 3) * x - sp.Float(0.5) * y,
    sp.sin(x) ** 2 + sp.cos(y) ** 3, sp.Add(x, sp.Add(y, -z, evaluate=False), evaluate=False),
    sp.Mul(-1, sp.Add(x, y), evaluate=False), sp.sqrt(x**2 + y**2), 1 / (x + y), x * (y + z) ** 4,
    sp.Abs(x) * y - sp.pi * z, x ** sp.Rational(3, 2) / (1 + y**2) ** 3, -sp.Float(2.5) * x * sp.exp(-y),
    sp.Mul(sp.Pow(sp.Add(x, 1), -2, evaluate=False), sp.Integer(-3), y, evaluate=False),
    sp.Mul(x, sp.Mul(-1, y, evaluate=False), sp.Rational(-2, 7), evaluate=False),
    sp.Add(sp.Mul(-1, x, evaluate=False), sp.Mul(-1, sp.Add(y, z, evaluate=False), evaluate=False), evaluate=False),
    sp.Pow(sp.Add(x, y, evaluate=False), 2, evaluate=False) - sp.Float(-0.0) * z,
]


def test_printed_c_evaluates_as_sympy(tmp_path):
    pr = Printer(NAMES)
    body = "\n".join(f"    out[{i}] = {pr.doprint(e)};" for i, e in enumerate(CASES))
    src = tmp_path / "p.c"
    src.write_text(f"#include <math.h>\nvoid f(const double *v, double *out) {{\n{body}\n}}\n")
    so = tmp_path / "p.so"
    subprocess.run([*compiler().split(), "-O2", "-fPIC", "-shared", str(src), "-o", str(so), "-lm"], check=True)
    f = ctypes.CDLL(str(so)).f
    rng = random.Random(1)
    for _ in range(20):
        v = [rng.uniform(0.2, 2.0), rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)]
        vin, out = (ctypes.c_double * 3)(*v), (ctypes.c_double * len(CASES))()
        f(vin, out)
        for i, e in enumerate(CASES):
            want = complex(e.evalf(30, subs={x: v[0], y: v[1], z: v[2]}))
            assert abs(out[i] - want.real) <= 1e-13 * (1 + abs(want)), (e, out[i], want)


def _graph(rng: random.Random, n: int) -> list[sp.Expr]:
    """Expressions sharing subexpressions, as a recursion builds them (each node built once)."""
    nodes = [x, y, z, sp.sin(x), sp.cos(y)]
    for _ in range(n):
        a, b = rng.sample(nodes, 2)
        op = rng.choice([sp.Add, sp.Mul])
        c = sp.Rational(rng.randint(-3, 3) or 1, rng.randint(1, 3))
        nodes.append(op(a, sp.Mul(c, b, evaluate=False), evaluate=False))
    return nodes[-6:]


def _value(e: sp.Expr, at: dict) -> float:
    """The value of an expression graph, each distinct node evaluated once."""
    def combine(n, args):
        if n.is_Atom:
            return float(at.get(n, n))
        if isinstance(n, sp.Add):
            return sum(args)
        if isinstance(n, sp.Mul):
            return math.prod(args)
        return float(n.func(*args))
    return fold(e, lambda n: () if n.is_Atom else n.args, combine, {})


def test_shared_cse_rebuilds_the_expressions():
    rng = random.Random(2)
    exprs = _graph(rng, 40)
    repl, reduced = shared_cse(exprs)
    assert repl  # the graph is shared: there is something to name
    names = [s for s, _ in repl]
    for k, (_, e) in enumerate(repl):  # each temporary uses only those before it
        assert not (set(free_symbols(e)) & set(names[k:]))
    for _ in range(5):
        at = {x: rng.uniform(-1, 1), y: rng.uniform(-1, 1), z: rng.uniform(-1, 1)}
        for s, e in repl:
            at[s] = _value(e, at)
        for old, new in zip(exprs, reduced):
            want = _value(old, at)
            assert abs(_value(new, at) - want) <= 1e-12 * (1 + abs(want))


def _deep_graph(n: int) -> sp.Expr:
    """A chain whose every node uses its predecessor twice (as a tree: 2ⁿ nodes), with powers
    and functions of sums, as a tree's kinematics builds them (unevaluated)."""
    e = x
    for k in range(n):
        square = sp.Pow(sp.Add(e, y, evaluate=False), 2, evaluate=False)
        e = sp.Add(sp.Mul(sp.cos(e, evaluate=False), square, evaluate=False),
                   sp.Mul(sp.Rational(1, k + 2), e, evaluate=False), evaluate=False)
    return e


def test_a_shared_graph_is_recognised_and_kept_shared():
    deep = _deep_graph(SHARED_MIN_NODES // 5 + 1)
    assert is_shared_graph([deep])  # a tree of ~2^200 nodes: sympy's cse would not finish
    assert not is_shared_graph(_graph(random.Random(2), 40))  # small: sympy's cse searches it
    assert not is_shared_graph([sp.Add(*[sp.sin(k * x) for k in range(1, 2 * SHARED_MIN_NODES)])])  # large, no sharing
    repl, reduced = shared_cse([deep])
    assert len(repl) <= 4 * (SHARED_MIN_NODES // 5 + 1)  # linear in the graph
    at = {x: 0.3, y: -0.2}
    for s, e in repl:  # the rebuilt powers and functions keep their values (built unevaluated)
        at[s] = _value(e, at)
    want = 0.3
    for k in range(SHARED_MIN_NODES // 5 + 1):  # the same recursion in floating point
        want = math.cos(want) * (want - 0.2) ** 2 + want / (k + 2)
    assert abs(_value(reduced[0], at) - want) <= 1e-12 * (1 + abs(want))
