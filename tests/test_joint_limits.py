"""Joint limits of a robot file as exact events: ``Model.limit_guards()``,
``HybridSystem.stop_at_limits()`` and ``amble simulate robot.urdf --limits stop``.

Truth: a pendulum released from rest at the horizontal reaches the angle ``a`` at the time of
the closed form with elliptic integrals (tests/oracles/pendulum.py, checked there against
SciPy's own integrator with an event), with the speed ``√(2 ω² sin a)`` of the energy; which
joints carry limits is what the file says (a mimic joint's and a continuous joint's do not)."""

from __future__ import annotations

import json
import math
import warnings

import pytest
from oracles.pendulum import omega2, speed_at_angle, time_by_integration, time_to_angle

from amble import HybridSystem, Joint, Model, limit_of, simulate
from amble.cli.main import main
from amble.errors import ModelError
from amble.models import load_robot

M, L, IYY = 1.5, 0.8, 0.02
W2 = omega2(M, L, IYY)
A = 1.0  # rad: the limit the pendulum swings into

_LINK = (f'<inertial><origin xyz="{L} 0 0"/><mass value="{M}"/>'
         f'<inertia ixx="0.01" ixy="0" ixz="0" iyy="{IYY}" iyz="0" izz="0.01"/></inertial>')


def _urdf(tmp_path, axis: str, limit: str, kind: str = "revolute", extra: str = "") -> str:
    """A pendulum on a horizontal pivot (its centre of mass on +x at zero, level with the pivot)."""
    text = f"""<robot name="pendulum">
  <link name="base"/>
  <link name="arm">{_LINK}</link>
  <joint name="hinge" type="{kind}">
    <parent link="base"/><child link="arm"/><axis xyz="{axis}"/>{limit}
  </joint>{extra}
</robot>"""
    path = tmp_path / "pendulum.urdf"
    path.write_text(text)
    return str(path)


def test_the_oracle_closed_form_agrees_with_an_integrated_pendulum():
    assert abs(time_to_angle(A, W2) - time_by_integration(A, W2)) < 1e-10


# axis +y: gravity swings the arm towards positive angles (into the upper limit); axis −y: negative
@pytest.mark.parametrize("axis, lower, upper, bound", [("0 1 0", -0.5, A, "upper"), ("0 -1 0", -A, 0.5, "lower")])
def test_a_pendulum_stops_at_its_limit_at_the_closed_form_time(tmp_path, axis, lower, upper, bound):
    limit = f'<limit lower="{lower}" upper="{upper}" effort="1" velocity="1"/>'
    system = load_robot(_urdf(tmp_path, axis, limit), fixed_base=True, limits="stop")
    tr = simulate(system, [0.0, 0.0], t_end=2.0, samples=False)
    assert tr.status == "joint_limit"
    event = tr.events[-1]
    assert limit_of(event.name) == ("hinge", bound)
    assert abs(event.t - time_to_angle(A, W2)) < 1e-9
    sign = 1.0 if bound == "upper" else -1.0
    assert abs(event.x_pre[0] - sign * A) < 1e-10
    assert abs(event.x_pre[1] - sign * speed_at_angle(A, W2)) < 1e-8


def test_where_a_start_on_or_beyond_a_bound_stops(tmp_path):
    """On a bound moving out: at once. On the lower bound at rest, gravity pulling in: not there
    but at the upper bound. Beyond the upper bound moving in: not when it enters, but when it
    swings back out through the bound."""
    system = load_robot(_urdf(tmp_path, "0 1 0", f'<limit lower="-0.5" upper="{A}" effort="1" velocity="1"/>'),
                        fixed_base=True, limits="stop")
    out = simulate(system, [-0.5, -0.1], t_end=1.0, samples=False)
    assert out.status == "joint_limit" and limit_of(out.events[-1].name) == ("hinge", "lower")
    assert out.events[-1].t < 1e-12
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no zero-time event at the lower bound
        rest = simulate(system, [-0.5, 0.0], t_end=2.0, samples=False)
    assert limit_of(rest.events[-1].name) == ("hinge", "upper") and len(rest.events) == 1
    back = simulate(system, [A + 0.2, -3.0], t_end=2.0, samples=False)
    assert limit_of(back.events[-1].name) == ("hinge", "upper") and back.events[-1].x_pre[1] > 0


def test_guards_are_the_distances_to_the_bounds_and_ignore_is_todays_run(tmp_path):
    limit = f'<limit lower="-0.5" upper="{A}" effort="1" velocity="1"/>'
    system = load_robot(_urdf(tmp_path, "0 1 0", limit), fixed_base=True)
    model = system.modes[system.mode_names[0]]
    (q,) = model.q
    guards = model.limit_guards()
    assert [(g.coordinate, g.bound, g.value) for g in guards] == [("hinge", "lower", -0.5), ("hinge", "upper", A)]
    assert [float((g.guard.expr - e).subs(q, 0.3)) for g, e in zip(guards, (q + 0.5, A - q))] == [0.0, 0.0]
    assert all(g.guard.direction == -1 for g in guards)
    # without stop_at_limits the joint passes its limit, as before
    tr = simulate(system, [0.0, 0.0], t_end=0.6, samples=False)
    assert tr.status == "end_time" and tr.final_state[0] > A


