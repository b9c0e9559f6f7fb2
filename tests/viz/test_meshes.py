"""Visual meshes of URDF robots in the 3D viewer.

The loader is checked against trimesh reading the mesh file directly and placing it with the
visual's origin built here from the URDF's roll-pitch-yaw convention (NumPy); the link poses
against yourdfpy's own forward kinematics of the same file; the page against its size budget; and,
in headless Chromium, Bolt's meshes are drawn and in frame.
"""

from __future__ import annotations

import importlib.metadata
import shutil
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
yourdfpy = pytest.importorskip("yourdfpy")

from test_html import HEIGHT, WIDTH, _chromium, _finish, _read_png, needs_chromium  # noqa: E402

from amble import simulate  # noqa: E402
from amble.models import load_robot  # noqa: E402
from amble.viz.animate import scene_of  # noqa: E402
from amble.viz.errors import SceneError  # noqa: E402
from amble.viz.html import render_html, write_html  # noqa: E402
from amble.viz.links import link_poses  # noqa: E402
from amble.viz.meshes import decimate, decode, encode, urdf_visuals, within_budget  # noqa: E402
from amble.viz.scene import Mesh, frames  # noqa: E402


def _robots() -> Path:
    dist = importlib.metadata.distribution("example-robot-data")
    f = next(f for f in dist.files or () if str(f).endswith("bolt.urdf"))
    return Path(dist.locate_file(f)).parents[2]


ROBOTS = _robots()
BOLT = ROBOTS / "bolt_description" / "robots" / "bolt.urdf"
LEG_STL = ROBOTS / "bolt_description" / "meshes" / "stl" / "upper_leg_200mm_left_side.stl"


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    """URDF origin rotation: about fixed x by roll, then y by pitch, then z by yaw."""
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


XYZ, RPY, SCALE = np.array([0.1, -0.2, 0.3]), (0.3, -0.5, 1.1), np.array([1.0, 2.0, 0.5])


def _urdf(tmp_path: Path) -> Path:
    """A one-link robot with a scaled mesh (a package:// path) and three primitives, each at an
    origin, in a ROS-like package layout."""
    pkg = tmp_path / "my_robot"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    shutil.copy(LEG_STL, pkg / "meshes" / "leg.stl")
    origin = f'<origin xyz="{" ".join(map(str, XYZ))}" rpy="{" ".join(map(str, RPY))}"/>'
    text = f"""<robot name="probe">
  <material name="red"><color rgba="0.9 0.1 0.1 1"/></material>
  <link name="body">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual>{origin}<geometry><mesh filename="package://my_robot/meshes/leg.stl" scale="1 2 0.5"/></geometry>
      <material name="red"/></visual>
    <visual>{origin}<geometry><box size="0.1 0.2 0.4"/></geometry></visual>
    <visual>{origin}<geometry><cylinder radius="0.05" length="0.3"/></geometry>
      <material name="c"><color rgba="0.2 0.3 0.4 0.5"/></material></visual>
    <visual><origin xyz="0 0 1"/><geometry><sphere radius="0.07"/></geometry></visual>
  </link>
</robot>"""
    path = pkg / "urdf" / "probe.urdf"
    path.write_text(text)
    return path


