"""Renamed public names keep working for one release: each old name warns, naming the new one,
and gives what the new one gives."""

import warnings

import pytest

import amble


@pytest.mark.parametrize("old", sorted(amble._RENAMED))
def test_an_old_root_name_warns_and_is_the_new_one(old):
    new = amble._RENAMED[old]
    with pytest.warns(DeprecationWarning, match=rf"amble\.{old} is now amble\.{new}"):
        value = getattr(amble, old)
    assert value is getattr(amble, new)
    assert old not in amble.__all__ and new in amble.__all__


def test_old_method_names_warn_and_answer_as_the_new_ones():
    m = amble.Model("renamed")
    m.coordinates(["q"])
    with pytest.warns(DeprecationWarning, match=r"Model\.mass_and_bias\(\)"):
        M, h = m.dynamics()
    assert (M, h) == m.mass_and_bias()
    s = amble.HybridSystem("renamed", m)
    with pytest.warns(DeprecationWarning, match=r"HybridSystem\.symbolic\(\)"):
        assert s.full() is s.symbolic() is s


def test_the_new_names_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert callable(amble.compiled)
        m = amble.Model("renamed-quiet")
        m.coordinates(["q"])
        m.mass_and_bias()
