"""The ``--animate`` and ``--series`` options of ``amble simulate`` and ``amble limit-cycle``: the
viewer's time-series panels asked for, and the animation file written."""

from __future__ import annotations

from typing import Any

from .args import UsageError, writable_path
from .output import write_output

SERIES_HELP = ("with --animate FILE.html: the time series plotted under the 3D view, NAME,NAME,... (names "
               "of one unit share a panel) or TITLE=NAME,... (one titled panel each; repeatable); names: "
               "state variables and 'energy'; 'none' for no plot (default: the coordinates and the energy)")


def parse_series(values: list[str] | None, anim_p: Any) -> Any:
    """The ``series`` of the viewer from ``--series`` options: ``None`` (the default panels),
    ``[]`` for ``none``, a list of names (one panel per unit), or panel title → names when every
    option reads ``TITLE=NAME,...``."""
    if not values:
        return None
    if anim_p is None or anim_p.suffix.lower() != ".html":
        raise UsageError("--series needs --animate FILE.html (the viewer's time-series plot)")
    if [v.strip().lower() for v in values] == ["none"]:
        return []
    panels: dict[str, list[str]] = {}
    names: list[str] = []
    for v in values:
        title, sep, rest = v.partition("=") if "=" in v else ("", "", v)
        parts = [n.strip() for n in rest.split(",") if n.strip()]
        if not parts or (sep and not title.strip()):
            raise UsageError(f"--series expects 'NAME,NAME,...' or 'TITLE=NAME,...', got {v!r}")
        if sep:
            panels.setdefault(title.strip(), []).extend(parts)
        names += parts
    if 0 < sum("=" in v for v in values) < len(values):
        raise UsageError("--series: give every panel a title (TITLE=NAME,...) or none")
    return panels or names


def drawing_outputs(args: Any) -> tuple[Any, Any, Any]:
    """``--plot``, ``--animate`` and ``--series`` checked before any work: the two paths (or
    ``None``) and the viewer's series; a movie format without its writer (MP4 without ffmpeg) is
    refused here, not after the run."""
    plot_p = writable_path(args.plot, (".png", ".svg", ".pdf"), "--plot")
    anim_p = writable_path(args.animate, (".html", ".gif", ".mp4"), "--animate")
    series = parse_series(args.series, anim_p)
    if anim_p:
        from ..viz.movie import check_writer

        check_writer(anim_p)
    return plot_p, anim_p, series


def write_animation(tr: Any, path: Any, series: Any = None) -> None:
    """Write the animation of ``tr``: a GIF or MP4 is written atomically by the movie writer itself
    (its messages name the file), an HTML page through a part file."""
    from ..viz.animate import animate

    if path.suffix.lower() in (".gif", ".mp4"):
        animate(tr, path)
    else:
        write_output(path, lambda part: animate(tr, part, series=series), "--animate")

