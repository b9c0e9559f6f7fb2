"""Text becomes an expression without being executed: the whitelist reader of
``amble.modelling.text``, fuzzed, and every door by which text reaches it (command-line
objective, guards and conditions written as text, strings in model declarations)."""

import math
import os
import subprocess
import sys
import time

import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sympy.parsing import sympy_parser

import amble
from amble import ExpressionError, Guard, HybridSystem, ModelError, ParameterError
from amble.modelling.text import parse

x, y = sp.symbols("x y", real=True)
NAMES = {"x": x, "y": y}


@pytest.fixture(autouse=True)
def _sympy_parser_never_runs(monkeypatch):
    """sympy's own parser evaluates Python: no text read in these tests may reach it."""
    def refuse(*args, **kwargs):
        raise AssertionError(f"sympy's parser was called with {args[:1]!r}")

    monkeypatch.setattr(sympy_parser, "parse_expr", refuse)


@pytest.mark.parametrize("text, value", [
    ("x + y^2", x + y**2),
    ("x + y**2", x + y**2),
    ("-x**2/3", -(x**2) / 3),
    ("2**-1", sp.Rational(1, 2)),
    ("2**3**2", 2**9),  # right to left, as in Python and mathematics
    ("x - y - 1", x - y - 1),
    ("x/y/2", x / (2 * y)),
    ("sin(x)*atan2(y, x) + sqrt(Abs(y)) + exp(-x) - log(2)", sp.sin(x) * sp.atan2(y, x) + sp.sqrt(sp.Abs(y))
     + sp.exp(-x) - sp.log(2)),
    ("Max(x, y, 1) + min(x, 0)", sp.Max(x, y, 1) + sp.Min(x, 0)),
    ("pi*E + 1.5e-3", sp.pi * sp.E + sp.Float("1.5e-3")),
])
def test_expressions_read_as_mathematics(text, value):
    assert sp.simplify(parse(text, NAMES) - value) == 0


@pytest.mark.parametrize("text, value", [
    ("x > 0 & y < 1", sp.And(x > 0, y < 1)),  # '&' looser than comparisons, as in C and MATLAB
    ("(x > 0) & (y < 1)", sp.And(x > 0, y < 1)),
    ("0 < x < 1", sp.And(sp.Lt(0, x), x < 1)),
    ("not x >= 0 or Eq(y, 2)", sp.Or(x < 0, sp.Eq(y, 2))),
    ("~(x != y)", sp.Eq(x, y)),
])
def test_conditions_read_as_logic(text, value):
    assert parse(text, NAMES, condition=True) == value


def test_a_name_of_the_caller_is_its_symbol_and_wins_over_a_constant():
    e = sp.Symbol("E", positive=True)
    assert parse("E + x", {"E": e, "x": x}) == e + x


@pytest.mark.parametrize("text, needle", [
    ("__import__('os').system('touch /tmp/amble-owned')", "quotes"),
    ("(lambda: 1)()", "':'"),
    ("().__class__", "'.'"),
    ("x.real", "'.'"),
    ("x[0]", "'['"),
    ("sin(x=1)", "'='"),
    ("eval", "unknown name 'eval'"),
    ("z + 1", "unknown name 'z'"),
    ("open(x)", "not a function"),
    ("x if y else 1", "unexpected 'if'"),
    ("x; y", "';'"),
    ("sin", "call it as sin"),
    ("sin(x, y)", "1 argument"),
    ("1/0", "not finite"),
    ("1e999", "finite"),
    ("1j", "complex"),
    ("9" * 5000, "number"),
    ("10**10**10", "too large"),
    ("((10**999)**999)**999", "too large"),
    ("-" * 1000 + "x", "nested"),
    ("(" * 500 + "x" + ")" * 500, "nested"),
    ("x" * 200_000, "characters"),
    ("", "empty"),
    ("x +", "ends too early"),
    ("x > 0", "conditions"),
    ("x\x00", "NUL"),
])
def test_anything_outside_the_whitelist_is_one_line_refused(text, needle):
    with pytest.raises(ExpressionError) as e:
        parse(text, NAMES)
    assert needle in str(e.value)
    assert "\n" not in str(e.value)
    assert isinstance(e.value, ModelError) and isinstance(e.value, ParameterError)  # either is caught


def test_a_bare_number_or_symbol_is_not_a_condition():
    for text in ("x", "1", "x + 1"):
        with pytest.raises(ExpressionError, match="not a condition"):
            parse(text, NAMES, condition=True)


def test_a_3000_term_sum_is_flat_and_fast():
    start = time.perf_counter()
    e = parse(" + ".join(f"{i}*x*y" for i in range(3000)) + " - y" * 3000, NAMES)
    assert e == sum(range(3000)) * x * y - 3000 * y
    assert time.perf_counter() - start < 20  # quadratic behaviour would take minutes, not a timing test


