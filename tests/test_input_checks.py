"""Model input refused where it is given: masses and inertias that no body has, model files that
exit or cannot be looked up, URDF files that are broken or contradict themselves; and the
recording budget bounding the memory a run takes."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import amble
from amble import Model, ModelError
from amble.cli.main import main
from amble.modelling.tree import Joint
from amble.models import load_file

ROOT = Path(__file__).resolve().parent.parent
WALKER = ROOT / "examples" / "my_walker.py"
BAD_NUMBERS = [-1.0, float("nan"), float("inf")]


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


# ---------------------------------------------------------------------------- masses and inertias
@pytest.mark.parametrize("mass", [0.0, *BAD_NUMBERS])
def test_a_point_mass_that_is_not_a_positive_number_is_refused_as_declared(mass):
    m = Model("pm")
    (th,) = m.coordinates("th")
    m.point("pivot", (0, 0))
    with pytest.raises(ModelError, match="'bob'"):
        m.point("bob", (th, -1), mass=mass)


@pytest.mark.parametrize("mass", BAD_NUMBERS)
def test_a_body_mass_that_is_negative_or_not_finite_names_the_body(mass):
    tree = Model("b", dims=3).rigid_tree()
    with pytest.raises(ModelError, match="body 'shank'"):
        tree.body("shank", joint=Joint("revolute", axis=(0, 1, 0)), mass=mass, com=(0, 0, -0.2),
                  inertia=((0.01, 0, 0), (0, 0.01, 0), (0, 0, 0.001)))


@pytest.mark.parametrize("where", ["inertia", "com"])
def test_a_body_inertial_that_is_not_finite_names_the_body(where):
    inertia = [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.001]]
    com = [0, 0, -0.2]
    if where == "inertia":
        inertia[1][1] = float("inf")
    else:
        com[2] = float("nan")
    tree = Model("b", dims=3).rigid_tree()
    with pytest.raises(ModelError, match="body 'shank'"):
        tree.body("shank", joint=Joint("revolute", axis=(0, 1, 0)), mass=1.0, com=com, inertia=inertia)


def test_a_massless_body_of_zero_inertia_still_declares():
    tree = Model("b", dims=3).rigid_tree()
    tree.body("frame", joint=Joint("revolute", axis=(0, 1, 0)))  # mass 0, zero inertia: a frame
    assert [str(q) for q in tree.model.q] == ["frame"]


@pytest.fixture(scope="module")
def walker():
    from amble.models import load_file

    return load_file(str(WALKER))


def test_a_mass_parameter_set_negative_is_refused_not_simulated(walker):
    # mh and m are the walker's masses and declare no domain: a negative value once ran and
    # ended as ``singular_mass``
    for name, value in (("mh", -10.0), ("m", 0.0)):
        with pytest.raises(amble.ParameterError, match=f"'{name}'"):
            amble.simulate(walker, params={name: value}, steps=1)
    assert amble.simulate(walker, params={"mh": 12.0}, steps=1).status == "completed"


@pytest.mark.parametrize("setting", ["mh=-10", "m=0"])
def test_the_command_line_refuses_a_bad_mass_in_one_line(capsys, setting):
    code, out, err = run(capsys, "simulate", WALKER, "--set", setting, "--steps", "2", "--json")
    assert code == 2, out
    assert err.count("\n") == 1 and setting.split("=")[0] in err, err
    assert json.loads(out)["type"] == "ParameterError"


def test_a_model_file_with_a_negative_body_mass_is_a_model_error(capsys, tmp_path):
    f = tmp_path / "neg.py"
    f.write_text(textwrap.dedent("""
        from amble import HybridSystem, Model
        from amble.modelling.tree import Joint

        def build():
            m = Model("neg", dims=3)
            m.gravity(9.81)
            m.rigid_tree().body("leg", joint=Joint("revolute", axis=(0, 1, 0)), mass=-2.0,
                                com=(0, 0, -0.5), inertia=((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.01)))
            return HybridSystem("neg", m, start=[0.1, 0.0])
    """), encoding="utf-8")
    code, out, err = run(capsys, "simulate", f, "--json")
    assert code == 2 and json.loads(out)["type"] == "ModelError"
    assert err.count("\n") == 1 and "body 'leg'" in err and ":8:" in err, err


# ---------------------------------------------------------------------------- model files and paths
@pytest.mark.parametrize("source, code", [
    ("import sys\n\ndef build():\n    sys.exit(0)\n", "0"),
    ("import sys\nsys.exit(3)\n", "3"),
], ids=["in-build", "at-module-level"])
def test_a_model_file_that_exits_is_a_model_error(capsys, tmp_path, source, code):
    f = tmp_path / "quits.py"
    f.write_text(source, encoding="utf-8")
    status, out, err = run(capsys, "simulate", f, "--json")
    assert status == 2
    assert json.loads(out)["type"] == "ModelError"
    assert err.count("\n") == 1 and f"sys.exit({code})" in err and "quits.py" in err, err
    with pytest.raises(ModelError, match=rf"sys.exit\({code}\)"):  # the API says so too
        load_file(str(f))


@pytest.mark.parametrize("path", ["a" * 5000 + ".py", "d/" * 3000 + "m.py:build"], ids=["long-name", "deep-path"])
def test_a_model_path_too_long_to_look_up_is_one_line(capsys, path):
    code, out, err = run(capsys, "equations", path)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "too long" in err and "internal" not in err, err
    assert len(err) < 300


# ---------------------------------------------------------------------------- URDF files
URDF = """<?xml version="1.0"?>
<robot name="t">
  <link name="base">
    <inertial><origin xyz="0 0 0"/><mass value="1"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="thigh">
    <inertial><origin xyz="0 0 -0.1"/><mass value="1"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="shank">
    <inertial><origin xyz="0 0 -0.1"/><mass value="1"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="hip" type="revolute">
    <parent link="base"/><child link="thigh"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="knee" type="revolute">
    <parent link="thigh"/><child link="shank"/><origin xyz="0 0 -0.2"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>
