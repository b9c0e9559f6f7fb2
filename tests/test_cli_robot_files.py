"""A robot file on the command line: ``amble simulate robot.urdf`` with a floating or fixed base.

Checked against laws, not against earlier output: a floating robot with no contact falls as one
body (its centre of mass moves with constant velocity plus ``g t²/2`` down, whatever its joints
do; started at rest its joints stay at rest — all parts fall alike); a fixed-base robot with no
damping keeps its energy."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from amble import simulate
from amble.cli.main import main
from amble.models import load_robot

ROOT = Path(__file__).resolve().parents[1]
RABBIT = str(Path(__file__).resolve().parent / "data" / "rabbit.urdf")
MJCF_FLOATER = str(Path(__file__).resolve().parent / "data" / "mjcf_floater.xml")
G = 9.81


def _run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def _rows(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head = [h.split(" [")[0] for h in rows[0]]
    return {h: np.array([float(r[i]) for r in rows[1:]]) for i, h in enumerate(head) if h not in ("mode", "event")}



def _falls_as_one_body(cols: dict, height: str) -> None:
    """The base's height column follows −g t²/2 and every other coordinate stays 0 (to 1e-9)."""
    t = cols["t"]
    assert np.allclose(cols[height], -0.5 * G * t**2, rtol=0, atol=1e-9)
    for name, v in cols.items():
        if name not in ("t", height, f"{height}_dot", "kinetic_energy", "potential_energy"):
            assert np.max(np.abs(v)) < 1e-9, name

def test_a_floating_robot_at_rest_falls_as_one_body(capsys, tmp_path):
    out = tmp_path / "fall.csv"
    code, text, _ = _run(capsys, "simulate", RABBIT, "--time", "0.5", "--out", str(out), "--json")
    assert code == 0
    d = json.loads(text)
    assert d["status"] == "end_time" and d["time"] == 0.5 and d["steps"] == 0
    _falls_as_one_body(_rows(out), "base_z")


def test_a_floating_robot_in_motion_keeps_its_centre_of_mass_on_a_parabola():
    system = load_robot(RABBIT)
    model = next(iter(system.modes.values()))
    rng = np.random.default_rng(3)
    x0 = np.concatenate([rng.uniform(-0.3, 0.3, len(model.q)), rng.uniform(-2, 2, len(model.q))])
    tr = simulate(system, x0, t_end=0.4, sample_dt=0.01, rtol=1e-12, atol=1e-12)
    assert tr.status == "end_time"
    pts = tr.world_points()
    masses = {k: float(v) for k, v in model.masses.items()}
    com = sum(m * pts[k] for k, m in masses.items()) / sum(masses.values())
    t = tr.t[:, None]
    # fit the start and the initial velocity; the acceleration is gravity's alone
    v0 = (com[1] - com[0]) / (t[1] - t[0]) + np.array([0, 0, 0.5 * G * t[1, 0]])
    predicted = com[0] + v0 * t + 0.5 * np.array([0.0, 0.0, -G]) * t**2
    assert np.max(np.abs(com - predicted)) < 1e-8


def test_a_fixed_base_robot_keeps_its_energy(capsys, tmp_path):
    out = tmp_path / "swing.csv"
    start = "x0=0.4,-0.3,0.6,0.2,0,0,0,0"
    code, _, _ = _run(capsys, "simulate", RABBIT, "--fixed-base", "--time", "1", "--start", start, "--out", str(out))
    assert code == 0
    cols = _rows(out)
    e = cols["kinetic_energy"] + cols["potential_energy"]
    assert np.max(np.abs(e - e[0])) < 1e-7 * (1 + abs(e[0]))
    assert np.max(np.abs(cols["left_hip_dot"])) > 0.1  # it did swing


def test_the_equations_of_a_robot_file(capsys):
    code, text, _ = _run(capsys, "equations", RABBIT, "--fixed-base", "--json")
    assert code == 0
    (mode,) = json.loads(text)["modes"].values()
    assert mode["coordinates"] == ["left_hip", "right_hip", "left_knee", "right_knee"]
    assert len(mode["mass_matrix"]) == 4


