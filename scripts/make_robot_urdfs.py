"""Write the robots of tests/data as URDF files: a 5-link planar biped (RABBIT proportions), a
12-DOF 3D biped and a 30-DOF humanoid. Run from the repository root:
``python scripts/make_robot_urdfs.py``.

Links are uniform boxes/rods (inertia from their size), with small offsets and tilts in joint
origins and centres of mass so that no term of the equations vanishes by symmetry.
"""

from __future__ import annotations

from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "tests" / "data"


def _f(xs) -> str:
    return " ".join(f"{x:.6g}" for x in xs)


def box_inertia(m: float, sx: float, sy: float, sz: float, skew: float = 0.0) -> dict:
    ixx, iyy, izz = m * (sy**2 + sz**2) / 12, m * (sx**2 + sz**2) / 12, m * (sx**2 + sy**2) / 12
    k = skew * min(ixx, iyy, izz)
    return dict(ixx=ixx, iyy=iyy, izz=izz, ixy=0.3 * k, ixz=-0.2 * k, iyz=0.1 * k)


class Urdf:
    def __init__(self, name: str) -> None:
        self.parts = [f'<?xml version="1.0"?>\n<robot name="{name}">']

    def link(self, name: str, mass: float, com=(0, 0, 0), inertia: dict | None = None, rpy=(0, 0, 0)) -> None:
        ine = inertia or box_inertia(mass, 0.1, 0.1, 0.1)
        attrs = " ".join(f'{k}="{v:.8g}"' for k, v in ine.items())
        self.parts.append(
            f'  <link name="{name}">\n    <inertial>\n      <origin xyz="{_f(com)}" rpy="{_f(rpy)}"/>\n'
            f'      <mass value="{mass:.8g}"/>\n      <inertia {attrs}/>\n    </inertial>\n  </link>')

    def joint(self, name: str, parent: str, child: str, axis=(0, 1, 0), xyz=(0, 0, 0), rpy=(0, 0, 0),
              kind: str = "revolute", limit=(-3.0, 3.0)) -> None:
        lim = f'\n    <limit lower="{limit[0]}" upper="{limit[1]}" effort="100" velocity="10"/>' \
            if kind in ("revolute", "prismatic") else ""
        ax = f'\n    <axis xyz="{_f(axis)}"/>' if kind != "fixed" else ""
        self.parts.append(
            f'  <joint name="{name}" type="{kind}">\n    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
            f'    <origin xyz="{_f(xyz)}" rpy="{_f(rpy)}"/>{ax}{lim}\n  </joint>')

    def write(self, path: Path) -> None:
        path.write_text("\n".join(self.parts) + "\n</robot>\n")


def rabbit() -> Urdf:
    """5-link planar biped: torso 20 kg, 0.625 m; femurs 6.8 kg, tibias 3.2 kg, 0.4 m; joints about y."""
    u = Urdf("rabbit")
    u.link("torso", 20.0, com=(0, 0, 0.24), inertia=box_inertia(20.0, 0.1, 0.1, 0.625))
    for side in ("left", "right"):
        u.link(f"{side}_femur", 6.8, com=(0, 0, -0.11), inertia=box_inertia(6.8, 0.06, 0.06, 0.4))
        u.link(f"{side}_tibia", 3.2, com=(0, 0, -0.24), inertia=box_inertia(3.2, 0.05, 0.05, 0.4))
        u.joint(f"{side}_hip", "torso", f"{side}_femur")
        u.joint(f"{side}_knee", f"{side}_femur", f"{side}_tibia", xyz=(0, 0, -0.4))
        u.parts.append(f'  <link name="{side}_foot"/>')  # the tibia's tip: a frame, no mass
        u.joint(f"{side}_ankle", f"{side}_tibia", f"{side}_foot", xyz=(0, 0, -0.4), kind="fixed")
    return u


