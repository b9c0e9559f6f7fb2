"""GIF and MP4 export of a trajectory (side view; side and front views for 3D models).

* Frame timing is exact: a GIF stores frame delays in hundredths of a second, so its rate is the
  nearest one not above the asked one whose frame lasts a whole number of them (30 fps → 25 fps,
  40 ms frames); an MP4 plays at the asked rate. The samples are taken at that rate, so the movie
  plays in the trajectory's own time, and a clock in the corner shows it.
* MP4 needs an ffmpeg: the one on ``PATH``, else the one that the ``imageio-ffmpeg`` package ships
  (``pip install "amble[video]"``). :func:`check_writer` looks for it before any work starts.
* The file is written beside the target and moved into place when complete: a failed export
  leaves no file (and no empty one).
* The figure is drawn without pyplot, so matplotlib's backend (e.g. a notebook's inline one) is
  never switched.
"""

from __future__ import annotations

import itertools
import math
import os
import shutil
import subprocess
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..simulation.trajectory import Trajectory
from .errors import ExportError

MAX_FPS = 30.0
#: At most this many triangles of a robot file's meshes are drawn in a movie (together).
MOVIE_TRIANGLES = 4000


def movie_fps(path: str | Path, fps: float) -> float:
    """The frame rate a movie is written at (see the module docstring)."""
    fps = min(float(fps), MAX_FPS)
    if Path(path).suffix.lower() == ".gif":
        return 100.0 / math.ceil(100.0 / fps - 1e-9)
    return fps


def ffmpeg_path() -> str | None:
    """An ffmpeg executable: the one on ``PATH``, else the one of ``imageio-ffmpeg``, else None."""
    found = shutil.which("ffmpeg")
    if found:
        return found
    try:
        import imageio_ffmpeg
    except ImportError:
        return None
    try:
        return imageio_ffmpeg.get_ffmpeg_exe()
    except (RuntimeError, OSError):
        return None


def check_writer(path: str | Path) -> None:
    """Raise :class:`ExportError` now if ``path`` cannot be written for want of a tool (an MP4
    without ffmpeg), so that no simulation is run for a movie that cannot be made."""
    if Path(path).suffix.lower() == ".mp4" and ffmpeg_path() is None:
        raise ExportError(f"cannot write {Path(path).name}: MP4 needs ffmpeg — pip install imageio-ffmpeg "
                          "(or amble[video]), or install ffmpeg; or use .gif or .html")


def write_movie(traj: Trajectory, path: Path, fps: float, shapes: Sequence[Any], slope: float | None,
                progress: bool | None = None, solids: Solids | None = None) -> Path:
    """Write the movie of ``traj`` (see the module docstring); ``solids``: the poses and meshes
    of the :class:`~amble.viz.scene.Mesh` shapes at the movie's frames (:func:`movie_times`)."""
    from tqdm.auto import tqdm

    check_writer(path)
    fps = movie_fps(path, fps)
    mf = movie_figure(traj, fps, shapes, slope, solids)
    frames = _frames(mf)
    part = path.with_name(f".{path.stem}.part{path.suffix}")
    bar = tqdm(total=len(mf.times), desc=f"writing {path.name}", unit="frame",
               disable=None if progress is None else not progress, leave=False)

    def counted():
        for frame in frames:
            bar.update(1)
            yield frame

    try:
        if path.suffix.lower() == ".gif":
            _write_gif(counted(), part, fps)
        else:
            _write_mp4(counted(), part, fps)
        os.replace(part, path)
    except (ValueError, RuntimeError, OSError, subprocess.SubprocessError) as e:
        raise ExportError(f"cannot write {path.name}: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
                          ) from None
    finally:
        bar.close()
        if part.exists():
            part.unlink()
    return path


@dataclass
class MovieFigure:
    """The figure of a movie: ``update(f)`` poses the moving ``artists`` at sample ``f`` of ``times``."""

    figure: Any
    canvas: Any
    times: np.ndarray
    artists: list[Any]
    update: Callable[[int], None]


#: The poses (frame → positions ``(F, 3)``, rotations ``(F, 3, 3)``) and the encoded meshes (key →
#: :func:`amble.viz.meshes.encode`) of a movie's :class:`~amble.viz.scene.Mesh` shapes.
Solids = tuple[dict[str, tuple[np.ndarray, np.ndarray]], dict[str, dict[str, Any]]]


def movie_times(traj: Trajectory, path: str | Path, fps: float) -> np.ndarray:
    """The times (s) of a movie's frames at the asked ``fps`` (see :func:`movie_fps`)."""
    return traj.resample(movie_fps(path, fps))[0]


