"""Robots of ``example-robot-data`` (published URDFs of real machines) against Pinocchio.

Each robot is loaded with ``Model.from_urdf`` (root link fixed to the world), built, and its mass
matrix ``M``, bias ``h = C q̇ + g`` and accelerations ``q̈`` compared with Pinocchio's ``crba``,
``rnea`` and ``M⁻¹(−h)`` at random states, to 1e-12 relative. Pinocchio's model is the one it
builds from the same file with every ``<mimic>`` ignored (one coordinate per moving joint),
projected onto the mimic relations read from the file here: with ``q_joints = G q + o``,
``M = Gᵀ M_joints G`` and ``h = Gᵀ h_joints`` — an independent reduced-coordinate computation;
the panda is also compared with Pinocchio's own mimic joints (``mimic=True``).

The last tests load every URDF the package ships and check the outcome — loaded with so many
coordinates, or refused for the reason given — against the list in ``docs/guide/urdf.md``.
"""

from __future__ import annotations

import html
import importlib.metadata
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from amble import HybridSystem, Model
from amble.backend.kernels import build
from amble.errors import ModelError

ROOT = Path(__file__).resolve().parent.parent


def _robots() -> Path:
    """The ``robots`` directory of the installed ``example-robot-data`` (its files are listed in
    the distribution's record: the package has no Python module to ask)."""
    dist = importlib.metadata.distribution("example-robot-data")
    files = [f for f in dist.files or () if str(f).endswith(".urdf")]
    assert files, "example-robot-data lists no URDF"
    path = Path(dist.locate_file(files[0]))
    while path.name != "robots":
        path = path.parent
    return path


ROBOTS = _robots()


def _mimic_map(path: Path) -> dict[str, tuple[str, float, float]]:
    """Moving joint → (joint at the end of its mimic chain, multiplier, offset), from the file."""
    root = ET.parse(path).getroot()
    kind = {j.get("name"): j.get("type") for j in root.findall("joint")}
    direct = {}
    for j in root.findall("joint"):
        mm = j.find("mimic")
        if mm is not None and j.get("type") != "fixed":
            direct[j.get("name")] = (mm.get("joint"), float(mm.get("multiplier", 1)), float(mm.get("offset", 0)))
    out = {}
    for name in direct:
        k, c, cur = 1.0, 0.0, name
        while cur in direct:
            ref, kk, cc = direct[cur]
            k, c, cur = k * kk, k * cc + c, ref
        assert kind[cur] != "fixed"
        out[name] = (cur, k, c)
    return out


