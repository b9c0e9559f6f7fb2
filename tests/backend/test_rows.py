"""Row-wise kernels check their inputs before handing them to C."""

import numpy as np
import pytest

from amble.backend.kernels import compiled
from amble.errors import StateError


@pytest.fixture()
def kp(compass):
    k = compiled(compass)
    return k, np.array(k.meta["param_defaults"], float)


def test_energy_rows_row_count_mismatch(kp):
    k, p = kp
    x = np.zeros((2, k.nx_max))
    with pytest.raises(StateError, match="3 times, 2 modes, 2 states"):
        k.energy_rows([0.0, 0.0, 0.0], [0, 0], x, p)
    with pytest.raises(StateError, match="2 times, 1 modes, 2 states"):
        k.energy_rows([0.0, 0.0], [0], x, p)


def test_kinematics_rows_row_count_mismatch(kp):
    k, p = kp
    with pytest.raises(StateError, match="row counts differ"):
        k.kinematics_rows([0.0], [0, 0], np.zeros((2, k.nx_max)), p)


def test_mode_out_of_range(kp):
    k, p = kp
    with pytest.raises(StateError, match="mode index 5 out of range"):
        k.energy_rows([0.0], [5], np.zeros((1, k.nx_max)), p)
    with pytest.raises(StateError, match="mode index -1"):
        k.kinematics_rows([0.0], [-1], np.zeros((1, k.nx_max)), p)


def test_matching_rows_still_work(kp):
    k, p = kp
    out = k.energy_rows([0.0, 0.0], [0, 0], np.zeros((2, k.nx_max)), p)
    assert out.shape == (2, 2) and np.isfinite(out).all()