def test_visuals_are_placed_by_their_origin_and_scale(tmp_path):
    visuals = urdf_visuals(_urdf(tmp_path))
    assert [v.link for v in visuals] == ["body"] * 4
    mesh, box, cyl, ball = visuals
    R = _rpy(*RPY)
    raw = trimesh.load(str(LEG_STL), force="mesh")
    expect = (np.asarray(raw.vertices) * SCALE) @ R.T + XYZ
    assert mesh.vertices.shape == expect.shape and len(mesh.faces) == len(raw.faces)
    np.testing.assert_allclose(mesh.vertices, expect, atol=1e-12)
    np.testing.assert_allclose(mesh.vertices.min(axis=0), expect.min(axis=0), atol=1e-12)
    assert mesh.color == (0.9, 0.1, 0.1)       # a material named at the robot's top
    # primitives: back in the visual's own frame, the box's corners are at ±size/2 ...
    local = (box.vertices - XYZ) @ R
    np.testing.assert_allclose(np.abs(local).max(axis=0), [0.05, 0.1, 0.2], atol=1e-12)
    np.testing.assert_allclose(np.abs(local), np.broadcast_to([0.05, 0.1, 0.2], local.shape), atol=1e-12)
    # ... the cylinder's axis is z, radius 5 cm, 30 cm long, centred
    local = (cyl.vertices - XYZ) @ R
    r = np.hypot(local[:, 0], local[:, 1])
    assert r.max() == pytest.approx(0.05, abs=1e-12) and np.ptp(local[:, 2]) == pytest.approx(0.3, abs=1e-12)
    assert local[:, 2].min() == pytest.approx(-0.15, abs=1e-12)
    assert (cyl.color, cyl.opacity) == ((0.2, 0.3, 0.4), 0.5)
    np.testing.assert_allclose(np.linalg.norm(ball.vertices - [0, 0, 1], axis=1), 0.07, atol=1e-12)


def test_package_paths_of_example_robot_data_resolve():
    visuals = urdf_visuals(BOLT)
    root = yourdfpy.URDF.load(str(BOLT), load_meshes=False, build_scene_graph=False).robot
    expected = [lk.name for lk in root.links for v in lk.visuals]
    assert [v.link for v in visuals] == expected and len(expected) == 9
    counts = []
    for lk in root.links:
        for v in lk.visuals:
            rel = v.geometry.mesh.filename.replace("package://example-robot-data/robots/", "")
            counts.append(len(trimesh.load(str(ROBOTS / rel), force="mesh").faces))
    assert [len(v.faces) for v in visuals] == counts


def test_a_missing_mesh_is_left_out_with_a_warning(tmp_path):
    path = _urdf(tmp_path)
    (path.parents[1] / "meshes" / "leg.stl").unlink()
    with pytest.warns(UserWarning, match="leg.stl.*not found"):
        visuals = urdf_visuals(path)
    assert len(visuals) == 3


def test_decimation_keeps_the_shape_within_the_count():
    sphere = trimesh.creation.icosphere(subdivisions=5)      # 20480 triangles of the unit sphere
    v, f = decimate(sphere.vertices, sphere.faces, 2000)
    assert 500 < len(f) <= 2000
    r = np.linalg.norm(v, axis=1)
    assert r.max() <= 1 + 1e-12 and r.min() > 0.9             # cluster means lie just inside
    assert f.max() < len(v) and len(np.unique(f)) == len(v)    # no dangling vertex
    small = trimesh.creation.box()
    v, f = decimate(small.vertices, small.faces, 100)
    assert len(f) == 12                                        # within the count: untouched


def test_encoding_round_trips_to_a_fraction_of_the_quantum():
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    enc = encode(sphere.vertices, sphere.faces)
    v, f = decode(enc)
    step = np.asarray(enc["step"])
    assert np.all(np.abs(v - sphere.vertices) <= step / 2 + 1e-15)
    np.testing.assert_array_equal(f, sphere.faces)
    assert not enc["wide"] and enc["triangles"] == len(sphere.faces)