def _check(path: Path, states: int, seed: int = 11, massless: bool = False) -> float:
    """The largest relative difference of M and h from Pinocchio's over ``states`` random states,
    and of M q̈ + h from zero relative to |M q̈| + |h| (the accelerations' backward error: their
    forward error is that times M's condition number, 1e7 for iCub's point masses) — unless
    ``massless`` links are allowed, where M may be singular and q̈ is not asked for."""
    model = Model.from_urdf(path, allow_massless=massless)
    k = build(HybridSystem(model.name, model))
    p = np.array(k.meta["param_defaults"], dtype=float)
    names = [str(s) for s in model.q]
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    mimic = _mimic_map(path)
    moving = [pm.names[i] for i in range(1, pm.njoints)]
    assert sorted(names) == sorted(j for j in moving if j not in mimic)
    col = {s: i for i, s in enumerate(names)}
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(states):
        q, v = rng.uniform(-1.5, 1.5, len(names)), rng.uniform(-2.0, 2.0, len(names))
        G = np.zeros((pm.nv, len(names)))
        qp = pin.neutral(pm)
        for jname in moving:
            jm = pm.joints[pm.getJointId(jname)]
            ref, kk, cc = mimic.get(jname, (jname, 1.0, 0.0))
            G[jm.idx_v, col[ref]] = kk
            a = kk * q[col[ref]] + cc
            if jm.nq == 2:  # a continuous joint: (cos, sin)
                qp[jm.idx_q:jm.idx_q + 2] = np.cos(a), np.sin(a)
            else:
                qp[jm.idx_q] = a
        vp = G @ v
        Mp = pin.crba(pm, pd, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T  # Pinocchio fills the upper triangle
        hp = pin.rnea(pm, pd, qp, vp, np.zeros(pm.nv))
        Mr, hr = G.T @ Mp @ G, G.T @ hp
        x = np.concatenate([q, v])
        M, h, _ = k.dynamics(0, 0.0, x, p)
        rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()  # noqa: E731
        worst = max(worst, rel(M, Mr), rel(h, hr))
        if not massless:
            qdd = k.rhs(0, 0.0, x, p)[len(names):]
            r = Mr @ qdd + hr + G.T @ (pm.damping * vp)  # the file's joint damping, as Pinocchio reads it
            worst = max(worst, np.abs(r).max() / (np.abs(Mr @ qdd).max() + np.abs(hr).max()))
    return worst


@pytest.mark.parametrize("robot", [
    "solo_description/robots/solo12.urdf",              # a quadruped, 12 revolute joints
    "panda_description/urdf/panda.urdf",                # an arm whose second finger mimics the first
    "anymal_b_simple_description/robots/anymal.urdf",   # a base inertia with eigenvalues -2e-22, 9e-23
    "talos_data/robots/talos_left_arm.urdf",            # Talos' arm: point-mass sensor frames, <mimic> on fixed joints
])
def test_robot_matches_pinocchio(robot):
    assert _check(ROBOTS / robot, states=30) <= 1e-12


@pytest.mark.slow
@pytest.mark.parametrize("robot", [
    "talos_data/robots/talos_full_v2.urdf",    # 32 coordinates; 24 gripper joints mimic two
    "tiago_pro_description/robots/tiago_pro.urdf",   # 23 coordinates; 10 gripper joints mimic two
    "icub_description/robots/icub.urdf",       # point masses with inertias of rounding (1e-35 kg m²)
])
def test_large_robot_matches_pinocchio(robot):
    assert _check(ROBOTS / robot, states=10) <= 1e-12


@pytest.mark.slow
def test_romeo_matches_pinocchio_with_its_massless_fingers():
    """Romeo: 33 coordinates, 22 finger joints mimicking the hands — and its fingers have zero
    mass and inertia, so it loads only with ``allow_massless=True`` and M is singular (Pinocchio's
    too): M and h are compared."""
    assert _check(ROBOTS / "romeo_description/urdf/romeo.urdf", states=10, massless=True) <= 1e-12


def test_panda_fingers_match_pinocchio_mimic_joints():
    """The panda's second finger against Pinocchio's own mimic joint: one coordinate for both."""
    path = ROBOTS / "panda_description/urdf/panda.urdf"
    model = Model.from_urdf(path)
    names = [str(s) for s in model.q]
    assert "panda_finger_joint1" in names and "panda_finger_joint2" not in names
    k = build(HybridSystem(model.name, model))
    pm = pin.buildModelFromUrdf(str(path), mimic=True)
    pd = pm.createData()
    assert pm.nv == len(names)
    iv = [pm.joints[pm.getJointId(s)].idx_v for s in names]
    rng = np.random.default_rng(2)
    for _ in range(20):
        q, v = rng.uniform(-1.5, 1.5, len(names)), rng.uniform(-2.0, 2.0, len(names))
        qp, vp = np.zeros(pm.nq), np.zeros(pm.nv)
        qp[iv], vp[iv] = q, v
        M, h, _ = k.dynamics(0, 0.0, np.concatenate([q, v]), np.zeros(1))
        Mp = pin.crba(pm, pd, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        hp = pin.rnea(pm, pd, qp, vp, np.zeros(pm.nv))
        assert np.abs(M - Mp[np.ix_(iv, iv)]).max() <= 1e-12 * np.abs(Mp).max()
        assert np.abs(h - hp[iv]).max() <= 1e-12 * np.abs(hp).max()
    # the fingers move together: the right finger's position follows the left's
    assert model.tree["panda_rightfinger"].coordinate == model.symbol("panda_finger_joint1")


# ---------------------------------------------------------------------------- every shipped URDF
def _listed() -> dict[str, str]:
    """The docs' list: file → ``loads: N coordinates`` or ``refused: <reason>``."""
    text = (ROOT / "docs" / "guide" / "urdf.md").read_text(encoding="utf-8")
    return {m[1]: m[2].strip() for m in re.finditer(r"^\| `([^`]+\.urdf)` \| (.+?) \|$", text, flags=re.M)}


def _outcome(path: Path) -> str:
    try:
        return f"loads: {len(Model.from_urdf(path).q)} coordinates"
    except ModelError as e:
        return f"refused: {e}"


def _rounding(text: str) -> str:
    """``text`` with numbers below 1e-15 in size (eigenvalues of rounding, which differ in their
    digits from one linear-algebra library to another) written as ``≈0``."""
    return re.sub(r"-?\d+(?:\.\d+)?e-(?:1[6-9]|[2-9]\d|\d{3})", "≈0", text)


def _shipped() -> list[str]:
    return sorted(str(p.relative_to(ROBOTS)) for p in ROBOTS.rglob("*.urdf"))


def test_the_guide_lists_every_shipped_urdf():
    assert sorted(_listed()) == _shipped()


def _cases() -> list:
    """One case a file; a robot of more than 20 coordinates (a second or more to build its
    tree) in the slow run."""
    listed = _listed()
    out = []
    for rel in _shipped():
        n = re.match(r"loads: (\d+) coordinates", listed.get(rel, ""))
        out.append(pytest.param(rel, marks=pytest.mark.slow) if n and int(n[1]) > 20 else rel)
    return out


@pytest.mark.parametrize("rel", _cases())
def test_a_shipped_urdf_loads_or_is_refused_as_the_guide_says(rel):
    got, want = _outcome(ROBOTS / rel), _listed()[rel]
    if want.startswith("loads"):
        assert got == want
    else:  # the guide quotes the message: names in `backticks` for 'quotes', <tags> escaped
        reason = html.unescape(want.removeprefix("refused: ").replace("`", "'"))
        assert got.startswith("refused: ") and _rounding(reason) in _rounding(got), got


def test_human_loads_with_massless_links_by_consent():
    """``human.urdf`` builds its ball joints from links without inertials moved by joints: refused
    by default (listed above), loaded when they are allowed."""
    model = Model.from_urdf(ROBOTS / "human_description/robots/human.urdf", allow_massless=True)
    assert len(model.q) == 36


# ---------------------------------------------------------------------------- small files
def _link(name: str, mass: float = 1.0, inertia: str = "0.02 0 0 0.03 0 0.04", com: str = "0.01 -0.02 -0.1") -> str:
    i = dict(zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), inertia.split()))
    attrs = " ".join(f'{k}="{v}"' for k, v in i.items())
    return (f'<link name="{name}"><inertial><origin xyz="{com}" rpy="0.1 0.2 0.3"/><mass value="{mass}"/>'
            f"<inertia {attrs}/></inertial></link>")


