"""RABBIT's proportions (``tests/data/rabbit.urdf``, a 5-link planar biped with a pivoting point
foot and four actuated joints): a 0.8 m/s gait from standing still, feasible to 1e-8, whose impact
and footfall amble's compiled kernels reproduce. (The URDF guide's walker with actuators added; the
library model ``rabbit`` under its HZD controller is tested in ``test_gait_rabbit_hzd.py``.)"""

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble import Model, walker  # noqa: E402
from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.modelling.tree import Joint  # noqa: E402

URDF = Path(__file__).resolve().parents[1] / "data" / "rabbit.urdf"


def rabbit_walker():
    m = Model.from_urdf(URDF, base="left_foot", base_joint=Joint("revolute", axis=(0, 1, 0)),
                        base_coordinate="stance")
    q = {str(s): s for s in m.q}
    swap = {q["left_knee"]: q["right_knee"], q["left_hip"]: q["right_hip"], q["right_hip"]: q["left_hip"],
            q["right_knee"]: q["left_knee"],
            q["stance"]: q["stance"] - q["left_knee"] - q["left_hip"] + q["right_hip"] + q["right_knee"]}
    for j in ("left_hip", "left_knee", "right_hip", "right_knee"):
        m.actuator(f"u_{j}", on=q[j], limit=150.0)
    names = [str(s) for s in m.q]
    stand = np.zeros(2 * len(names))
    stand[names.index("left_hip")], stand[names.index("right_hip")] = 0.25, -0.25
    return walker(m, foot="right_foot", hip="torso", slope=0.0, relabel=swap, start=list(stand))


def test_rabbit_walks_at_0_8_m_per_s_from_standing():
    """The NLP's step (CasADi, from the SymPy model) against amble's compiled C kernels of the same
    walker: the collocated impact is the compiled heel-strike reset (its own impulse solve), the
    pre-impact state is on the compiled footfall guard, and the step length is the compiled swing
    foot's position there."""
    from amble.backend.kernels import compiled
    from amble.simulation.simulate import parameter_vector

    w = rabbit_walker()
    g = optimize_gait(w, speed=0.8, guess="stand", step_time=0.4, nodes=20)
    assert g.max_violation <= 1e-8
    assert g.step_length / g.step_time == pytest.approx(0.8, rel=1e-9)
    assert g.constraints["contact"]["max_violation"] <= 1e-8
    assert np.abs(g.inputs).max() <= 150.0 + 1e-8
    k = compiled(w)
    p = parameter_vector(k, None)
    _, post = k.reset("heel_strike", 0.0, g.pre_impact_state, p)
    assert np.abs(post - g.fixed_point).max() <= 1e-9
    assert abs(k.guards(0, 0.0, g.pre_impact_state, p)[0]) <= 1e-12  # the footfall guard (swing foot height, m)
    pos, _ = k.kinematics_rows([0.0], [0], g.pre_impact_state, p)
    foot = pos[0][k.meta["points"].index("right_foot")]
    assert foot[0] == pytest.approx(g.step_length, abs=1e-12) and abs(foot[2]) <= 1e-12
