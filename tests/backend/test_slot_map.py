"""The generated C says what each slot of ``x`` and ``p`` holds, for every mode of a system."""

import re

import pytest

from amble.backend.codegen import generate
from amble.models import load


@pytest.mark.parametrize("name", ["kneed-biped", "humanoid-3d"])
def test_every_state_and_parameter_slot_is_named_in_the_source(name):
    system = load(name)
    source, _ = generate(system)
    head = source[source.index("/* Slots"): source.index("*/", source.index("/* Slots"))]
    for mode, model in system.modes.items():
        line = next(ln for ln in head.splitlines() if f"'{mode}':" in ln)
        assert re.findall(r"x\[(\d+)\] (\w+)", line) == [(str(i), s) for i, s in enumerate(model.state_names)]
    line = next(ln for ln in head.splitlines() if "parameters:" in ln)
    assert re.findall(r"p\[(\d+)\] (\w+)", line) == [(str(i), s) for i, s in enumerate(system.parameters)]