def test_a_mesh_needs_its_frame_and_its_triangles():
    t = np.array([0.0, 0.1])
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    meshes = {"m": encode(box.vertices, box.faces)}
    still = (np.array([[0.0, 0.0, 1.0]] * 2), np.stack([np.eye(3)] * 2))
    with pytest.raises(SceneError, match="unknown frame 'arm'"):
        frames([Mesh("arm", "m")], {}, t, poses={}, meshes=meshes)
    with pytest.raises(SceneError, match="unknown mesh 'n'"):
        frames([Mesh("arm", "n")], {}, t, poses={"arm": still}, meshes=meshes)
    with pytest.raises(SceneError, match="shapes"):
        frames([Mesh("arm", "m")], {}, t, poses={"arm": (still[0][:1], still[1])}, meshes=meshes)
    scene = frames([Mesh("arm", "m")], {}, t, poses={"arm": still}, meshes=meshes)
    assert scene["poses"]["arm"] == [0, 0, 1, 0, 0, 0, 1] * 2          # x, y, z, then (x, y, z, w)
    # the bounds are the box's, where the pose puts it
    assert scene["bounds"] == {"min": [-0.05, -0.1, 0.85], "max": [0.05, 0.1, 1.15]}
    assert scene["size"] == pytest.approx(np.linalg.norm([0.1, 0.2, 0.3]), abs=1e-5)


@pytest.fixture(scope="module")
def bolt_run():
    system = load_robot(BOLT, fixed_base=True)
    x0 = np.zeros(2 * 6)
    x0[[1, 4]] = [0.6, -0.4]          # hip flexions: the legs swing apart
    return simulate(system, x0, t_end=0.3)


def test_link_poses_match_yourdfpy_forward_kinematics(bolt_run):
    times = np.linspace(0.0, 0.3, 7)
    poses = link_poses(bolt_run, times)
    urdf = yourdfpy.URDF.load(str(BOLT), load_meshes=False)
    q_names = [str(q) for q in bolt_run.system.modes[bolt_run.mode_names[0]].q]
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(bolt_run.t - t)))
        assert bolt_run.t[i] == pytest.approx(t, abs=1e-12)   # times on the samples
        urdf.update_cfg({n: float(bolt_run.x[i, j]) for j, n in enumerate(q_names)})
        for link in urdf.link_map:
            T = urdf.get_transform(link, "base_link")
            p, R = poses[link]
            np.testing.assert_allclose(p[k], T[:3, 3], atol=1e-12)
            np.testing.assert_allclose(R[k], T[:3, :3], atol=1e-12)


def test_bolt_page_holds_its_meshes_within_the_budget(bolt_run, tmp_path):
    scene = scene_of(bolt_run, fps=30)
    meshes = [s for s in scene["shapes"] if s["type"] == "mesh"]
    assert len(meshes) == 9 and set(scene["meshes"]) == {s["mesh"] for s in meshes}
    assert sum(m["triangles"] for m in scene["meshes"].values()) == sum(len(v.faces) for v in urdf_visuals(BOLT))
    assert not any(s["type"] == "sphere" for s in scene["shapes"])   # no balls inside the meshes
    page = render_html(scene)
    assert scene["meshes"][meshes[0]["mesh"]]["positions"] in page
    assert len(page.encode()) < 3_000_000
    # the floor is under the lowest mesh vertex and the robot's size is the meshes' extent
    ground = next(s for s in scene["shapes"] if s["type"] == "ground")
    assert ground["height"] == pytest.approx(scene["bounds"]["min"][2], abs=1e-5)
    assert 0.5 < scene["size"] < 1.2
    bare = scene_of(bolt_run, fps=30, max_triangles=0)
    assert "meshes" not in bare and any(s["type"] == "sphere" for s in bare["shapes"])


def test_a_large_robot_is_reduced_to_the_budget():
    visuals = urdf_visuals(ROBOTS / "solo_description" / "robots" / "solo12.urdf")
    total = sum(len(v.faces) for v in visuals)
    small = within_budget(visuals, 10_000)
    assert total > 40_000 and sum(len(v.faces) for v in small) <= 10_000 + 48 * len(visuals)
    for a, b in zip(visuals, small):   # each part keeps its place and size, to a cell
        np.testing.assert_allclose(b.vertices.min(axis=0), a.vertices.min(axis=0), atol=0.01)
        np.testing.assert_allclose(b.vertices.max(axis=0), a.vertices.max(axis=0), atol=0.01)


