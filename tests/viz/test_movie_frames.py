"""A movie's frames drawn by blitting (the still figure once, the moving parts per frame) are the
frames a full redraw of the same figure gives, and the GIF keeps their colours."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import amble
from amble.models import load
from amble.viz import movie
from amble.viz.animate import look_of


@pytest.fixture(scope="module")
def walk():
    walker = load("compass-gait")
    return amble.simulate(walker, steps=2)


def _redrawn(mf: movie.MovieFigure, f: int) -> np.ndarray:
    """Frame ``f`` drawn the plain way: every artist, the whole figure."""
    for a in mf.artists:
        a.set_animated(False)
    mf.update(f)
    buf = io.BytesIO()
    mf.figure.savefig(buf, format="rgba", dpi=mf.figure.dpi)
    w, h = mf.canvas.get_width_height()
    for a in mf.artists:
        a.set_animated(True)
    return np.frombuffer(buf.getvalue(), np.uint8).reshape(h, w, 4)[:, :, :3]


def test_blitted_frames_equal_full_redraws(walk):
    shapes = look_of(walk.system, walk.parameters)
    slope = walk.system.slope_value(walk.parameters)
    frames = list(movie._frames(movie.movie_figure(walk, 25.0, shapes, slope)))
    mf = movie.movie_figure(walk, 25.0, shapes, slope)
    assert len(frames) == len(mf.times) > 10
    for f in (0, len(frames) // 2, len(frames) - 1):
        assert np.array_equal(frames[f], _redrawn(mf, f))
    assert not np.array_equal(frames[0], frames[len(frames) // 2])  # the walker moved


def test_gif_keeps_the_scene_colours(walk, tmp_path):
    path = amble.animate(walk, tmp_path / "w.gif")
    shapes = look_of(walk.system, walk.parameters)
    mf = movie.movie_figure(walk, movie.movie_fps(path, 60.0), shapes, walk.system.slope_value(walk.parameters))
    frames = list(movie._frames(mf))
    gif = Image.open(path)
    assert gif.n_frames == len(frames)
    for f in (0, len(frames) // 2):
        gif.seek(f)
        got = np.asarray(gif.convert("RGB")).astype(int)
        assert np.array_equal(got[0, 0], [255, 255, 255])  # the background stays white
        assert np.mean(np.abs(got - frames[f])) < 1.0


def test_a_urdf_robots_movie_draws_its_meshes_where_its_links_are(tmp_path):
    """Bolt's first frame: the shaded meshes fill, in the side view, the box that its visuals'
    vertices span when placed by yourdfpy's forward kinematics at the initial configuration."""
    import importlib.metadata
    from pathlib import Path

    yourdfpy = pytest.importorskip("yourdfpy")
    pytest.importorskip("trimesh")
    from amble.models import load_robot
    from amble.viz.animate import movie_look
    from amble.viz.meshes import urdf_visuals

    dist = importlib.metadata.distribution("example-robot-data")
    bolt = Path(dist.locate_file(next(f for f in dist.files or () if str(f).endswith("bolt.urdf"))))
    system = load_robot(bolt, fixed_base=True)
    x0 = np.zeros(12)
    x0[[1, 4]] = [0.6, -0.4]          # hip flexions: the legs swing apart
    run = amble.simulate(system, x0, t_end=0.2)
    path = tmp_path / "bolt.gif"
    shapes, solids = movie_look(run, path, 60.0)
    assert solids is not None and not any(type(s).__name__ == "Sphere" for s in shapes)
    mf = movie.movie_figure(run, movie.movie_fps(path, 60.0), shapes, None, solids)
    frame = next(movie._frames(mf))
    # the expected box: every visual vertex, placed by yourdfpy at x0 (the base link is the world)
    urdf = yourdfpy.URDF.load(str(bolt), load_meshes=False)
    names = [str(q) for q in system.modes[system.name].q]
    urdf.update_cfg(dict(zip(names, x0[:12])))
    world = np.concatenate([v.vertices @ urdf.get_transform(v.link, "base_link")[:3, :3].T
                            + urdf.get_transform(v.link, "base_link")[:3, 3] for v in urdf_visuals(bolt)])
    ax = mf.figure.axes[0]                                  # the side view: x across, z up
    height = frame.shape[0]
    px = ax.transData.transform(world[:, [0, 2]])
    cols, rows = px[:, 0], height - px[:, 1]
    # the drawn pixels inside the axes (the frame lines left out)
    (x0a, y0a), (x1a, y1a) = ax.bbox.get_points()
    inside = frame[int(height - y1a) + 3:int(height - y0a) - 3, int(x0a) + 3:int(x1a) - 3].astype(int)
    r, c = np.nonzero(np.abs(inside - 255).sum(axis=2) > 30)
    r, c = r + int(height - y1a) + 3, c + int(x0a) + 3
    assert len(r) > 2000, "the meshes are not drawn"
    for got, want in ((r.min(), rows.min()), (r.max(), rows.max()), (c.min(), cols.min()), (c.max(), cols.max())):
        assert abs(got - want) < 5, (got, want)
    assert len(np.unique(inside.reshape(-1, 3), axis=0)) > 20     # shaded faces, not a flat shadow
    gif = amble.animate(run, path, progress=False)
    assert Image.open(gif).n_frames == len(mf.times)