def _joint(name: str, parent: str, child: str, kind: str = "revolute", axis: str = "0 1 0",
           xyz: str = "0.05 0.02 -0.3", mimic: str = "") -> str:
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="0.3 -0.2 0.1"/><axis xyz="{axis}"/>'
            f'<limit lower="-2" upper="2" effort="1" velocity="1"/>{mimic}</joint>')


def _robot(tmp_path: Path, *parts: str) -> Path:
    path = tmp_path / "robot.urdf"
    path.write_text('<robot name="r">' + "".join(parts) + "</robot>", encoding="utf-8")
    return path


def _mimic(joint: str, k: float = 1.0, c: float = 0.0) -> str:
    return f'<mimic joint="{joint}" multiplier="{k}" offset="{c}"/>'


def test_mimic_joints_match_pinocchio_projected(tmp_path):
    """Mimics of every kind on one tree: a sibling branch listed before the joint it follows (the
    tree is reordered), a mimic below the joint it follows (its terms meet on M's diagonal), a
    chain (a mimic of a mimic: ``q = k₁(k₂ a + c₂) + c₁``), a prismatic joint following a
    revolute one; multipliers and offsets other than 1 and 0. Against Pinocchio without mimics,
    projected on the relations."""
    path = _robot(
        tmp_path,
        _link("base"), _link("a"), _link("b", 0.5), _link("c", 0.3), _link("d", 0.2), _link("e", 0.7),
        _joint("jb", "base", "b", axis="1 0 0", mimic=_mimic("ja", -0.7, 0.2)),   # before its reference
        _joint("ja", "base", "a"),
        _joint("jc", "a", "c", axis="0 0 1", mimic=_mimic("ja", 1.5, -0.1)),     # below its reference
        _joint("jd", "c", "d", kind="prismatic", axis="0 0 1", mimic=_mimic("jb", 0.05, 0.01)),  # a chain
        _joint("je", "a", "e", axis="0.6 0 0.8"),
    )
    model = Model.from_urdf(path)
    assert [str(s) for s in model.q] == ["ja", "je"]
    qd, ja = model.tree["d"].coordinate, model.symbol("ja")   # 0.05 (−0.7 ja + 0.2) + 0.01
    assert float(qd.coeff(ja)) == pytest.approx(-0.035, rel=1e-15)
    assert float(qd.subs(ja, 0)) == pytest.approx(0.02, rel=1e-15)
    assert _check(path, states=20) <= 1e-12


