"""MuJoCo's own dynamics as the oracle of a model read from or written to MJCF: its mass matrix,
whatever the installed MuJoCo's signature of ``mj_fullM``. Nothing here comes from amble."""

import mujoco
import numpy as np


def full_mass_matrix(m, d) -> np.ndarray:
    """The dense joint-space mass matrix of model ``m`` at the state of ``d`` (after ``mj_forward``)."""
    out = np.zeros((m.nv, m.nv))
    try:
        mujoco.mj_fullM(m, d, out)  # MuJoCo 4
    except TypeError:
        mujoco.mj_fullM(m, out, d.qM)  # MuJoCo 3
    return out