# ---------------------------------------------------------------------- fuzz
_PIECES = ["x", "y", "1", "2.5", "sin", "cos", "atan2", "sqrt", "pi", "E", "(", ")", ",", "+", "-", "*", "/",
           "**", "^", "<", ">", "==", "&", "|", "~", "not", "and", "__import__", "os", "'", '"', ".", "[", "]",
           "lambda", ":", "=", "exec", "eval", "open", "__class__", "Symbol", "Function", "1e400", "9" * 50]
_fuzz = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _check(text: str, condition: bool) -> None:
    try:
        value = parse(text, NAMES, condition=condition)
    except ExpressionError as e:
        assert "\n" not in str(e) and len(str(e)) < 1000
        return
    assert isinstance(value, sp.Basic)
    assert value.free_symbols <= {x, y}  # no name invented, nothing but the given symbols


@_fuzz
@given(st.lists(st.sampled_from(_PIECES), max_size=30), st.booleans())
def test_fuzz_sympy_like_text_is_read_or_refused_in_one_line(pieces, condition):
    _check(" ".join(pieces), condition)


@_fuzz
@given(st.text(max_size=200), st.booleans())
def test_fuzz_random_text_is_read_or_refused_in_one_line(text, condition):
    _check(text, condition)


_PYTHON = st.sampled_from([
    "__import__('os').system('touch {f}')", "open('{f}', 'w').write('x')", "exec(\"open('{f}','w')\")",
    "(lambda: open('{f}', 'w'))()", "[c for c in ().__class__.__base__.__subclasses__()]",
    "getattr(__builtins__, 'open')('{f}', 'w')", "x.__class__.__init__.__globals__",
    "Symbol('{f}')", "sympify(\"open('{f}', 'w')\")", "x + open('{f}', 'w').close()",
])


@settings(max_examples=60, deadline=None)
@given(_PYTHON, st.sampled_from(["", "x + ", "sin(", "-("]), st.booleans())
def test_fuzz_python_that_would_write_a_file_never_runs(tmp_path_factory, source, prefix, condition):
    f = tmp_path_factory.mktemp("owned") / "made"
    text = prefix + source.format(f=f) + (")" if prefix.endswith("(") else "")
    with pytest.raises(ExpressionError):
        parse(text, NAMES, condition=condition)
    assert not f.exists()


# ---------------------------------------------------------------------- the doors
def test_the_objective_of_the_command_line_is_never_executed(tmp_path):
    """``amble optimize-gait --objective`` once went through ``sympify``: the text ran."""
    made = tmp_path / "made"
    env = {**os.environ, "AMBLE_CACHE_DIR": str(tmp_path / "cache")}
    for objective in (f"__import__('os').system('touch {made}')", "(lambda: 1)()", "().__class__",
                      " + ".join(["stance_dot"] * 3000)[:-1] + "*"):
        cmd = [sys.executable, "-m", "amble.cli", "optimize-gait", "compass-gait", "--objective", objective]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and "objective" in r.stderr
        assert "Traceback" not in r.stderr and not made.exists()


def _ball(name: str):
    m = amble.Model(name)
    (h,) = m.coordinates(["y"])
    (g,) = m.parameters(g=9.81)
    m.point("c", sp.Matrix([0, h]), mass=1)
    m.gravity(g)
    return m


def test_text_in_guards_and_model_declarations_is_read_not_run(tmp_path):
    made = tmp_path / "made"
    m = _ball("text-ball")
    s = HybridSystem(m.name, m)
    with pytest.raises(ModelError, match="quotes"):
        s.terminal("floor", m.name, Guard(f"__import__('os').system('touch {made}')"), "landed")
    with pytest.raises(ModelError, match="quotes"):
        s.terminal("floor", m.name, Guard("y", enabled=f"open('{made}', 'w') > 0"), "landed")
    with pytest.raises(ModelError, match="quotes"):
        m.add_potential(f"__import__('os').system('touch {made}')")
    assert not made.exists()
    g = next(p for p in m.params if str(p) == "g")
    m.add_potential("g*y/10")  # text in the model's own symbols is read as such
    assert m.V - m.V.subs(g, 0) == sp.Rational(11, 10) * g * m.q[0]  # m g y from the gravity, plus g y / 10
    assert m.parse("g*y_dot") == g * m.qd[0]


def test_text_without_a_model_is_refused_where_there_are_no_names():
    with pytest.raises(ExpressionError, match="sympy symbols"):
        amble.vector("x", 0)
    with pytest.raises(ExpressionError, match="be one expression"):
        amble.modelling.text.expr_of(("x",), NAMES)  # sympify would read the strings inside


def test_a_text_guard_walks_like_the_symbolic_one():
    """A ball dropped from 1 m under a text guard first reaches the floor at sqrt(2 h / g)."""
    m = _ball("text-guard-ball")
    s = HybridSystem(m.name, m)
    s.terminal("floor", m.name, Guard("y", direction=-1, enabled="y_dot < 0 & y < 2"), "landed")
    tr = amble.simulate(s, [1.0, 0.0], t_end=2.0, samples=False)
    assert tr.status == "landed" and math.isclose(tr.events[-1].t, math.sqrt(2 / 9.81), rel_tol=1e-8)