@pytest.mark.parametrize("parts, needle", [
    ((_joint("ja", "base", "a", mimic=_mimic("jb")), _joint("jb", "a", "b", mimic=_mimic("ja"))),
     "follow each other in a loop"),
    ((_joint("ja", "base", "a", kind="fixed"), _joint("jb", "a", "b", mimic=_mimic("ja"))), "'ja', which is fixed"),
    ((_joint("ja", "base", "a", mimic=_mimic("jb")), _joint("jb", "a", "b")), "only moves links below it"),
], ids=["loop", "of-a-fixed-joint", "of-a-descendant"])
def test_a_mimic_that_cannot_be_is_refused(tmp_path, parts, needle):
    path = _robot(tmp_path, _link("base"), _link("a"), _link("b"), *parts)
    with pytest.raises(ModelError, match=needle):
        Model.from_urdf(path)


def test_a_fixed_joints_mimic_is_dropped(tmp_path):
    path = _robot(tmp_path, _link("base"), _link("a"), _link("b"), _joint("ja", "base", "a"),
                  _joint("jb", "a", "b", kind="fixed", mimic=_mimic("ja")))
    assert [str(s) for s in Model.from_urdf(path).q] == ["ja"]


# the inertias of real files: Talos' sensor frames, iCub's head, a thin rod, ANYmal's base
POINT = "0 0 0 0 0 0"
ICUB_HEAD = "0 0 2.40741e-35 0 0 0"
ROD = "0 0 0 1.2e-4 0 1.2e-4"
ANYMAL_BASE = "3e-06 0 0 0 0 0"   # principal moments 3e-6, 0, 0: a placeholder no rigid body has
ANYMAL_ROUNDED = "1.5e-06 1.5e-06 0 1.5e-06 0 0"   # eigenvalues 3e-6 and two of rounding, like the file's


def test_physical_inertias_load_and_match_pinocchio(tmp_path):
    """A point mass on a moving link and on a fixed sensor frame, a point mass whose written
    inertia is rounding (1e-35 kg m²), a thin rod (one zero moment) and ANYmal's base placeholder
    as the fixed base: all load, and the dynamics equal Pinocchio's."""
    path = _robot(
        tmp_path,
        _link("base", 1e-6, ANYMAL_ROUNDED), _link("arm", 2.0, ROD), _link("hand", 1.33687, ICUB_HEAD),
        _link("sensor", 0.01, POINT), _link("tip", 0.2, POINT),
        _joint("j1", "base", "arm"), _joint("j2", "arm", "hand", axis="1 0 0"),
        _joint("fix", "hand", "sensor", kind="fixed"), _joint("j3", "hand", "tip", kind="prismatic"),
    )
    assert [str(s) for s in Model.from_urdf(path).q] == ["j1", "j2", "j3"]
    assert _check(path, states=20) <= 1e-12


