"""Rich display in Jupyter: a trajectory as the interactive 3D viewer, a limit cycle as its
phase portrait.

The simulation and analysis layers know nothing of drawing, so their types carry no
``_repr_html_``; instead this module registers display formatters with IPython (its documented
way to show third-party types), when ``amble.viz`` is imported inside a running IPython kernel.
"""

from __future__ import annotations

import html as _html
import io
import sys
from typing import Any

_TRAJECTORY = ("amble.simulation.trajectory", "Trajectory")
_CYCLE = ("amble.analysis.poincare", "LimitCycle")


#: Frames of the inline viewer at most: a long run is shown at a lower frame rate, so that a
#: display stays near the size of the viewer's own library (≈ 0.8 MB), however long the run.
MAX_FRAMES = 900
#: Triangles of a robot file's meshes in the inline viewer at most (about 0.5 MB of the display).
MAX_TRIANGLES = 40_000


def trajectory_html(traj: Any, height: int = 480, max_frames: int = MAX_FRAMES) -> str:
    """The 3D viewer of a trajectory as an ``<iframe>`` for a notebook cell (30 fps, fewer for a
    run longer than ``max_frames`` / 30 time units; a robot file's meshes reduced to
    :data:`MAX_TRIANGLES`)."""
    from .animate import scene_of
    from .html import render_html

    duration = float(traj.t[-1] - traj.t[0]) if len(traj.t) else 0.0
    fps = min(30.0, max_frames / duration) if duration > 0 else 30.0
    page = render_html(scene_of(traj, fps=fps, max_triangles=MAX_TRIANGLES), title=f"amble — {traj.system.name}")
    return (f'<iframe srcdoc="{_html.escape(page)}" style="width:100%;height:{height}px;border:0" '
            'sandbox="allow-scripts"></iframe>')


def cycle_png(cycle: Any) -> bytes:
    """The phase portrait of a limit cycle as PNG bytes."""
    import matplotlib.pyplot as plt

    from .plot import plot_limit_cycle

    fig = plot_limit_cycle(cycle)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return buf.getvalue()


def register() -> bool:
    """Register the formatters with the running IPython shell; ``False`` outside IPython."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is None:
        return False
    formatters = shell.display_formatter.formatters
    formatters["text/html"].for_type_by_name(*_TRAJECTORY, trajectory_html)
    formatters["image/png"].for_type_by_name(*_CYCLE, cycle_png)
    return True
