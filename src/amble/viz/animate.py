"""Animations of a trajectory: a self-contained 3D HTML viewer, or GIF/MP4 through matplotlib."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..modelling.hybrid import HybridSystem
from ..modelling.walker import Walker
from ..simulation.trajectory import Trajectory
from .errors import ExportError, SceneError, VizError
from .scene import Cylinder, Ground, Shape, Sphere, default_look, frames


def look_of(system: HybridSystem, params: dict[str, float], look: Sequence[Any] | None = None) -> list[Any]:
    """The shapes that draw a system: ``look`` if given (with the walker's ground added), else a
    default from its masses, links and slope."""
    slope = _slope(system, params)
    if look:
        shapes = list(look)
        for s in shapes:
            if not isinstance(s, Shape):
                raise SceneError(f"look: not a shape (Sphere, Cylinder, Box or Ground): {s!r}")
        if not any(isinstance(s, Ground) for s in shapes):
            shapes.insert(0, Ground(slope=slope))
        return shapes
    masses: dict[str, float] = {}
    links: list[tuple[str, str]] = []
    for m in system.modes.values():
        subs = {s: params.get(str(s), v) for s, v in m.params.items()}
        for name, mass in m.masses.items():
            masses[name] = max(masses.get(name, 0.0), float(mass.subs(subs)))
        links += [lk for lk in m.links if lk not in links]
    shapes = default_look(system.point_names, links, masses, slope=slope)
    # Legs swap names at every footfall; colouring spheres by mass keeps a leg's colour fixed.
    colours: dict[float, Any] = {}
    out = []
    for s in shapes:
        if isinstance(s, Sphere) and masses.get(s.at, 0.0) > 0:
            s = replace(s, color=colours.setdefault(round(masses[s.at], 9), s.color))
        out.append(s)
    return out


def _slope(system: HybridSystem, params: dict[str, float]) -> float:
    return system.slope_value(params) if isinstance(system, Walker) else 0.0


def scene_of(traj: Trajectory, fps: float = 60.0, look: Sequence[Any] | None = None) -> dict:
    """Scene JSON (see :func:`amble.viz.scene.frames`) of a trajectory in world coordinates."""
    system = traj.system
    times, pts = traj.resample(fps)
    shapes = look_of(system, traj.parameters, look)
    step_idx = np.searchsorted([e.t for e in traj.step_events], times, side="right")
    hip = system.hip if isinstance(system, Walker) else None
    follow = hip if hip in pts else None
    used = {n for s in shapes for n in s.points()}
    pts = {n: np.nan_to_num(v) for n, v in pts.items() if n in used or n == follow}
    return frames(shapes, pts, times, follow=follow, labels={"step": step_idx.tolist()})


def animate(traj: Trajectory, path: str | Path, fps: float = 60.0, look: Sequence[Any] | None = None) -> Path:
    """Write an animation of ``traj``: ``.html`` (3D, offline, interactive), ``.gif`` or ``.mp4``.

    ``look``: the shapes to draw (:mod:`amble.viz.scene`); default: made from the model."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".html":
        from .html import write_html

        return write_html(path, scene_of(traj, fps, look), title=f"amble — {traj.system.name}")
    if suffix in (".gif", ".mp4"):
        return _movie(traj, path, fps=min(fps, 30.0), look=look)
    raise VizError(f"unknown animation format {path.suffix!r}: use .html, .gif or .mp4")


def _movie(traj: Trajectory, path: Path, fps: float, look: Sequence[Any] | None) -> Path:
    """Side view (x–z) for 2D models; side and front views for 3D ones."""
    system = traj.system
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    times, pts = traj.resample(fps)
    shapes = look_of(system, traj.parameters, look)
    links = [s for s in shapes if isinstance(s, Cylinder)]
    balls = [s for s in shapes if isinstance(s, Sphere)]
    views = [(0, 2, "side (x–z)")] + ([(1, 2, "front (y–z)")] if system.dims == 3 else [])
    fig, axes = plt.subplots(1, len(views), figsize=(5 * len(views), 4), squeeze=False)
    allp = np.concatenate([np.nan_to_num(v) for v in pts.values()])
    slope = _slope(system, traj.parameters)
    artists = []
    for ax, (i, j, title) in zip(axes[0], views):
        ax.set_aspect("equal")
        ax.set_title(title)
        lo, hi = allp.min(axis=0) - 0.3, allp.max(axis=0) + 0.3
        ax.set_xlim(lo[i], hi[i])
        ax.set_ylim(min(lo[j], -np.tan(slope) * hi[0]) - 0.1, hi[j])
        if i == 0:
            xs = np.array([lo[0], hi[0]])
            ax.plot(xs, -np.tan(slope) * xs, color="0.5")
        lines = [ax.plot([], [], "-", color="0.4", lw=2)[0] for _ in links]
        dots = [ax.plot([], [], "o", color=s.color, ms=4 + 60 * s.radius)[0] for s in balls]
        artists.append((i, j, lines, dots))

    def draw(f: int):
        out = []
        for i, j, lines, dots in artists:
            for ln, s in zip(lines, links):
                a, b = pts[s.between[0]][f], pts[s.between[1]][f]
                ln.set_data([a[i], b[i]], [a[j], b[j]])
                out.append(ln)
            for d, s in zip(dots, balls):
                d.set_data([pts[s.at][f][i]], [pts[s.at][f][j]])
                out.append(d)
        return out

    anim = FuncAnimation(fig, draw, frames=len(times), interval=1000 / fps, blit=True)
    if path.suffix.lower() == ".gif":
        anim.save(path, writer=PillowWriter(fps=fps))
    else:
        try:
            anim.save(path, fps=fps)
        except (ValueError, RuntimeError, FileNotFoundError) as e:
            raise ExportError(f"cannot write {path.name}: MP4 needs ffmpeg ({e}); use .gif or .html") from None
    plt.close(fig)
    return path
