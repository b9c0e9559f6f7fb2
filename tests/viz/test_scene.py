"""Scene description: shapes, default look and the frames() format."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from amble.errors import AmbleError
from amble.viz.errors import SceneError
from amble.viz.scene import Box, Cylinder, Ground, Sphere, default_look, frames


def _points(n: int = 5) -> tuple[dict[str, np.ndarray], np.ndarray]:
    t = np.linspace(0.0, 1.0, n)
    hip = np.column_stack([0.5 * t, np.zeros(n), 1.0 + 0.01 * np.sin(t)])
    foot = hip + np.column_stack([0.3 * np.sin(t), np.zeros(n), -np.ones(n)])
    return {"hip": hip, "foot": foot, "unused": hip * 2}, t


def test_frames_structure() -> None:
    pts, t = _points(5)
    shapes = [
        Ground(slope=0.1),
        Cylinder(("hip", "foot"), radius=0.02),
        Sphere("hip", radius=0.1, color=(1.0, 0.0, 0.0)),
        Box(center="foot", size=(0.1, 0.05, 0.02), rotation=(0.0, 0.0, 0.3)),
        Box(center=(1.0, 0.0, 0.0), size=(0.2, 0.2, 0.2), opacity=0.5),
    ]
    scene = frames(shapes, pts, t, follow="hip", labels={"step": [0, 0, 1, 1, 2]})

    assert scene["format"] == "amble.scene/1"
    assert scene["times"] == [0, 0.25, 0.5, 0.75, 1]
    # Only referenced points are exported, as flat (x, y, z) per frame.
    assert set(scene["points"]) == {"hip", "foot"}
    assert len(scene["points"]["hip"]) == 3 * len(t)
    np.testing.assert_allclose(np.reshape(scene["points"]["foot"], (-1, 3)), pts["foot"], atol=1e-5)
    assert [s["type"] for s in scene["shapes"]] == ["ground", "cylinder", "sphere", "box", "box"]
    ground, cyl, sph, box, fixed = scene["shapes"]
    assert ground["slope"] == 0.1 and ground["width"] == 2.0
    s0, s1 = ground["extent"]
    assert s0 < 0.0 and s1 > 0.5 / math.cos(0.1)  # covers the motion
    assert cyl["between"] == ["hip", "foot"] and cyl["radius"] == 0.02
    assert sph == {"type": "sphere", "at": "hip", "radius": 0.1, "color": [1, 0, 0], "opacity": 1}
    assert box["center"] == "foot" and box["rotation"] == [0, 0, 0.3]
    assert fixed["center"] == [1, 0, 0] and fixed["opacity"] == 0.5
    assert scene["follow"] == "hip"
    assert scene["labels"] == {"step": [0, 0, 1, 1, 2]}
    lo, hi = scene["bounds"]["min"], scene["bounds"]["max"]
    assert lo[0] == 0 and hi[0] == pytest.approx(0.5 + 0.3 * math.sin(1.0), abs=1e-5)


def test_frames_is_json_serialisable_and_compact() -> None:
    # 20 s at 60 fps, three points of a planar walker.
    n = 20 * 60
    t = np.arange(n) / 60.0
    hip = np.column_stack([0.4 * t, np.zeros(n), 0.9 + 0.02 * np.cos(7 * t)])
    pts = {
        "hip": hip,
        "a": hip + np.column_stack([np.sin(t), np.zeros(n), -np.cos(t)]),
        "b": hip + np.column_stack([-np.sin(t), np.zeros(n), -np.cos(t)]),
    }
    shapes = default_look(["hip", "a", "b"], [("hip", "a"), ("hip", "b")], {"hip": 10.0})
    labels = {"step": (t // 0.9).astype(np.int64), "phase": ["stance"] * n}
    scene = frames(shapes, pts, t, follow="hip", labels=labels)
    text = json.dumps(scene, allow_nan=False)
    assert json.loads(text) == scene
    assert len(text) < 400_000
    # Rounded to 1e-5: no long float tails.
    assert all(len(repr(v)) <= 12 for v in scene["points"]["a"][:300])
    assert isinstance(scene["labels"]["step"][0], int)


def test_planar_points_are_xz() -> None:
    t = np.array([0.0, 0.1])
    scene = frames([Sphere("p", 0.05)], {"p": np.array([[1.0, 2.0], [3.0, 4.0]])}, t)
    assert scene["points"]["p"] == [1, 0, 2, 3, 0, 4]


def test_default_look() -> None:
    names = ["hip", "knee", "foot"]
    shapes = default_look(names, [("hip", "knee"), ("knee", "foot")], {"hip": 8.0, "knee": 1.0})
    ground = [s for s in shapes if isinstance(s, Ground)]
    cyls = [s for s in shapes if isinstance(s, Cylinder)]
    spheres = {s.at: s for s in shapes if isinstance(s, Sphere)}
    assert len(ground) == 1 and ground[0].slope == 0.0
    assert [c.between for c in cyls] == [("hip", "knee"), ("knee", "foot")]
    assert set(spheres) == set(names)
    # Radius scales with the cube root of mass: 8x the mass, 2x the radius.
    assert spheres["hip"].radius == pytest.approx(2 * spheres["knee"].radius)
    assert spheres["foot"].radius < spheres["knee"].radius  # massless marker
    assert spheres["hip"].color != spheres["knee"].color
    assert not any(isinstance(s, Ground) for s in default_look(names, [], {}, slope=None))
    assert default_look(names, [], {}, slope=0.05)[0] == Ground(slope=0.05)


def test_default_look_unknown_names() -> None:
    with pytest.raises(ValueError, match="'toe'"):
        default_look(["hip"], [("hip", "toe")], {})
    with pytest.raises(ValueError, match="'tail'"):
        default_look(["hip"], [], {"tail": 1.0})


def test_unknown_point_name() -> None:
    pts, t = _points()
    with pytest.raises(ValueError, match="'knee'"):
        frames([Cylinder(("hip", "knee"), 0.02)], pts, t)
    with pytest.raises(ValueError, match="'head'"):
        frames([Sphere("hip", 0.1)], pts, t, follow="head")


@pytest.mark.parametrize("radius", [0.0, -0.1, float("nan"), float("inf")])
def test_bad_radius(radius: float) -> None:
    with pytest.raises(ValueError, match="radius"):
        Sphere("hip", radius)
    with pytest.raises(ValueError, match="radius"):
        Cylinder(("a", "b"), radius)


def test_shape_validation() -> None:
    with pytest.raises(ValueError, match="color"):
        Sphere("hip", 0.1, color=(0.0, 2.0, 0.0))
    with pytest.raises(ValueError, match="color"):
        Sphere("hip", 0.1, color=(0.0, 1.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="opacity"):
        Sphere("hip", 0.1, opacity=1.5)
    with pytest.raises(ValueError, match="size"):
        Box(center=(0.0, 0.0, 0.0), size=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="slope"):
        Ground(slope=2.0)
    with pytest.raises(ValueError, match="between"):
        Cylinder(("a",), 0.1)  # type: ignore[arg-type]


def test_frames_validation() -> None:
    pts, t = _points(5)
    sphere = [Sphere("hip", 0.1)]
    with pytest.raises(ValueError, match="frames"):
        frames(sphere, {"hip": pts["hip"][:3]}, t)
    with pytest.raises(ValueError, match="shape"):
        frames(sphere, {"hip": np.zeros((5, 4))}, t)
    with pytest.raises(ValueError, match="non-decreasing"):
        frames(sphere, pts, t[::-1])
    with pytest.raises(ValueError, match="non-finite"):
        bad = pts["hip"].copy()
        bad[2, 0] = np.nan
        frames(sphere, {"hip": bad}, t)
    with pytest.raises(ValueError, match="label 'step'"):
        frames(sphere, pts, t, labels={"step": [1, 2]})
    with pytest.raises(ValueError, match="at most one Ground"):
        frames([Ground(), Ground()], pts, t)
    # Repeated times (an impact: before and after) are fine.
    frames(sphere, pts, np.array([0.0, 0.5, 0.5, 0.7, 1.0]))


def test_errors_are_typed() -> None:
    # SceneError is both an AmbleError (the CLI reports a user error) and a ValueError.
    pts, t = _points()
    for bad in (
        lambda: Sphere("hip", -1.0),
        lambda: Box(center=(0.0, 0.0), size=(1.0, 1.0, 1.0)),
        lambda: frames([Sphere("knee", 0.1)], pts, t),
        lambda: frames(["not a shape"], pts, t),  # type: ignore[list-item]
        lambda: default_look(["hip"], [], {"hip": -1.0}),
    ):
        with pytest.raises(SceneError) as info:
            bad()
        assert isinstance(info.value, AmbleError) and isinstance(info.value, ValueError)


def test_shape_points_and_fields() -> None:
    assert Sphere("hip", 0.1).points() == ("hip",)
    assert Cylinder(["hip", "foot"], 0.1).points() == ("hip", "foot")  # type: ignore[arg-type]
    assert Cylinder(["hip", "foot"], 0.1).between == ("hip", "foot")  # type: ignore[arg-type]
    assert Box("foot", (1.0, 1.0, 1.0)).points() == ("foot",)
    assert Box((0, 0, 1), (1, 1, 1)).points() == ()  # type: ignore[arg-type]
    assert Box((0, 0, 1), (1, 1, 1)).center == (0.0, 0.0, 1.0)  # type: ignore[arg-type]
    assert Ground().points() == ()
    assert Ground(0.1).to_dict((-1.0, 2.0)) == {
        "type": "ground", "slope": 0.1, "width": 2.0, "color": [0.86, 0.88, 0.91],
        "opacity": 1.0, "grid": 0.1, "extent": [-1.0, 2.0],
    }
    # Shapes stay frozen, comparable and hashable dataclasses.
    assert Sphere("hip", 0.1) == Sphere(at="hip", radius=0.1)
    assert len({Sphere("hip", 0.1), Sphere("hip", 0.1)}) == 1
    with pytest.raises(AttributeError):
        Sphere("hip", 0.1).radius = 2.0  # type: ignore[misc]
