"""Robots of ``example-robot-data`` (published URDFs of real machines) against Pinocchio.

Each robot is loaded with ``Model.from_urdf`` (root link fixed to the world), built, and its mass
matrix ``M``, bias ``h = C q̇ + g`` and accelerations ``q̈`` compared with Pinocchio's ``crba``,
``rnea`` and ``M⁻¹(−h)`` at random states, to 1e-12 relative. Pinocchio's model is the one it
builds from the same file with every ``<mimic>`` ignored (one coordinate per moving joint),
projected onto the mimic relations read from the file here: with ``q_joints = G q + o``,
``M = Gᵀ M_joints G`` and ``h = Gᵀ h_joints`` — an independent reduced-coordinate computation;
the panda is also compared with Pinocchio's own mimic joints (``mimic=True``).

The last test loads every URDF the package ships and checks the outcome — loaded with so many
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


def _check(path: Path, states: int, seed: int = 11, model: Model | None = None) -> float:
    """The largest relative difference of M, h, q̈ from Pinocchio's, over ``states`` random states."""
    model = model or Model.from_urdf(path)
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
        qdd = k.rhs(0, 0.0, x, p)[len(names):]
        rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()  # noqa: E731
        worst = max(worst, rel(M, Mr), rel(h, hr), rel(qdd, np.linalg.solve(Mr, -hr)))
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
    "romeo_description/urdf/romeo.urdf",       # 33 coordinates; 22 finger joints mimic the hands
    "tiago_pro_description/robots/tiago_pro.urdf",
    "icub_description/robots/icub.urdf",       # point masses with inertias of rounding (1e-35 kg m²)
])
def test_large_robot_matches_pinocchio(robot):
    assert _check(ROBOTS / robot, states=10) <= 1e-12


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


def test_every_shipped_urdf_loads_or_is_refused_as_the_guide_says():
    listed = _listed()
    shipped = sorted(str(p.relative_to(ROBOTS)) for p in ROBOTS.rglob("*.urdf"))
    assert sorted(listed) == shipped
    for rel in shipped:
        got, want = _outcome(ROBOTS / rel), listed[rel]
        if want.startswith("loads"):
            assert got == want, rel
        else:  # the guide quotes the message: names in `backticks` for 'quotes', <tags> escaped
            reason = html.unescape(want.removeprefix("refused: ").replace("`", "'"))
            assert got.startswith("refused: ") and reason in got, (rel, got)