class _Solids:
    """The triangles of the meshes, posed per frame and drawn in each view as flat-shaded
    polygons, the farthest first (an orthographic painter's algorithm)."""

    def __init__(self, shapes: Sequence[Any], solids: Solids | None) -> None:
        from .meshes import decode
        from .scene import Mesh

        self.parts = []
        poses, meshes = solids or ({}, {})
        for s in shapes:
            if isinstance(s, Mesh):
                v, f = decode(meshes[s.mesh])
                self.parts.append((v, f, np.asarray(s.color, float), *poses[s.frame]))

    def extent(self) -> np.ndarray:
        """Every posed vertex of every frame, ``(n, 3)`` (for the axis limits)."""
        if not self.parts:
            return np.zeros((0, 3))
        return np.concatenate([(v @ np.swapaxes(R, 1, 2) + p[:, None, :]).reshape(-1, 3)
                               for v, _, _, p, R in self.parts])

    def triangles(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The world triangles ``(n, 3, 3)`` at frame ``k`` and their colours ``(n, 3)``."""
        tri = [(v @ R[k].T + p[k])[f] for v, f, _, p, R in self.parts]
        col = [np.broadcast_to(c, (len(f), 3)) for _, f, c, _, _ in self.parts]
        return np.concatenate(tri), np.concatenate(col)

    @staticmethod
    def project(tri: np.ndarray, col: np.ndarray, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """The polygons of view ``(i, j)`` (the axes across and up; the view looks along their
        cross product) in drawing order, and their shaded colours."""
        depth_axis = 3 - i - j
        toward = -1.0 if (i, j) == (0, 2) else 1.0      # side: seen from -y; front: from +x
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        facing = np.abs(n[:, depth_axis]) / np.maximum(np.linalg.norm(n, axis=1), 1e-300)
        order = np.argsort(toward * tri[:, :, depth_axis].mean(axis=1))   # far first
        shade = (0.35 + 0.65 * facing)[order, None]
        return tri[order][:, :, [i, j]], np.clip(col[order] * shade, 0.0, 1.0)


def movie_figure(traj: Trajectory, fps: float, shapes: Sequence[Any], slope: float | None,
                 solids: Solids | None = None) -> MovieFigure:
    """A side view (and a front view for a 3D model) of the links, balls and meshes of
    ``shapes``, with a walker's ground and a clock, sampled at ``fps``; the moving artists are
    marked animated. ``solids``: the poses and meshes of the ``Mesh`` shapes at those samples."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    from .scene import Cylinder, Sphere

    system = traj.system
    times, pts = traj.resample(fps)
    links = [s for s in shapes if isinstance(s, Cylinder)]
    balls = [s for s in shapes if isinstance(s, Sphere)]
    solid = _Solids(shapes, solids)
    views = [(0, 2, "side (x–z)")] + ([(1, 2, "front (y–z)")] if system.dims == 3 else [])
    fig = Figure(figsize=(5 * len(views), 4))
    canvas = FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(views), squeeze=False)
    allp = np.concatenate([np.nan_to_num(v) for v in pts.values()] + [solid.extent()])
    clock = fig.text(0.01, 0.97, "", ha="left", va="top", family="monospace", animated=True)
    moving: list[tuple[int, int, list[Any], list[Any]]] = []
    for ax, (i, j, title) in zip(axes[0], views):
        ax.set_aspect("equal")
        ax.set_title(title)
        lo, hi = allp.min(axis=0) - 0.3, allp.max(axis=0) + 0.3
        ax.set_xlim(lo[i], hi[i])
        if slope is not None and i == 0:  # the ground of a walker, in the side view
            xs = np.array([lo[0], hi[0]])
            ax.set_ylim(min(lo[j], -np.tan(slope) * hi[0]) - 0.1, hi[j])
            ax.plot(xs, -np.tan(slope) * xs, color="0.5")
        else:
            ax.set_ylim(lo[j], hi[j])
        lines = [ax.plot([], [], "-", color="0.4", lw=2, animated=True)[0] for _ in links]
        dots = [ax.plot([], [], "o", color=s.color, ms=4 + 60 * s.radius, animated=True)[0] for s in balls]
        if solid.parts:   # not antialiased: no seams between the triangles
            lines.insert(0, ax.add_collection(PolyCollection([], linewidths=0, antialiased=False, animated=True)))
        moving.append((i, j, lines, dots))
    unit = system.time_unit

    def update(f: int) -> None:
        clock.set_text(f"t = {times[f]:.2f} {unit}")
        posed = solid.triangles(f) if solid.parts else None
        for i, j, lines, dots in moving:
            if posed is not None:
                polys, colours = solid.project(*posed, i, j)
                lines[0].set_verts(polys)
                lines[0].set_facecolor(colours)
                lines = lines[1:]
            for ln, s in zip(lines, links):
                a, b = pts[s.between[0]][f], pts[s.between[1]][f]
                ln.set_data([a[i], b[i]], [a[j], b[j]])
            for d, s in zip(dots, balls):
                d.set_data([pts[s.at][f][i]], [pts[s.at][f][j]])

    artists = [clock] + [a for _, _, lines, dots in moving for a in (*lines, *dots)]
    return MovieFigure(fig, canvas, times, artists, update)


