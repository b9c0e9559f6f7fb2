"""Arguments of the wrong type are typed errors before any work: a string where a state, a count or
a time belongs, a list where a mapping belongs, guards the compiled code could not express."""

from __future__ import annotations

import math

import pytest
import sympy as sp

import amble
from amble import Explicit, Guard, HybridSystem, Model, ModelError, ParameterError, StateError
from amble.analysis.poincare import find_fixed_point


@pytest.mark.parametrize("kw, needle", [
    ({"x0": "abcd"}, "sequence of numbers"),  # once ValueError: could not convert string to float
    ({"x0": [0.1, "a", 0.0, 0.0]}, "sequence of numbers"),
    ({"x0": [[0.1, 0.2], [0.3]]}, "sequence of numbers"),
    ({"steps": "3"}, "integer"),  # once TypeError: '<' not supported between 'str' and 'int'
    ({"steps": 2.5}, "integer"),  # once truncated silently
    ({"steps": True}, "integer"),
    ({"steps": 10**30}, "at most"),  # once OverflowError: Python int too large to convert to C long
    ({"t_end": "1"}, "number"),
    ({"sample_dt": "0.1"}, "number"),
    ({"rtol": "1e-8"}, "number"),
    ({"mode": 3}, "mode name"),  # once KeyError: 3
])
def test_wrong_types_are_state_errors(compass, kw, needle):
    with pytest.raises(StateError, match=needle):
        amble.simulate(compass, **({"steps": 1} | kw))


@pytest.mark.parametrize("params", [[("slope", 0.05)], ["slope"], "slope=0.05"])
def test_params_must_be_a_mapping(compass, params):
    # once AttributeError: 'list' object has no attribute 'items'
    with pytest.raises(ParameterError, match="mapping"):
        amble.simulate(compass, params=params, steps=1)
    with pytest.raises(ParameterError, match="mapping"):
        find_fixed_point(compass, params=params)


def test_an_integer_like_step_count_is_accepted(compass):
    import numpy as np

    tr = amble.simulate(compass, steps=np.int64(2), samples=False)
    assert tr.status == "completed" and tr.steps == 2


def _ball(name: str) -> tuple[Model, sp.Symbol, sp.Symbol]:
    m = Model(name)
    (y,) = m.coordinates(["y"])
    (g,) = m.parameters(g=9.81)
    m.point("c", sp.Matrix([0, y]), mass=1)
    m.gravity(g)
    return m, y, m.qd[0]


def _bounce(name: str, **guard: object) -> HybridSystem:
    m, y, yd = _ball(name)
    s = HybridSystem(m.name, m)
    s.transition("bounce", m.name, Guard(**({"expr": y} | guard)), Explicit(q=[y], qd=[-yd / 2]))
    return s


_n = sp.Symbol("n", integer=True)


@pytest.mark.parametrize("guard, needle", [
    ({"enabled": sp.false}, "always false"),  # once CompileError: 'false' undeclared
    ({"enabled": False}, "always false"),
    ({"direction": True}, "direction"),  # once CompileError: 'True' undeclared
    ({"direction": "down"}, "direction"),
    ({"enabled": sp.Gt(sp.I, 0, evaluate=False)}, "complex"),  # once CompileError: 'I' undeclared
    ({"expr": sp.I * sp.Symbol("y", real=True)}, "complex"),
    ({"expr": sp.Sum(sp.Symbol("y", real=True) ** _n, (_n, 1, 3))}, "unevaluated Sum"),  # once 'Sum' undeclared
    ({"expr": sp.Function("f")(sp.Symbol("y", real=True))}, "undefined function"),
    ({"enabled": 1}, "comparison"),
    ({"enabled": sp.Symbol("y", real=True)}, "comparison"),
    ({"expr": "y +* 2"}, "cannot read"),
])
def test_guards_compiled_code_could_not_express_are_model_errors(guard, needle):
    with pytest.raises(ModelError, match=needle):
        _bounce("guard-bad", **guard)


def test_text_guards_read_the_modes_own_symbols():
    s = _bounce("guard-text", expr="y", enabled="y_dot < 0")
    m = s.modes["guard-text"]
    g = s.transitions[0].guard
    # the real coordinate and velocity of the mode, not fresh symbols of the same name
    assert g.expr == m.q[0] and g.enabled == (m.qd[0] < 0)


def test_an_always_true_condition_fires_like_none():
    # a ball dropped from 1 m first reaches the floor at sqrt(2 h / g)
    s = _bounce("guard-true", enabled=sp.true, direction=-1.0)
    assert s.transitions[0].guard.enabled is None and s.transitions[0].guard.direction == -1
    tr = amble.simulate(s, [1.0, 0.0], t_end=0.5, samples=False)
    assert [e.name for e in tr.events] == ["bounce"]
    assert tr.events[0].t == pytest.approx(math.sqrt(2 / 9.81), rel=1e-9)


@pytest.mark.parametrize("qd, needle", [
    ([sp.I * sp.Symbol("y_dot", real=True)], "complex"),  # once CompileError: 'I' undeclared
    ([sp.zoo * sp.Symbol("y_dot", real=True)], "infinite"),  # once PrintMethodNotImplementedError
    ([sp.Sum(sp.Symbol("y_dot", real=True) ** _n, (_n, 1, 2))], "unevaluated Sum"),  # once 'Sum' undeclared
    ([sp.Function("f")(sp.Symbol("y_dot", real=True))], "undefined function"),  # once PrintMethodNotImplementedError
    ([None], "must be an expression"),  # once AttributeError: 'NoneType' object has no attribute 'free_symbols'
    (None, "mapping or a sequence"),
    ("y_dot", "mapping or a sequence"),
])
def test_resets_compiled_code_could_not_express_are_model_errors(qd, needle):
    m, y, _ = _ball("reset-bad")
    with pytest.raises(ModelError, match=needle):
        HybridSystem(m.name, m).transition("bounce", m.name, Guard(y), Explicit(q=[y], qd=qd))


def test_a_text_reset_reads_the_source_modes_symbols():
    # a ball dropped from 1 m reaches the floor at v = sqrt(2 g h) and leaves it at half that speed
    m, y, _ = _ball("reset-text")
    s = HybridSystem(m.name, m)
    s.transition("bounce", m.name, Guard(y), Explicit(q=["y"], qd=["-y_dot/2"]))
    tr = amble.simulate(s, [1.0, 0.0], t_end=0.5, samples=False)
    assert tr.events[0].x_post[1] == pytest.approx(math.sqrt(2 * 9.81) / 2, rel=1e-8)
