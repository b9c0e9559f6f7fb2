"""Offline browser animation of a scene built by :func:`amble.viz.scene.frames`.

:func:`write_html` writes one self-contained HTML file: the scene data, the
viewer and the vendored three.js (with OrbitControls) are all inlined, so the
file opens from disk with no network. The page shows a 3D view with an orbit
camera and a control bar (play/pause, time slider, clock, speed, camera
follow, shadows).

The page can be driven from a script:

* ``window.amble`` has ``play()``, ``pause()``, ``seek(t)``, ``time()`` and
  ``ready`` (true once the first frame is drawn).
* ``document.body.dataset.ambleState`` is ``"loading"``, ``"ready"``,
  ``"no-webgl"`` or ``"error"``.
* The URL hash sets the initial state, e.g. ``page.html#t=1.5`` opens paused
  at t = 1.5 s. Keys: ``t`` (seconds), ``play`` (0/1), ``speed``, ``follow``
  (0/1), ``shadows`` (0/1), ``ui`` (0 hides the control bar and captions),
  ``view`` (``iso``, ``side`` or ``front``: the initial camera direction).

Keyboard: space plays/pauses, left/right arrows step one frame.

The page's parts are package data in ``viewer/``: ``viewer.html`` (the template, with
``@TITLE@``, ``@CSS@``, ``@SCENE@``, ``@THREE@`` and ``@VIEWER@`` placeholders),
``viewer.css``, and the script in three parts of one function body: ``data.js`` (status,
scene data, URL hash, frame lookup), ``scene.js`` (three.js objects and camera),
``meshes.js`` (triangle meshes on link frames), ``series.js`` (the time-series panel) and
``player.js`` (time, controls, ``window.amble``, the loop).
"""

from __future__ import annotations

import html as _html
import json
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from .errors import SceneError
from .scene import FORMAT

__all__ = ["render_html", "write_html"]

#: The viewer's parts of one function body, joined in this order (see viewer/data.js).
_VIEWER_PARTS = ("data.js", "scene.js", "meshes.js", "series.js", "player.js")


def _read(*path: str) -> str:
    return resources.files(__package__).joinpath(*path).read_text(encoding="utf-8")


@lru_cache(maxsize=1)
def _viewer() -> tuple[str, str, str]:
    """The page template, its style sheet and the viewer script (package data in ``viewer/``).

    The script is plain ES2020 for a classic ``<script>``: it uses the global ``THREE`` that the
    inlined bundle defines, so no module loading is involved."""
    js = "".join(_read("viewer", name) for name in _VIEWER_PARTS)
    return _read("viewer", "viewer.html"), _read("viewer", "viewer.css"), js


@lru_cache(maxsize=1)
def _three_js() -> str:
    """The vendored three.js bundle (defines the global ``THREE``)."""
    code = _read("_vendor", "three.min.js")
    # A literal "</script" would end the inline element early; "<\/" means the
    # same inside JS strings and regular expressions.
    return re.sub(r"</(script)", r"<\\/\1", code, flags=re.IGNORECASE)


def _scene_json(scene: dict[str, Any]) -> str:
    text = json.dumps(scene, separators=(",", ":"), allow_nan=False)
    # "<", ">" and "&" only occur inside JSON strings, where \u escapes are
    # equivalent; escaping them keeps the data from closing its <script> element.
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def render_html(scene: dict[str, Any], title: str = "amble") -> str:
    """The self-contained viewer page for ``scene`` as a string.

    Args:
        scene: a scene from :func:`amble.viz.scene.frames`.
        title: page title, also shown in the top-left corner.

    Raises:
        SceneError: ``scene`` is not in the ``amble.scene/1`` format or holds
            non-finite numbers.
    """
    if not isinstance(scene, dict) or scene.get("format") != FORMAT:
        got = scene.get("format") if isinstance(scene, dict) else type(scene).__name__
        raise SceneError(f"write_html: expected a scene in format {FORMAT!r}, got {got!r}")
    for key in ("times", "points", "shapes"):
        if key not in scene:
            raise SceneError(f"write_html: scene has no {key!r}")
    template, css, js = _viewer()
    fill = {
        "TITLE": _html.escape(title),
        "CSS": css,
        "SCENE": _scene_json(scene),
        "THREE": _three_js(),
        "VIEWER": js,
    }
    # One pass over the template: the inserted texts are not searched for placeholders.
    return re.sub(r"@([A-Z]+)@", lambda m: fill[m.group(1)], template)

def write_html(path: str | Path, scene: dict[str, Any], title: str = "amble") -> Path:
    """Write the animation of ``scene`` to one offline HTML file.

    Args:
        path: where to write; parent folders are created.
        scene: a scene from :func:`amble.viz.scene.frames`.
        title: page title, also shown in the top-left corner.

    Returns:
        The absolute path of the written file.

    Raises:
        SceneError: see :func:`render_html`.
    """
    page = render_html(scene, title)
    out = Path(path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page, encoding="utf-8")
    return out