@pytest.mark.parametrize("inertia, mass, needle", [
    ("-3.53e-08 0 0 3.5e-08 0 9.09e-08", 1e-6, "negative principal moment"),   # TIAGo's antenna
    ("0.001 0 0 0.001 0 0.01", 0.1, "triangle inequality"),                     # the PR2's sensor mount
    (ANYMAL_BASE, 1e-6, "triangle inequality"),                                 # on a link that moves
    ("1e-20 0 0 -1e-20 0 0", 0.0, "negative principal moment"),                 # massless: no scale of mass
    (POINT, -0.01, "negative mass"),
], ids=["negative", "triangle", "placeholder-that-moves", "massless-negative", "negative-mass"])
def test_an_unphysical_inertia_is_refused_naming_its_link(tmp_path, inertia, mass, needle):
    path = _robot(tmp_path, _link("base"), _link("arm"), _link("bad", mass, inertia),
                  _joint("j1", "base", "arm"), _joint("j2", "arm", "bad"))
    with pytest.raises(ModelError, match=needle) as e:
        Model.from_urdf(path)
    assert "'bad'" in str(e.value)


def test_massless_frames_on_fixed_joints_are_merged_into_their_body(tmp_path):
    """Two massless frames on fixed joints (one without an inertial, one of zero mass and inertia)
    between two moving links are no bodies: each is a point of the body it hangs from, at the
    place of Pinocchio's frame of that name, a contact point on one is placed through it, and
    the link below hangs through both with M, h, q̈ equal to Pinocchio's."""
    import sympy as sp

    path = _robot(
        tmp_path,
        _link("base"), _link("arm"), '<link name="mount"/>', _link("camera", 0.0, POINT), _link("hand", 0.4),
        _joint("j1", "base", "arm"), _joint("f1", "arm", "mount", kind="fixed"),
        _joint("f2", "mount", "camera", kind="fixed", xyz="0.1 0 0.02"),
        _joint("j2", "camera", "hand", axis="1 0 0"),
    )
    model = Model.from_urdf(path, contact_points={"lens": ("camera", (0.01, 0.02, 0.03))})
    assert [b.name for b in model.tree.bodies] == ["arm", "hand"]
    assert _check(path, states=10) <= 1e-12
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    q = np.array([0.7, -0.4])
    pin.framesForwardKinematics(pm, pd, q)  # both coordinates are revolute: q in the same order
    assert [str(s) for s in model.q] == [pm.names[1], pm.names[2]]
    for name, at in (("mount", (0, 0, 0)), ("camera", (0, 0, 0)), ("lens", (0.01, 0.02, 0.03))):
        oMf = pd.oMf[pm.getFrameId("camera" if name == "lens" else name)]
        want = oMf.translation + oMf.rotation @ np.asarray(at)
        got = np.asarray(sp.lambdify(model.q, model.points[name])(*q), dtype=float).ravel()
        assert np.abs(got - want).max() <= 1e-14


def test_a_moving_link_of_zero_mass_and_inertia_needs_consent(tmp_path):
    """Like a link without an inertial (Romeo's fingers): its joint would have no inertia."""
    path = _robot(tmp_path, _link("base"), _link("arm", 0.0, POINT), _link("hand"),
                  _joint("j1", "base", "arm"), _joint("j2", "arm", "hand"))
    with pytest.raises(ModelError, match="'arm' is moved by joint 'j1' but has an inertial of zero mass"):
        Model.from_urdf(path)
    assert [str(s) for s in Model.from_urdf(path, allow_massless=True).q] == ["j1", "j2"]
