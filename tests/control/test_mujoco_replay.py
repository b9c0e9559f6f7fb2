"""RABBIT exported to MuJoCo: MuJoCo is the independent oracle of the exported robot's dynamics, and
the HZD gait replayed there on soft ground walks.

amble's RABBIT is pinned at its stance foot (5 coordinates); the export is free in the plane
(7: hip x, hip z, torso pitch, two hips, two knees). With the foot held, MuJoCo's velocities are
``v = J q̇`` where ``J`` is read from MuJoCo's own foot Jacobian ``J_c`` (``J_c v = 0``: the hip's
rates are ``−J_c,rest q̇``, the joints map one to one), and its accelerations ``J q̈ + a`` with
``a = −J̇_c v`` on the hip rows (``mj_jacDot``). Then amble's ``M`` and ``h`` must be ``Jᵀ M_mj J``
and ``Jᵀ (M_mj a + qfrc_bias)`` — MuJoCo's composite rigid body and recursive Newton–Euler on the
exported bodies, nothing of amble's derivation.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from amble.analysis.mujoco_replay import mujoco_state, planar_biped_mjcf, replay_in_mujoco
from amble.backend.kernels import compiled
from amble.errors import ModelError, ParameterError
from amble.models import load
from amble.simulation.simulate import parameter_vector

mujoco = pytest.importorskip("mujoco", reason="MuJoCo (pip install mujoco) is the reference; not installed")
from oracles.mujoco_dynamics import full_mass_matrix  # noqa: E402  (after the skip)

#: amble's coordinates (torso stance_hip swing_hip stance_knee swing_knee) → MuJoCo's velocity index
#: while leg a stands (MuJoCo: rootx rootz torso hip_a knee_a hip_b knee_b), written out here
_ROWS = [2, 3, 5, 4, 6]


@pytest.fixture(scope="module")
def rabbit():
    return load("rabbit")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_exported_dynamics_are_amble_s(rabbit, seed):
    params = {"mT": 18.0, "lf": 0.42, "pt": 0.11, "It": 0.8}  # not the defaults: every value reaches the file
    k = compiled(rabbit)
    p = parameter_vector(k, params, rabbit)
    values = {**rabbit.parameters, **params}
    m = mujoco.MjModel.from_xml_string(planar_biped_mjcf(rabbit, params))
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(-0.6, 0.6, 5), rng.uniform(-2.0, 2.0, 5)])
    d.qpos[:], d.qvel[:] = mujoco_state(x, values, 0, foot=(0.3, 0.0))
    mujoco.mj_forward(m, d)
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "foot_a")
    body = int(m.site_bodyid[site])
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jacp, jacr, site)
    Jc = jacp[[0, 2]]
    # the state map puts the stance foot where it was asked, at rest
    np.testing.assert_allclose(d.site_xpos[site][[0, 2]], [0.3, 0.0], atol=1e-12)
    np.testing.assert_allclose(Jc @ d.qvel, 0.0, atol=1e-12)
    np.testing.assert_allclose(Jc[:, :2], np.eye(2), atol=1e-12)  # the slides move the foot as themselves
    J = np.zeros((m.nv, 5))
    J[_ROWS, range(5)] = 1.0
    J[:2] = -Jc[:, _ROWS]
    dp, dr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jacDot(m, d, dp, dr, d.site_xpos[site], body)
    a = np.zeros(m.nv)
    a[:2] = -(dp[[0, 2]] @ d.qvel)
    Mmj = full_mass_matrix(m, d)
    M, h, _ = k.dynamics("rabbit", 0.0, x, p)
    scale = np.max(np.abs(M))
    np.testing.assert_allclose(J.T @ Mmj @ J, M, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(J.T @ (Mmj @ a + d.qfrc_bias), h, rtol=0, atol=1e-9 * np.max(np.abs(h)))


def test_hzd_gait_walks_ten_steps_in_mujoco(rabbit):
    r = replay_in_mujoco(rabbit, steps=10)
    assert r.status == "completed" and r.steps == 10
    s = r.summary()
    # soft contact with the default stiffness: the step stays 0.395 m, the step time within 10 %,
    # the stance foot holds (slip and sinking of a few mm at most)
    assert s["max_step_length_error"] < 2e-3
    assert s["max_step_time_error"] < 0.1 * r.drift[0].amble_step_time
    assert s["max_angle_rms"] < 0.1
    assert s["max_stance_slip"] < 5e-3 and s["max_penetration"] < 5e-3
    # on the zero dynamics until the first footfall; the soft footfalls leave the outputs off it by ~0.01 rad
    assert r.drift[0].max_output < 3e-3 and 3e-3 < s["max_output"] < 0.05
    # the law meets each soft footfall with the velocities before the impact: clipped for a few ms
    assert r.max_input > 150.0 and 0 < r.saturated_time < 0.02 * r.time


def test_other_layouts_and_bad_settings_are_refused(rabbit):
    with pytest.raises(ModelError, match="RABBIT's layout"):
        planar_biped_mjcf(load("compass-gait"))
    with pytest.raises(ParameterError, match="slope"):
        planar_biped_mjcf(rabbit, {"slope": 0.1})
    with pytest.raises(ParameterError, match="contact_time"):
        planar_biped_mjcf(rabbit, contact_time=1e-4)
    with pytest.raises(ParameterError, match="unknown parameter"):
        planar_biped_mjcf(rabbit, {"nope": 1.0})


def test_command_writes_the_model_and_reports_per_step(capsys, tmp_path):
    from amble.cli.main import main

    path = tmp_path / "rabbit.xml"
    assert main(["mujoco", "rabbit", "--steps", "2", "--mjcf", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "completed" and out["steps"] == 2 and len(out["per_step"]) == 2
    assert abs(out["per_step"][0]["step_length"] - out["per_step"][0]["amble_step_length"]) < 2e-3
    m = mujoco.MjModel.from_xml_path(str(path))  # the file is a MuJoCo model of the robot
    assert m.nq == 7 and m.nu == 4 and abs(sum(m.body_mass) - (20.0 + 2 * 6.8 + 2 * 3.2)) < 1e-12
    assert main(["mujoco", "rabbit", "--steps", "0"]) == 2
    assert main(["mujoco", "rabbit", "--start", "x0=1,,2"]) == 2
    assert "amble: error:" in capsys.readouterr().err


def test_a_model_with_rabbit_s_names_but_other_mechanics_is_refused():
    from amble import Model, R, walker

    m = Model("not-rabbit")
    T, hst, hsw, kst, ksw = m.coordinates("torso stance_hip swing_hip stance_knee swing_knee")
    mT, mf, mt, lf, lt, pT, pf, pt, IT, If, It, g = m.parameters(
        mT=20.0, mf=6.8, mt=3.2, lf=0.4, lt=0.4, pT=0.2, pf=0.163, pt=0.128, IT=2.22, If=1.08, It=0.93, g=9.81)
    f1, t1, f2, t2 = T + hst, T + hst + kst, T + hsw, T + hsw + ksw
    m.point("stance_foot", (0, 0))
    knee1 = m.point("stance_knee_joint", lt * R(t1), link="stance_foot")
    hip = m.point("hip", knee1 + lf * R(f1), link="stance_knee_joint")
    m.point("torso_com", hip + pT * R(T), mass=mT)
    m.point("stance_femur_com", hip - pf * R(f1), mass=mf)
    m.point("stance_tibia_com", knee1 - pt * R(t1), mass=mt)
    knee2 = m.point("swing_knee_joint", hip - lf * R(f2), link="hip")
    m.point("swing_femur_com", hip - pf * R(f2), mass=mf)
    m.point("swing_tibia_com", knee2 - 2 * pt * R(t2), mass=mt)  # not where the export puts it
    m.point("swing_foot", knee2 - lt * R(t2), link="swing_knee_joint")
    for angle, inertia in ((T, IT), (f1, If), (t1, It), (f2, If), (t2, It)):
        m.inertia(angle, inertia)
    m.gravity(g)
    other = walker(m, foot="swing_foot", hip="hip", slope=0.0,
                   relabel={T: T, hst: hsw, hsw: hst, kst: ksw, ksw: kst})
    x0 = [0.1, -0.4, 0.1, 0.1, 0.1, 0.6, 0.8, 0.2, -1.0, 0.2]
    with pytest.raises(ModelError, match="not the exported biped's"):
        replay_in_mujoco(other, 1, x0=x0)


def test_amble_reads_the_exported_file_back_as_rabbit(rabbit, tmp_path):
    """amble's own MJCF import of the export, pinned at the stance foot, is RABBIT again: the
    conventions of the export and of the import (axes, signs, ``qpos``) are one."""
    import warnings

    from amble import HybridSystem, Model

    path = tmp_path / "rabbit.xml"
    path.write_text(planar_biped_mjcf(rabbit), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the motors: the import reads no actuators
        tree = Model.from_mjcf(path)
    assert [str(q) for q in tree.q] == ["rootx", "rootz", "torso", "hip_a", "knee_a", "hip_b", "knee_b"]
    kt, kr = compiled(HybridSystem(tree.name, tree)), compiled(rabbit)
    x = np.array([0.1, -0.4, 0.1, 0.1, 0.1, 0.6105463, 0.82904739, 0.15687426, -1.07386594, 0.20003823])
    qpos, qvel = mujoco_state(x, rabbit.parameters, 0)
    Mt, _, _ = kt.dynamics(0, 0.0, np.concatenate([qpos, qvel]), np.zeros(1))
    M, _, _ = kr.dynamics("rabbit", 0.0, x, parameter_vector(kr, {}, rabbit))
    # with the foot held: q̇_tree = J q̇, J from the legs' geometry (hip = foot + lt R(θ_tibia) + lf R(θ_femur))
    eps = 1e-6
    J = np.column_stack([(mujoco_state(x + eps * np.eye(10)[i], rabbit.parameters, 0)[0]
                          - mujoco_state(x - eps * np.eye(10)[i], rabbit.parameters, 0)[0]) / (2 * eps)
                         for i in range(5)])
    np.testing.assert_allclose(J.T @ Mt @ J, M, rtol=0, atol=1e-7 * np.max(np.abs(M)))
    # at rest only gravity is left in h: the import pulls the same way (J̇ q̇ = 0)
    rest = np.concatenate([x[:5], np.zeros(5)])
    _, gt, _ = kt.dynamics(0, 0.0, np.concatenate([qpos, np.zeros(7)]), np.zeros(1))
    _, g, _ = kr.dynamics("rabbit", 0.0, rest, parameter_vector(kr, {}, rabbit))
    np.testing.assert_allclose(J.T @ gt, g, rtol=0, atol=1e-7 * np.max(np.abs(g)))


def test_a_start_far_off_the_gait_falls_in_mujoco_and_says_so(rabbit):
    x0 = [0.1, -0.4, 0.1, 0.1, 0.1, -2.6, 0.83, 0.16, -1.07, 0.2]  # the torso thrown backwards
    r = replay_in_mujoco(rabbit, 3, x0=x0)
    assert r.status == "fell" and r.steps < 3
    json.dumps(r.to_json(), allow_nan=False)  # no NaN in the JSON