def _standing(system, srdf: Path, state: str) -> np.ndarray:
    """The state at rest in a configuration of the robot's SRDF (``group_state``), read here
    with the standard library: coordinates by joint name, zero velocities."""
    import xml.etree.ElementTree as ET

    group = next(g for g in ET.parse(srdf).getroot().iter("group_state") if g.get("name") == state)
    values = {j.get("name"): j.get("value") for j in group.iter("joint")}
    names = [str(q) for q in system.modes[system.name].q]
    x0 = np.zeros(2 * len(names))
    x0[: len(names)] = [float(values.get(n, 0.0)) for n in names]
    assert sum(n in values for n in names) >= 0.9 * len(names)   # Talos: not its 2 grippers
    return x0


def _screenshot(scene: dict, tmp_path: Path, t: float) -> tuple[np.ndarray, np.ndarray]:
    """The page of ``scene`` in headless Chromium at time ``t`` (s), bare (``ui=0``), with the
    meshes painted red and the floor green: the masks of mesh and of floor pixels."""
    for s in scene["shapes"]:
        if s["type"] == "mesh":
            s["color"] = [0.9, 0.1, 0.1]   # red: told apart from the floor and the sky
        elif s["type"] == "ground":
            s["color"] = [0.1, 0.7, 0.2]
    path = write_html(tmp_path / "robot.html", scene)
    png = tmp_path / "robot.png"
    _finish(_chromium(f"{path.as_uri()}#t={t}&ui=0", f"--window-size={WIDTH},{HEIGHT}",
                      "--virtual-time-budget=2000", f"--screenshot={png}", profile=tmp_path / "p"))
    img = _read_png(png)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 60) & (r > 1.8 * g) & (r > 1.8 * b)
    green = (g > 60) & (g > 1.5 * r) & (g > 1.5 * b)
    return red, green


def _whole_in_frame(red: np.ndarray, green: np.ndarray, least: int) -> None:
    """The robot's pixels: many, clear of every border, not a speck; the floor's too."""
    assert red.sum() > least, f"only {red.sum()} pixels of mesh"
    rows, cols = np.nonzero(red)
    assert rows.min() > 10 and cols.min() > 10 and rows.max() < HEIGHT - 10 and cols.max() < WIDTH - 10, \
        f"mesh pixels reach the border: rows {rows.min()}..{rows.max()}, columns {cols.min()}..{cols.max()}"
    assert rows.max() - rows.min() > HEIGHT / 5
    assert green.sum() > 0.05 * HEIGHT * WIDTH, f"only {green.sum()} pixels of floor"
    # the floor is seen under the robot: floor pixels below its lowest mesh pixel
    assert green[rows.max() + 1:].sum() > 1000


@pytest.mark.browser
@needs_chromium
def test_bolts_meshes_are_drawn_in_frame(bolt_run, tmp_path):
    red, green = _screenshot(scene_of(bolt_run, fps=30, series=[]), tmp_path, 0.2)
    _whole_in_frame(red, green, 3000)


ROBOT_SHOTS = [
    pytest.param("solo_description/robots/solo12.urdf", "solo.srdf", "standing", id="solo12"),
    # 32 coordinates: compiling its kernels takes about 30 s from a cold cache (once per machine)
    pytest.param("talos_data/robots/talos_reduced.urdf", "talos.srdf", "half_sitting", id="talos"),
]


@pytest.mark.browser
@needs_chromium
@pytest.mark.parametrize(("urdf", "srdf", "state"), ROBOT_SHOTS)
def test_a_robot_standing_is_drawn_whole_over_its_floor(urdf, srdf, state, tmp_path):
    """Solo12 and Talos in a standing configuration of their SRDF, fixed at the base: the
    scene of a short run is built as for any user (meshes from the URDF, poses by the link
    kinematics) and shown at its start."""
    path = ROBOTS / urdf
    system = load_robot(path, fixed_base=True)
    x0 = _standing(system, path.parents[1] / "srdf" / srdf, state)
    run = simulate(system, x0, t_end=0.05)
    scene = scene_of(run, fps=30, series=[])
    assert len([s for s in scene["shapes"] if s["type"] == "mesh"]) == len(urdf_visuals(path))
    red, green = _screenshot(scene, tmp_path, 0.0)
    _whole_in_frame(red, green, 3000)


