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