def _leg(u: Urdf, side: str, parent: str, sign: float) -> None:
    y = 0.09 * sign
    u.link(f"{side}_hip_yaw_link", 1.2, com=(0.01, 0.0, -0.03), inertia=box_inertia(1.2, 0.08, 0.06, 0.07, 0.5))
    u.link(f"{side}_hip_roll_link", 1.5, com=(0.0, 0.01 * sign, -0.02), inertia=box_inertia(1.5, 0.07, 0.08, 0.06, 0.4))
    u.link(f"{side}_thigh", 6.0, com=(0.01, 0.005 * sign, -0.17), inertia=box_inertia(6.0, 0.1, 0.1, 0.4, 0.6))
    u.link(f"{side}_shin", 3.0, com=(0.0, 0.0, -0.18), inertia=box_inertia(3.0, 0.08, 0.08, 0.4, 0.3))
    u.link(f"{side}_ankle_link", 0.4, com=(0.0, 0.0, -0.01), inertia=box_inertia(0.4, 0.05, 0.05, 0.04, 0.2))
    u.link(f"{side}_foot", 1.0, com=(0.04, 0.0, -0.04), inertia=box_inertia(1.0, 0.22, 0.1, 0.04, 0.5))
    u.joint(f"{side}_hip_yaw", parent, f"{side}_hip_yaw_link", axis=(0, 0, 1), xyz=(0.0, y, -0.1),
            rpy=(0.02 * sign, 0.0, 0.0))
    u.joint(f"{side}_hip_roll", f"{side}_hip_yaw_link", f"{side}_hip_roll_link", axis=(1, 0, 0), xyz=(0, 0, -0.06))
    u.joint(f"{side}_hip_pitch", f"{side}_hip_roll_link", f"{side}_thigh", axis=(0, 1, 0), xyz=(0, 0.01 * sign, 0))
    u.joint(f"{side}_knee", f"{side}_thigh", f"{side}_shin", axis=(0, 1, 0), xyz=(0.005, 0, -0.4),
            rpy=(0.0, 0.05, 0.0))
    u.joint(f"{side}_ankle_pitch", f"{side}_shin", f"{side}_ankle_link", axis=(0, 1, 0), xyz=(0, 0, -0.4))
    u.joint(f"{side}_ankle_roll", f"{side}_ankle_link", f"{side}_foot", axis=(1, 0, 0), xyz=(0, 0, -0.02))


def biped12() -> Urdf:
    u = Urdf("biped12")
    u.link("torso", 15.0, com=(0.01, 0.0, 0.2), inertia=box_inertia(15.0, 0.2, 0.3, 0.5, 0.3))
    for side, sign in (("left", 1.0), ("right", -1.0)):
        _leg(u, side, "torso", sign)
    return u


def humanoid30() -> Urdf:
    """The 12-DOF legs, a 3-DOF waist, two 7-DOF arms and a 1-DOF neck: 30 joints."""
    u = Urdf("humanoid30")
    u.link("pelvis", 8.0, com=(0.0, 0.0, 0.02), inertia=box_inertia(8.0, 0.2, 0.3, 0.15, 0.3))
    for side, sign in (("left", 1.0), ("right", -1.0)):
        _leg(u, side, "pelvis", sign)
    u.link("waist_yaw_link", 1.0, com=(0, 0, 0.02), inertia=box_inertia(1.0, 0.08, 0.08, 0.06, 0.3))
    u.link("waist_pitch_link", 1.0, com=(0.01, 0, 0.01), inertia=box_inertia(1.0, 0.08, 0.08, 0.06, 0.3))
    u.link("chest", 12.0, com=(0.0, 0.0, 0.2), inertia=box_inertia(12.0, 0.2, 0.3, 0.4, 0.4))
    u.joint("waist_yaw", "pelvis", "waist_yaw_link", axis=(0, 0, 1), xyz=(0, 0, 0.1))
    u.joint("waist_pitch", "waist_yaw_link", "waist_pitch_link", axis=(0, 1, 0), xyz=(0, 0, 0.05))
    u.joint("waist_roll", "waist_pitch_link", "chest", axis=(1, 0, 0), xyz=(0, 0, 0.02))
    u.link("head", 3.0, com=(0.01, 0, 0.1), inertia=box_inertia(3.0, 0.15, 0.15, 0.2, 0.2))
    u.joint("neck", "chest", "head", axis=(0, 0, 1), xyz=(0, 0, 0.45))
    arm = [("shoulder_pitch", (0, 1, 0), 0.8), ("shoulder_roll", (1, 0, 0), 0.8), ("shoulder_yaw", (0, 0, 1), 1.5),
           ("elbow", (0, 1, 0), 1.0), ("wrist_yaw", (0, 0, 1), 0.5), ("wrist_pitch", (0, 1, 0), 0.3),
           ("wrist_roll", (1, 0, 0), 0.4)]
    for side, sign in (("left", 1.0), ("right", -1.0)):
        parent, xyz = "chest", (0.0, 0.2 * sign, 0.38)
        for name, axis, mass in arm:
            child = f"{side}_{name}_link"
            u.link(child, mass, com=(0.01, 0.0, -0.05), inertia=box_inertia(mass, 0.06, 0.06, 0.15, 0.4))
            u.joint(f"{side}_{name}", parent, child, axis=axis, xyz=xyz, rpy=(0.01 * sign, 0.0, 0.0))
            parent = child
            xyz = (0.0, 0.0, -0.25) if name in ("shoulder_yaw", "elbow") else (0.0, 0.0, -0.03)
    return u


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for name, make in (("rabbit", rabbit), ("biped12", biped12), ("humanoid30", humanoid30)):
        make().write(OUT / f"{name}.urdf")
        print(OUT / f"{name}.urdf")


if __name__ == "__main__":
    main()
