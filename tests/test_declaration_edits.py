"""A declaration edited after it was built is built again: the next run answers for what the
model now says, never with the kernels of what it said before."""

import numpy as np
import pytest
import sympy as sp

from amble import Explicit, Guard, HybridSystem, Model, simulate


def _pendulum(name: str) -> tuple[Model, HybridSystem]:
    m = Model(name)
    (th,) = m.coordinates(["th"])
    (g,) = m.parameters(g=9.81)
    m.point("bob", sp.Matrix([sp.sin(th), -sp.cos(th)]), mass=1.0)
    m.gravity(g)
    return m, HybridSystem(m.name, m)


def _run(s: HybridSystem) -> np.ndarray:
    return simulate(s, [0.5, 0.0], t_end=2.0, samples=False).final_state


def _damped(m: Model) -> None:
    m.force([-0.3 * m.qd[0]])


def _stiffer(m: Model) -> None:
    m.add_potential(2.0 * m.q[0] ** 2)


def _heavier_bob(m: Model) -> None:
    m.point("bob2", sp.Matrix([2 * sp.sin(m.q[0]), -2 * sp.cos(m.q[0])]), mass=1.0)


def _new_potential(m: Model) -> None:
    m.V = 5.0 * m.q[0] ** 2  # a property assignment


@pytest.mark.parametrize("edit", [_damped, _stiffer, _heavier_bob, _new_potential])
def test_an_edit_after_a_run_changes_the_next_run_as_a_fresh_system_would(edit):
    name = f"edited-{edit.__name__.strip('_')}"
    m, s = _pendulum(name)
    before = _run(s)
    edit(m)
    after = _run(s)  # once: the same numbers as before, from the kernels built before the edit
    fm, fresh = _pendulum(name + "-fresh")
    edit(fm)
    expected = _run(fresh)
    assert not np.allclose(after, before)
    assert np.allclose(after, expected, rtol=1e-10, atol=1e-12)


def test_a_transition_added_after_a_run_fires_in_the_next():
    m, s = _pendulum("edited-transition")
    assert simulate(s, [0.5, 0.0], t_end=2.0, samples=False).events == []
    th, thd = m.q[0], m.qd[0]
    s.transition("wall", m.name, Guard(th + 0.2, direction=-1), Explicit(q=[th], qd=[-thd]))
    tr = simulate(s, [0.5, 0.0], t_end=2.0, samples=False)
    assert [e.name for e in tr.events][:1] == ["wall"]


def test_revisions_only_grow_and_reads_do_not_advance_them():
    m, s = _pendulum("revisions")
    r = m.revision
    m.state_names, m.symbol_table(), m.parse("th"), m.point_velocity("bob")  # reads
    assert m.revision == r
    _damped(m)
    assert m.revision > r
