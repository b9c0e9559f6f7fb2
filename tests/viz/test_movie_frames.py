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
