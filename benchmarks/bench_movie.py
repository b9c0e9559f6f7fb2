"""Movies: a GIF and an MP4 of the compass gait walking for about 7 s (10 steps, 25 fps GIF /
30 fps MP4, 500 × 400 px), written by ``amble.animate``, beside matplotlib's own
``FuncAnimation.save`` of the same figure (the usual way, and amble's earlier writer) in the same
run. Times are wall-clock medians (and amble's CPU time, which load on the machine inflates
less) over ``REPEATS`` runs, interleaved, the walk simulated once beforehand.

Run alone: ``python -m benchmarks --only movie --no-write``.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.common import Goal, Section, table

REPEATS = 3
GOAL_S = 3.0


def _matplotlib_save(traj: Any, path: Path, fps: float) -> None:
    """The same figure and artists, redrawn whole for every frame by ``FuncAnimation.save``."""
    import matplotlib
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    from amble.viz.animate import look_of
    from amble.viz.movie import ffmpeg_path, movie_figure, movie_fps

    fps = movie_fps(path, fps)
    slope = traj.system.slope_value(traj.parameters)
    mf = movie_figure(traj, fps, look_of(traj.system, traj.parameters), slope)
    for a in mf.artists:
        a.set_animated(False)
    anim = FuncAnimation(mf.figure, mf.update, frames=len(mf.times), interval=1000 / fps, blit=False)
    if path.suffix == ".gif":
        writer: Any = PillowWriter(fps=fps)
    else:
        matplotlib.rcParams["animation.ffmpeg_path"] = ffmpeg_path()
        writer = FFMpegWriter(fps=fps)
    anim.save(path, writer=writer)


def run(quick: bool = False) -> Section:
    import amble
    from amble.models import load
    from amble.viz.movie import ffmpeg_path

    walker = load("compass-gait")
    traj = amble.simulate(walker, steps=4 if quick else 10)
    suffixes = [".gif"] + ([".mp4"] if ffmpeg_path() else [])
    rows, goals, data = [], [], {}
    with tempfile.TemporaryDirectory() as d:
        for suffix in suffixes:
            samples: dict[str, list[float]] = {"amble.animate": [], "matplotlib FuncAnimation.save": []}
            cpu: list[float] = []
            for _ in range(1 if quick else REPEATS):
                for name, write in (("amble.animate", lambda p: amble.animate(traj, p, progress=False)),
                                    ("matplotlib FuncAnimation.save", lambda p: _matplotlib_save(traj, p, 60.0))):
                    p = Path(d) / f"walk{suffix}"
                    t0, c0 = time.perf_counter(), time.process_time()
                    write(p)
                    samples[name].append(time.perf_counter() - t0)
                    if name == "amble.animate":  # CPU of this process (the MP4's ffmpeg child not counted)
                        cpu.append(time.process_time() - c0)
            med = {k: statistics.median(v) for k, v in samples.items()}
            data[suffix] = med
            ours, peer = med["amble.animate"], med["matplotlib FuncAnimation.save"]
            data[suffix]["amble cpu"] = statistics.median(cpu)
            rows.append([suffix[1:].upper(), f"{ours:.2f}", f"{statistics.median(cpu):.2f}", f"{peer:.2f}",
                         f"{peer / ours:.1f}×"])
            goals.append(Goal(f"{suffix[1:].upper()} of 7 s of walking", f"≤ {GOAL_S:g} s",
                              f"{med['amble.animate']:.2f} s", med["amble.animate"] <= GOAL_S))
    span = traj.t[-1] - traj.t[0]
    md = [f"Compass gait, {span:.1f} s of walking; seconds to write the file (median of {REPEATS}):", "",
          table(["file", "amble s", "amble CPU s", "matplotlib save s", "ratio"], rows)]
    return Section("Movies", "\n".join(md), goals, data)


if __name__ == "__main__":
    print(run().markdown)