def test_a_mimic_joint_and_a_continuous_joint_make_no_guards(tmp_path):
    mimic = f"""
  <link name="finger">{_LINK}</link>
  <joint name="follower" type="revolute">
    <parent link="arm"/><child link="finger"/><axis xyz="0 1 0"/><origin xyz="{L} 0 0"/>
    <mimic joint="hinge" multiplier="2" offset="0.1"/>
    <limit lower="-0.2" upper="0.2" effort="1" velocity="1"/>
  </joint>"""
    limit = '<limit lower="-0.5" upper="1.0" effort="1" velocity="1"/>'
    model = Model.from_urdf(_urdf(tmp_path, "0 1 0", limit, extra=mimic))
    assert [(g.coordinate, g.bound) for g in model.limit_guards()] == [("hinge", "lower"), ("hinge", "upper")]
    spinning = Model.from_urdf(_urdf(tmp_path, "0 1 0", limit, kind="continuous"))
    assert spinning.limit_guards() == []
    system = HybridSystem("spinning", spinning)
    with pytest.warns(UserWarning, match="no joint has a limit"):
        assert system.stop_at_limits() == []
    assert system.transitions == []


def test_an_empty_range_is_refused_and_one_sided_or_infinite_bounds_count_once():
    model = Model("chain", dims=3)
    tree = model.rigid_tree()
    tree.body("a", joint=Joint("revolute", axis=(0, 1, 0), lower=None, upper=0.4), mass=1, com=(0.1, 0, 0))
    tree.body("b", "a", joint=Joint("prismatic", axis=(1, 0, 0), lower=-math.inf, upper=math.inf), mass=1)
    assert [(g.coordinate, g.bound) for g in model.limit_guards()] == [("a", "upper")]
    tree.body("c", "b", joint=Joint("revolute", lower=1.0, upper=0.0), mass=1, com=(0.1, 0, 0))
    with pytest.raises(ModelError, match="'c' has the empty range"):
        model.limit_guards()


def test_several_modes_name_each_limit_after_its_mode():
    model = Model("arm", dims=3)
    model.rigid_tree().body("a", joint=Joint("revolute", axis=(0, 1, 0), lower=-1, upper=1), mass=1, com=(1, 0, 0))
    system = HybridSystem("two", {"one": model, "other": model})
    names = [tr.name for tr in system.stop_at_limits("other")]
    assert names == ["a_lower_limit@other", "a_upper_limit@other"]
    assert [limit_of(n) for n in names] == [("a", "lower"), ("a", "upper")]
    assert limit_of("hip_on_ground") is None


def test_mjcf_limits_stop_the_run_at_the_closed_form_time(tmp_path):
    pytest.importorskip("mujoco", reason="MJCF files are read by MuJoCo's compiler")
    xml = tmp_path / "pendulum.xml"
    xml.write_text(f"""<mujoco model="pendulum">
  <compiler angle="radian"/>
  <worldbody>
    <body name="arm">
      <joint name="hinge" type="hinge" axis="0 1 0" limited="true" range="-0.5 {A}"/>
      <inertial pos="{L} 0 0" mass="{M}" diaginertia="0.01 {IYY} 0.01"/>
    </body>
    <body name="free_arm" pos="0 1 0">
      <joint name="swing" type="hinge" axis="0 1 0" limited="false" range="-0.5 0.5"/>
      <inertial pos="{L} 0 0" mass="{M}" diaginertia="0.01 {IYY} 0.01"/>
    </body>
  </worldbody>
</mujoco>""")
    system = load_robot(str(xml), limits="stop")
    assert [tr.name for tr in system.transitions] == ["hinge_lower_limit", "hinge_upper_limit"]
    tr = simulate(system, [0.0] * 4, t_end=2.0, samples=False)
    event = tr.events[-1]
    assert tr.status == "joint_limit" and limit_of(event.name) == ("hinge", "upper")
    assert abs(event.t - time_to_angle(A, W2)) < 1e-9
    assert abs(event.x_pre[0] - A) < 1e-10


def _run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_the_command_line_stops_at_the_first_limit_and_reports_it(capsys, tmp_path):
    path = _urdf(tmp_path, "0 1 0", f'<limit lower="-0.5" upper="{A}" effort="1" velocity="1"/>')
    code, out, _ = _run(capsys, "simulate", path, "--fixed-base", "--limits", "stop", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["status"] == "joint_limit"
    hit = d["limit"]
    assert (hit["coordinate"], hit["bound"], hit["transition"]) == ("hinge", "upper", "hinge_upper_limit")
    assert abs(hit["t"] - time_to_angle(A, W2)) < 1e-9 and abs(hit["position"] - A) < 1e-10
    code, out, _ = _run(capsys, "simulate", path, "--fixed-base", "--limits", "stop")
    assert code == 0 and "hinge reached its upper limit at t = 0.4151411438" in out
    # the default is today's run: the joint passes its limit, and the JSON has no limit field
    code, out, _ = _run(capsys, "simulate", path, "--fixed-base", "--json")
    d = json.loads(out)
    assert code == 0 and d["status"] == "end_time" and "limit" not in d


def test_the_command_line_refuses_a_bad_value_and_warns_without_limits(capsys, tmp_path):
    path = _urdf(tmp_path, "0 1 0", "", kind="continuous")
    code, out, err = _run(capsys, "simulate", path, "--fixed-base", "--limits", "bounce")
    assert code == 2 and "--limits" in err and len(err.strip().splitlines()) == 1
    code, out, err = _run(capsys, "simulate", path, "--fixed-base", "--limits", "stop", "--time", "0.1", "--json")
    assert code == 0 and json.loads(out)["limit"] is None
    assert "no joint with a limit" in err
