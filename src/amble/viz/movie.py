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

import math
import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..simulation.trajectory import Trajectory
from .errors import ExportError

MAX_FPS = 30.0


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
                progress: bool | None = None) -> Path:
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from tqdm.auto import tqdm

    from .scene import Cylinder, Sphere

    check_writer(path)
    fps = movie_fps(path, fps)
    system = traj.system
    times, pts = traj.resample(fps)
    links = [s for s in shapes if isinstance(s, Cylinder)]
    balls = [s for s in shapes if isinstance(s, Sphere)]
    views = [(0, 2, "side (x–z)")] + ([(1, 2, "front (y–z)")] if system.dims == 3 else [])
    fig = Figure(figsize=(5 * len(views), 4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(views), squeeze=False)
    allp = np.concatenate([np.nan_to_num(v) for v in pts.values()])
    artists = []
    unit = system.time_unit
    clock = fig.text(0.01, 0.97, "", ha="left", va="top", family="monospace")
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
        lines = [ax.plot([], [], "-", color="0.4", lw=2)[0] for _ in links]
        dots = [ax.plot([], [], "o", color=s.color, ms=4 + 60 * s.radius)[0] for s in balls]
        artists.append((i, j, lines, dots))

    def draw(f: int):
        out = [clock]
        clock.set_text(f"t = {times[f]:.2f} {unit}")
        for i, j, lines, dots in artists:
            for ln, s in zip(lines, links):
                a, b = pts[s.between[0]][f], pts[s.between[1]][f]
                ln.set_data([a[i], b[i]], [a[j], b[j]])
                out.append(ln)
            for d, s in zip(dots, balls):
                d.set_data([pts[s.at][f][i]], [pts[s.at][f][j]])
                out.append(d)
        return out

    anim = FuncAnimation(fig, draw, frames=len(times), interval=1000 / fps, blit=False)
    if path.suffix.lower() == ".gif":
        writer: Any = PillowWriter(fps=fps)
    else:
        import matplotlib

        matplotlib.rcParams["animation.ffmpeg_path"] = ffmpeg_path()
        writer = FFMpegWriter(fps=fps)
    part = path.with_name(f".{path.stem}.part{path.suffix}")
    bar = tqdm(total=len(times), desc=f"writing {path.name}", unit="frame",
               disable=None if progress is None else not progress, leave=False)
    try:
        anim.save(part, writer=writer, progress_callback=lambda i, n: bar.update(1))
        os.replace(part, path)
    except (ValueError, RuntimeError, OSError, subprocess.SubprocessError) as e:
        raise ExportError(f"cannot write {path.name}: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
                          ) from None
    finally:
        bar.close()
        if part.exists():
            part.unlink()
    return path
