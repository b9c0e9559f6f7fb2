"""compiled() serves a system the kernels it was served before, and notices what changes the library."""

import gc
import os
import uuid
import weakref

from amble import Guard, HybridSystem, Model
from amble.backend import kernels


def _dropping_mass(name: str) -> HybridSystem:
    m = Model(name)
    x, z = m.coordinates("x z")
    mass, g = m.parameters(mass=1.0, g=9.81)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    system = HybridSystem(name, m)
    system.terminal("landed", name, Guard(z + 1), status="landed")
    return system


def test_the_same_system_is_served_the_same_kernels():
    s = _dropping_mass("served-again")
    assert kernels.compiled(s) is kernels.compiled(s)


def test_a_transition_added_after_a_build_gets_a_new_library():
    s = _dropping_mass("served-grown")
    before = kernels.compiled(s)
    assert before.n_tr == 1
    s.terminal("far", "served-grown", Guard(s.modes["served-grown"].q[0] - 5), status="far")
    after = kernels.compiled(s)
    assert after.n_tr == 2 and after.path != before.path


def test_plain_builds_get_the_derivative_kernels_once_they_exist():
    # a structure of its own: a cache kept from an earlier run of the suite holds the derivative
    # library of any fixed name already, and serves it to the plain call too
    s = _dropping_mass(f"served-derivatives-{uuid.uuid4().hex[:12]}")
    plain = kernels.compiled(s)
    assert not plain.meta.get("derivatives")
    full = kernels.compiled(s, derivatives=True)
    assert full.meta["derivatives"] and full is not plain
    assert kernels.compiled(s) is full  # as a fresh process that finds both libraries would serve


def test_a_changed_compiler_setting_is_seen(monkeypatch):
    s = _dropping_mass("served-flags")
    first = kernels.compiled(s)
    given = os.environ.get("AMBLE_CFLAGS")  # whatever the run was started with
    monkeypatch.setenv("AMBLE_CFLAGS", "-O1" if given != "-O1" else "-O0")
    assert kernels.compiled(s).path != first.path
    monkeypatch.undo()  # the setting as it was
    assert os.environ.get("AMBLE_CFLAGS") == given
    assert kernels.compiled(s) is first


def test_serving_keeps_no_system_alive():
    s = _dropping_mass("served-dropped")
    kernels.compiled(s)
    ref = weakref.ref(s)
    del s
    gc.collect()
    assert ref() is None