def _mjcf(tmp_path: Path) -> Path:
    """A two-hinge arm with a mesh, a capsule, a box and a sphere, and a hidden geom (group 3)."""
    shutil.copy(LEG_STL, tmp_path / "leg.stl")
    text = """<mujoco model="arm">
  <asset><mesh name="leg" file="leg.stl"/></asset>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="upper" pos="0 0 1" euler="0.2 0 0.3">
      <joint name="shoulder" type="hinge" axis="0 1 0" pos="0 0 0.05"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.03" rgba="0.9 0.1 0.1 1"/>
      <geom type="mesh" mesh="leg" pos="0.05 0 -0.1" euler="0 0.4 0"/>
      <body name="lower" pos="0 0 -0.4">
        <joint name="elbow" type="hinge" axis="1 0 0"/>
        <geom type="box" size="0.02 0.03 0.2" pos="0 0 -0.2"/>
        <geom type="sphere" size="0.05" pos="0 0 -0.4"/>
        <geom type="sphere" size="0.5" group="3"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""
    path = tmp_path / "arm.xml"
    path.write_text(text)
    return path


def test_mjcf_geoms_and_body_poses_match_mujoco(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    from amble.viz.meshes import mjcf_visuals

    path = _mjcf(tmp_path)
    visuals = mjcf_visuals(path)
    assert [v.link for v in visuals] == ["upper", "upper", "lower", "lower"]   # no plane, no group 3
    assert visuals[0].color == pytest.approx((0.9, 0.1, 0.1))
    system = load_robot(path)
    traj = simulate(system, [0.7, -0.5, 0.0, 0.0], t_end=0.2)
    times = np.array([0.0, 0.1, 0.2])
    poses = link_poses(traj, times)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    q_names = [str(q) for q in system.modes[traj.mode_names[0]].q]
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(traj.t - t)))
        d.qpos[:] = m.qpos0 + traj.x[i, : len(q_names)]
        mujoco.mj_kinematics(m, d)
        for b, name in ((1, "upper"), (2, "lower")):
            np.testing.assert_allclose(poses[name][0][k], d.xpos[b], atol=1e-12)
            np.testing.assert_allclose(poses[name][1][k], d.xmat[b].reshape(3, 3), atol=1e-12)
        # the mesh geom lands where MuJoCo puts it: its vertices through the body's pose, against
        # MuJoCo's own geom frame applied to the mesh's vertices
        g = 2
        v0, nv = m.mesh_vertadr[0], m.mesh_vertnum[0]
        expect = m.mesh_vert[v0:v0 + nv] @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]
        got = visuals[1].vertices @ poses["upper"][1][k].T + poses["upper"][0][k]
        np.testing.assert_allclose(got, expect, atol=1e-6)
    scene = scene_of(traj, fps=20)
    assert sum(s["type"] == "mesh" for s in scene["shapes"]) == 4


@pytest.mark.slow
def test_link_poses_of_a_rerooted_robot_match_yourdfpy():
    """Bolt fixed at its left shank: the joints up to the URDF root are traversed backwards."""
    system = load_robot(BOLT, base="FL_LOWER_LEG", fixed_base=True)
    x0 = np.zeros(12)
    x0[:6] = [0.3, -0.2, 0.5, 0.1, 0.4, -0.6]
    traj = simulate(system, x0, t_end=0.2)
    times = np.array([0.0, 0.1, 0.2])
    poses = link_poses(traj, times)
    urdf = yourdfpy.URDF.load(str(BOLT), load_meshes=False)
    q_names = [str(q) for q in system.modes[traj.mode_names[0]].q]
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(traj.t - t)))
        urdf.update_cfg({n: float(traj.x[i, j]) for j, n in enumerate(q_names)})
        for link in urdf.link_map:
            T = urdf.get_transform(link, "FL_LOWER_LEG")
            np.testing.assert_allclose(poses[link][0][k], T[:3, 3], atol=1e-12)
            np.testing.assert_allclose(poses[link][1][k], T[:3, :3], atol=1e-12)


@pytest.mark.slow
def test_talos_meshes_fit_the_budget():
    """Talos (about 159 000 triangles) reduced to the default budget: a page of a few MB."""
    visuals = urdf_visuals(ROBOTS / "talos_data" / "robots" / "talos_reduced.urdf")
    assert sum(len(v.faces) for v in visuals) > 150_000
    small = within_budget(visuals)
    assert sum(len(v.faces) for v in small) <= 120_000 + 48 * len(visuals)
    size = sum(len(encode(v.vertices, v.faces)["positions"]) + len(encode(v.vertices, v.faces)["indices"])
               for v in small)
    assert size < 2_000_000


def test_a_floating_robots_links_and_massless_frames_are_posed(tmp_path):
    """A floating two-link robot with a massless camera on a fixed joint (merged into its body):
    every link's pose is the base pose of the documented convention — translation, then
    ``Rz(yaw) Ry(pitch) Rx(roll)`` — composed with yourdfpy's kinematics from the base."""
    inertia = '<inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/>'
    text = f"""<robot name="cam">
  <link name="torso"><inertial><mass value="2"/>{inertia}</inertial>
    <visual><geometry><box size="0.2 0.1 0.3"/></geometry></visual></link>
  <link name="arm"><inertial><origin xyz="0 0 -0.1"/><mass value="1"/>{inertia}</inertial>
    <visual><origin xyz="0 0 -0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual></link>
  <link name="camera"><visual><geometry><box size="0.03 0.03 0.03"/></geometry></visual></link>
  <joint name="shoulder" type="revolute"><parent link="torso"/><child link="arm"/>
    <origin xyz="0 0.1 0.1" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="mount" type="fixed"><parent link="arm"/><child link="camera"/>
    <origin xyz="0.02 0 -0.2" rpy="0.1 0.5 -0.3"/></joint>
</robot>"""
    path = tmp_path / "cam.urdf"
    path.write_text(text)
    system = load_robot(path)
    names = [str(q) for q in system.modes[system.name].q]
    x0 = np.zeros(2 * len(names))
    x0[: len(names)] = [0.1, -0.2, 0.3, 0.4, -0.3, 0.2, 0.7]
    x0[len(names):] = [0.2, 0.1, 0.0, 0.5, -0.4, 0.3, 1.0]
    traj = simulate(system, x0, t_end=0.2)
    times = np.array([0.0, 0.1, 0.2])
    poses = link_poses(traj, times)
    assert set(poses) == {"torso", "arm", "camera"}
    urdf = yourdfpy.URDF.load(str(path), load_meshes=False)
    for k, t in enumerate(times):
        i = int(np.argmin(np.abs(traj.t - t)))
        q = dict(zip(names, traj.x[i, : len(names)]))
        Rb = _rpy(q["base_roll"], q["base_pitch"], q["base_yaw"])
        pb = np.array([q["base_x"], q["base_y"], q["base_z"]])
        urdf.update_cfg({"shoulder": float(q["shoulder"])})
        for link in ("torso", "arm", "camera"):
            T = urdf.get_transform(link, "torso")
            np.testing.assert_allclose(poses[link][0][k], pb + Rb @ T[:3, 3], atol=1e-12)
            np.testing.assert_allclose(poses[link][1][k], Rb @ T[:3, :3], atol=1e-12)
    scene = scene_of(traj, fps=20)
    assert sorted(s["frame"] for s in scene["shapes"] if s["type"] == "mesh") == ["arm", "camera", "torso"]
    assert not any(s["type"] in ("sphere", "cylinder") for s in scene["shapes"])
