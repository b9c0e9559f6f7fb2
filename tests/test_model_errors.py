import pytest
import sympy as sp

from amble import Model, ModelError, derive


def test_unknown_symbol_in_position_is_named():
    m = Model("bad")
    (q,) = m.coordinates("q")
    with pytest.raises(ModelError, match="zeta"):
        m.point("p", (q + sp.Symbol("zeta"), 0))


def test_non_positive_mass_is_rejected():
    m = Model("bad")
    (q,) = m.coordinates("q")
    m.parameters(mm=-1.0)
    m.point("p", (q, 0), mass=m.symbol("mm"))
    with pytest.raises(ModelError, match="positive"):
        derive(m)


def test_wrong_dimension_point():
    m = Model("bad", dims=3)
    (q,) = m.coordinates("q")
    with pytest.raises(ModelError, match="3 for a 3D"):
        m.point("p", (q, 0))


def _pendulum():
    m = Model("pendulum")
    (q,) = m.coordinates("q")
    (g,) = m.parameters(g=9.81)
    m.point("bob", (sp.sin(q), -sp.cos(q)), mass=1)
    m.gravity(g)
    return m


def test_guard_that_does_not_depend_on_the_state():
    from amble import Guard, HybridSystem

    m = _pendulum()
    s = HybridSystem("p", m)
    with pytest.raises(ModelError, match="does not depend on the state"):
        s.terminal("never", "pendulum", Guard(m.symbol("g") - 1))


def test_reset_to_unknown_or_missing_target_coordinates():
    from amble import Explicit, HybridSystem, Impact

    m = _pendulum()
    (q,) = m.q
    s = HybridSystem("p", m)
    with pytest.raises(ModelError, match="not among the target coordinates"):
        s.transition("bad", "pendulum", __import__("amble").Guard(q), Impact("bob", {"nope": q}))
    with pytest.raises(ModelError, match="impact point"):
        s.transition("bad", "pendulum", __import__("amble").Guard(q), Impact("elbow", {}))
    with pytest.raises(ModelError, match="values for"):
        s.transition("bad", "pendulum", __import__("amble").Guard(q), Explicit(q=[q, q], qd=[q]))


def test_unknown_mode_and_parameter_clash():
    from amble import Guard, HybridSystem

    m = _pendulum()
    s = HybridSystem("p", m)
    with pytest.raises(ModelError, match="unknown mode"):
        s.terminal("x", "nowhere", Guard(m.q[0]))
    other = Model("other")
    other.coordinates("r")
    other.parameters(g=1.0)
    with pytest.raises(ModelError, match="defaults"):
        HybridSystem("clash", {"a": _pendulum(), "b": other})


def test_impact_needs_point_masses():
    from amble import Guard, HybridSystem, Impact, simulate

    m = Model("k-outright")
    (q,) = m.coordinates("q")
    m.point("tip", (sp.sin(q), -sp.cos(q)))
    m.K = m.dot(q) ** 2 / 2
    m.V = -sp.cos(q)
    s = HybridSystem("k", m)
    s.transition("hit", "k-outright", Guard(q), Impact("tip", {}))
    with pytest.raises(ModelError, match="point masses"):
        simulate(s, [0.5, 0.0], t_end=1.0)


@pytest.mark.parametrize("declare, message", [
    (lambda m: m.parameter("t", 3.0), "reserved for time"),
    (lambda m: m.coordinates("x x_dot"), "already taken"),        # x_dot is x's velocity
    (lambda m: (m.coordinates("x"), m.parameter("x_dot", 1.0)), "already taken"),
    (lambda m: (m.parameter("k", 1.0), m.coordinates("k")), "already taken"),
    (lambda m: m.coordinates(["x y"]), "not an identifier"),
])
def test_a_name_stands_for_one_symbol(declare, message):
    # each of these once gave silently wrong physics (a parameter t replaced the time symbol;
    # a coordinate x_dot shared its symbol with x's velocity)
    with pytest.raises(ModelError, match=message):
        declare(Model("names"))


@pytest.mark.parametrize("declare, message", [
    (lambda m, x: m.point("p", None), "must be a vector"),                       # was AttributeError
    (lambda m, x: m.point("p", ("x +* 2", 0)), "cannot read"),                  # was SympifyError
    (lambda m, x: m.point("p", (sp.Function("f")(x), 0)), "undefined function"),  # failed in the C compiler
    (lambda m, x: m.point("p", (x / 0, 0)), "infinite, undefined or complex"),   # zoo reached code generation
    (lambda m, x: m.add_potential(sp.I * x), "infinite, undefined or complex"),
    (lambda m, x: m.force([x > 0]), "must be an expression"),
    (lambda m, x: m.torque("tau +* 1", x), "cannot read"),
    (lambda m, x: m.body_inertia([[1, 0], [0]], sp.eye(3)), "rows of different lengths"),
])
def test_bad_expressions_are_model_errors_where_they_are_written(declare, message):
    m = Model("bad")
    (x,) = m.coordinates("x")
    with pytest.raises(ModelError, match=message):
        declare(m, x)