"""
SHANK_INERTIA = '<mass value="1"/>\n      <inertia ixx="0.01" iyy="0.01" izz="0.01"'
KNEE_END = '<limit lower="-1" upper="1" effort="1" velocity="1"/>\n  </joint>\n</robot>'


def _shank_inertia(ixx: str, iyy: str, izz: str) -> str:
    head, _, tail = URDF.rpartition(SHANK_INERTIA)
    return head + f'<mass value="1"/>\n      <inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}"' + tail


def _mimic(joint: str) -> str:
    return URDF.replace(KNEE_END, KNEE_END.replace("\n  </joint>", f'\n    <mimic joint="{joint}"/>\n  </joint>'))


@pytest.mark.parametrize("text, needle", [
    (URDF[:-30], "not well-formed XML"),                                 # cut short
    (URDF.replace('name="shank"', 'name="sh\0ank"', 1), "NUL byte"),
    (URDF.replace("<robot", "\0<robot"), "NUL byte"),
    (URDF.replace('link name="shank"', 'link name="thigh"'), "'thigh'"),  # two links of one name
    (_shank_inertia("1", "1", "5"), "'shank'"),                           # 5 > 1 + 1
    (_mimic("ankle"), "'ankle'"),
    (_shank_inertia("nan", "0.01", "0.01"), "'shank'"),
    (URDF.replace('<mass value="1"/>', '<mass value="inf"/>', 1), "'base'"),
], ids=["truncated", "nul-in-name", "nul-before-root", "duplicate-link", "triangle", "mimic-of-nothing",
        "nan-inertia", "inf-mass"])
def test_a_broken_or_contradictory_urdf_is_refused(tmp_path, text, needle):
    assert text != URDF
    path = tmp_path / "bad.urdf"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError, match=needle) as e:
        Model.from_urdf(path)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("text", [
    URDF,
    _shank_inertia("0.01", "0.01", "0.02000000000001"),  # a flat plate, rounded when written
    _mimic("hip"),
], ids=["as-is", "flat-plate", "mimic"])
def test_a_sound_urdf_still_loads(tmp_path, text):
    path = tmp_path / "ok.urdf"
    path.write_text(text, encoding="utf-8")
    # a knee that mimics the hip has no coordinate of its own
    assert [str(q) for q in Model.from_urdf(path).q] == (["hip"] if "<mimic" in text else ["hip", "knee"])


def test_a_link_of_zero_mass_and_inertia_still_loads(tmp_path):
    path = tmp_path / "light.urdf"
    path.write_text(URDF.replace('<mass value="1"/>', '<mass value="0"/>').replace(
        'ixx="0.01" iyy="0.01" izz="0.01"', 'ixx="0" iyy="0" izz="0"', 1), encoding="utf-8")
    assert len(Model.from_urdf(path).q) == 2


# ---------------------------------------------------------------------------- the recording budget
_MEASURE = """
import sys
import amble
from amble.models import load

budget = int(sys.argv[1])
system = load("compass-gait")
amble.simulate(system, steps=2)  # compiled and warm: the run below measures the recording only


def status(key):
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith(key))


with open("/proc/self/clear_refs", "w") as f:  # the peak (VmHWM) starts again from here
    f.write("5")
before = status("VmRSS")
tr = amble.simulate(system, t_end=1e4, sample_dt=1e-5, budget=budget)
print(tr.status, status("VmHWM") - before, len(tr.t))
"""


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="needs Linux's /proc peak reset")
def test_a_record_limited_run_takes_about_its_budget_in_memory():
    # 48 MiB: the compass gait's sample buffers double from 1.375 MiB to 44 MiB and the next
    # doubling would pass the budget; the recording then nearly fills it
    budget = 48 * 2**20
    out = subprocess.run([sys.executable, "-c", _MEASURE, str(budget)], capture_output=True, text=True,
                         timeout=300, check=True).stdout.split()
    status, growth, rows = out[0], int(out[1]), int(out[2])
    assert status == "record_limit"
    assert rows * (8 + 4 + 8 * 4) > budget / 2  # the run recorded most of what it may
    allowance = 8 * 2**20  # the trajectory object, messages, allocator slack
    assert growth <= 1.3 * budget + allowance, f"peak grew by {growth / 2**20:.1f} MiB for a 48 MiB budget"