@pytest.mark.parametrize("args, what", [
    (("simulate", "compass-gait", "--base", "torso"), "apply to a robot file"),
    (("simulate", RABBIT, "--base", "nope"), "base link 'nope' is not a link"),
    (("simulate", "robot.sdf"), "SDF files are not read"),
    (("simulate", MJCF_FLOATER, "--base", "arm"), "an MJCF file keeps its own tree"),
    (("simulate", "missing.urdf"), "does not exist"),
])
def test_bad_robot_requests_are_one_line_and_exit_2(capsys, args, what):
    code, _, err = _run(capsys, *args)
    assert code == 2
    assert what in err and len(err.strip().splitlines()) == 1


def test_an_mjcf_robot_at_rest_falls_as_one_body(capsys, tmp_path):
    """The free torso of the file falls from where the file places it; its limbs stay put."""
    out = tmp_path / "fall.csv"
    code, text, _ = _run(capsys, "simulate", MJCF_FLOATER, "--time", "0.5", "--out", str(out), "--json")
    assert code == 0 and json.loads(text)["status"] == "end_time"
    _falls_as_one_body(_rows(out), "root_z")


def test_a_fixed_base_mjcf_chain_keeps_its_energy(capsys, tmp_path):
    pendulum = tmp_path / "double.xml"
    pendulum.write_text(
        '<mujoco model="double"><worldbody><body name="upper" pos="0 0 1" euler="5 -10 20">'
        '<joint name="a" axis="0.3 1 0" pos="0 0 0.02"/>'
        '<inertial pos="0.02 0 -0.2" quat="0.9 0.2 0.1 0.3" mass="1" diaginertia="0.02 0.015 0.008"/>'
        '<body name="lower" pos="0 0.03 -0.4"><joint name="b" axis="1 0 0.2"/>'
        '<inertial pos="0 0.01 -0.15" mass="0.6" diaginertia="0.01 0.009 0.003"/></body></body>'
        '</worldbody></mujoco>')
    out = tmp_path / "swing.csv"
    code, _, _ = _run(capsys, "simulate", str(pendulum), "--fixed-base", "--time", "1", "--start",
                      "x0=0.8,-0.5,1.0,2.0", "--out", str(out))
    assert code == 0
    cols = _rows(out)
    e = cols["kinetic_energy"] + cols["potential_energy"]
    assert np.max(np.abs(e - e[0])) < 1e-7 * (1 + abs(e[0]))
    assert np.max(np.abs(cols["b_dot"])) > 0.5  # it did swing


def _modules_after(args, env):
    run = ("import json, sys; from amble.cli import main; "
           f"assert main({list(args)!r}) == 0; print(json.dumps(sorted(sys.modules)), file=sys.stderr)")
    r = subprocess.run([sys.executable, "-c", run], env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return set(json.loads(r.stderr.strip().splitlines()[-1]))


def test_a_robot_file_starts_warm_without_sympy_and_each_base_is_its_own_entry(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "AMBLE_CACHE_DIR": str(tmp_path / "cache"),
           "AMBLE_WARM_START": "1"}
    fixed = ["simulate", RABBIT, "--fixed-base", "--time", "0.1", "--json"]
    assert "sympy" in _modules_after(fixed, env)  # cold: derived, compiled, indexed
    warm = _modules_after(fixed, env)
    assert "amble.backend.compiled" in warm and "sympy" not in warm
    floating = _modules_after(fixed[:2] + fixed[3:], env)  # another base joint: another system
    assert "sympy" in floating


def test_an_edit_to_an_included_mjcf_file_is_an_edit_to_the_robot(tmp_path):
    from amble.models import source_files

    (tmp_path / "arm.xml").write_text('<mujoco><worldbody><body name="arm"><joint name="a"/>'
                                      '<geom size="0.1"/></body></worldbody></mujoco>')
    (tmp_path / "robot.xml").write_text('<mujoco model="r"><include file="arm.xml"/></mujoco>')
    files = source_files(str(tmp_path / "robot.xml"))
    assert files == [(tmp_path / "robot.xml").resolve(), (tmp_path / "arm.xml").resolve()]