def _frames(mf: MovieFigure) -> Iterator[np.ndarray]:
    """The movie's frames (RGB, uint8, height × width × 3).

    The still parts of the figure (axes, ticks, ground) are drawn once; each frame restores that
    background and draws only the moving artists (Agg blitting). Redrawing the whole figure, as
    ``FuncAnimation.save`` does (twice per frame), spends ~95 % of a movie's time on tick labels."""
    mf.canvas.draw()  # the still figure: animated artists are left out of it
    background = mf.canvas.copy_from_bbox(mf.figure.bbox)
    for f in range(len(mf.times)):
        mf.canvas.restore_region(background)
        mf.update(f)
        for a in mf.artists:
            (a.axes or mf.figure).draw_artist(a)
        yield np.asarray(mf.canvas.buffer_rgba())[:, :, :3].copy()


def _write_gif(frames: Iterator[np.ndarray], path: Path, fps: float) -> None:
    """Frames to a looping GIF with one palette for all: the first frame's 256 most frequent colours
    (the scene's colours do not change; the background stays exactly white). Each pixel takes its
    colour's palette index, found once per new colour (the nearest palette colour) and then looked
    up — Pillow's ``quantize(palette=…)`` matches on a coarser colour cube and tints the white."""
    from PIL import Image

    first = next(frames)
    colours, counts = np.unique(_packed(first), return_counts=True)
    palette = colours[np.argsort(-counts, kind="stable")[:256]]
    rgb = np.stack([(palette >> 16) & 255, (palette >> 8) & 255, palette & 255], axis=1)
    # a table over all 2^24 colours (16 MB each): a gather per frame instead of a search
    seen = np.zeros(1 << 24, bool)
    lut = np.zeros(1 << 24, np.uint8)
    seen[palette], lut[palette] = True, np.arange(len(palette), dtype=np.uint8)
    flat = np.zeros((256, 3), np.uint8)
    flat[: len(rgb)] = rgb
    images = []
    for f in itertools.chain([first], frames):
        p = _packed(f)
        new = np.unique(p[~seen[p]])
        if new.size:  # colours not met before: their nearest palette colour, remembered
            c = np.stack([(new >> 16) & 255, (new >> 8) & 255, new & 255], axis=1).astype(np.int32)
            near = np.argmin(((c[:, None, :] - rgb[None, :, :].astype(np.int32)) ** 2).sum(axis=2), axis=1)
            seen[new], lut[new] = True, near.astype(np.uint8)
        im = Image.fromarray(lut[p], mode="P")
        im.putpalette(flat.ravel().tolist())
        images.append(im)
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=round(1000 / fps), loop=0,
                   optimize=False)


def _packed(frame: np.ndarray) -> np.ndarray:
    """An RGB frame's pixels as one int32 each (0xRRGGBB), height × width."""
    f = frame.astype(np.int32)
    return (f[:, :, 0] << 16) | (f[:, :, 1] << 8) | f[:, :, 2]


def _write_mp4(frames: Iterator[np.ndarray], path: Path, fps: float) -> None:
    """Frames piped to ffmpeg as raw RGB (H.264, yuv420p so that every player shows it)."""
    first = next(frames)
    h, w = first.shape[:2]
    cmd = [ffmpeg_path() or "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
           "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-vcodec", "libx264", "-pix_fmt", "yuv420p",
           # yuv420p needs even sides
           "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4", str(path)]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert proc.stdin is not None
        proc.stdin.write(first.tobytes())
        for f in frames:
            proc.stdin.write(f.tobytes())
        proc.stdin.close()
    except BrokenPipeError:
        pass
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    if proc.wait() != 0:
        raise RuntimeError(f"ffmpeg failed: {err.strip().splitlines()[-1] if err.strip() else proc.returncode}")
