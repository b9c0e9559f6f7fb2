"""Offline HTML viewer: page content, and rendering in headless Chromium.

The browser tests drive Chromium from the command line only: the page reads
its initial time from the URL hash (``#t=...``), so two ``--screenshot`` runs
at two times show whether the robot is drawn and whether it moves.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from amble.errors import AmbleError
from amble.viz.errors import SceneError
from amble.viz.html import render_html, write_html
from amble.viz.scene import Cylinder, Ground, Sphere, frames

CHROMIUM = shutil.which("chromium") or (
    "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None
)
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="headless Chromium not found (apt-get install chromium)"
)

# Software WebGL (SwiftShader), no network, no profile side effects.
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-dev-shm-usage",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--mute-audio",
    "--hide-scrollbars",
]
WIDTH, HEIGHT = 800, 600
HIP_RED = (0.9, 0.1, 0.1)
FOOT_BLUE = (0.1, 0.25, 0.95)


def walker_scene(duration: float = 2.0, fps: int = 60) -> dict:
    """A two-link walker: the hip slides down a 0.1 rad slope, the legs swing."""
    slope, leg, speed = 0.1, 1.0, 0.6
    t = np.arange(int(duration * fps) + 1) / fps
    s = speed * t  # distance along the slope
    hip = np.column_stack([s * np.cos(slope), 0 * t, -s * np.sin(slope) + 0.93])
    swing = 0.4 * np.sin(2 * np.pi * t / 1.2)
    feet = {
        name: hip + leg * np.column_stack([np.sin(a), 0 * t, -np.cos(a)])
        for name, a in (("left", swing), ("right", -swing))
    }
    shapes = [
        Ground(slope=slope, width=1.5),
        Cylinder(("hip", "left"), radius=0.03),
        Cylinder(("hip", "right"), radius=0.03),
        Sphere("hip", radius=0.12, color=HIP_RED),
        Sphere("left", radius=0.05, color=FOOT_BLUE),
        Sphere("right", radius=0.05, color=FOOT_BLUE),
    ]
    points = {"hip": hip, **feet}
    return frames(shapes, points, t, follow="hip", labels={"step": (t // 0.6).astype(int)})


# ---- page content (no browser) -------------------------------------------------


def test_page_is_self_contained(tmp_path: Path) -> None:
    path = write_html(tmp_path / "sub" / "walk.html", walker_scene(), title="walker <demo>")
    page = path.read_text(encoding="utf-8")
    assert path.is_absolute() and path.exists()
    assert "<title>walker &lt;demo&gt;</title>" in page
    # Nothing is loaded from elsewhere: no external scripts, styles or imports.
    assert not re.search(r"<script[^>]*\bsrc=", page)
    assert "<link" not in page
    assert not re.search(r"\bimport\s*\(|from\s*['\"]https?:", page)
    assert "OrbitControls" in page and "WebGLRenderer" in page
    assert "preserveDrawingBuffer" in page
    # Three inline scripts: data, three.js, viewer; no stray closing tags inside.
    assert page.count("</script>") == 3
    # The scene round-trips through the embedded JSON.
    data = re.search(r'id="amble-scene">(.*?)</script>', page, re.S).group(1)
    assert json.loads(data)["points"]["hip"][:3] == [0, 0, 0.93]


def test_scene_text_cannot_break_out_of_script() -> None:
    scene = walker_scene(duration=0.1)
    scene["labels"]["note"] = ["</script><b>x</b>"] * len(scene["times"])
    page = render_html(scene)
    assert "</script><b>" not in page
    data = re.search(r'id="amble-scene">(.*?)</script>', page, re.S).group(1)
    assert json.loads(data)["labels"]["note"][0] == "</script><b>x</b>"


def test_rejects_non_scene(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="amble.scene/1"):
        write_html(tmp_path / "x.html", {"times": []})
    with pytest.raises(AmbleError, match="'shapes'"):
        render_html({"format": "amble.scene/1", "times": [0], "points": {}})


def test_viewer_parts_are_filled_in() -> None:
    scene = walker_scene(duration=0.1)
    page = render_html(scene)
    assert not re.search(r"@(TITLE|CSS|SCENE|THREE|VIEWER)@", page)  # every placeholder filled
    # Inserted text is not searched for placeholders again.
    assert render_html(scene, title="@CSS@").count("@CSS@") == 2  # in <title> and in the corner
    for part in ("ambleState = 'ready'", "function addGround", "function locate", "#bar button"):
        assert part in page


# ---- in the browser ---------------------------------------------------------------


def _chromium(url: str, *args: str, profile: Path) -> subprocess.Popen:
    cmd = [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args, url]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _finish(proc: subprocess.Popen, timeout: float = 60.0) -> str:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"chromium did not finish within {timeout} s")
    assert proc.returncode == 0, f"chromium exited with {proc.returncode}:\n{err[-2000:]}"
    return out


def _dump_dom(url: str, tmp_path: Path, *args: str) -> str:
    proc = _chromium(url, "--virtual-time-budget=1000", *args, "--dump-dom", profile=tmp_path / "p")
    return _finish(proc)


def _visible(dom: str) -> str:
    """The DOM without its (large) scripts, for failure messages."""
    return re.sub(r"<script.*?</script>", "", dom, flags=re.S)[:3000]


def _state(dom: str) -> str:
    m = re.search(r'<body[^>]*data-amble-state="([^"]*)"', dom)
    assert m, _visible(dom)
    return m.group(1)


def _read_png(path: Path) -> np.ndarray:
    image = pytest.importorskip("matplotlib.image")
    rgb = np.asarray(image.imread(str(path)))[..., :3]
    return np.rint(rgb * 255).astype(np.int16)  # int16: differences must not wrap


def _masks(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of the red hip and of the blue feet (shading keeps the hue)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 90) & (r > 2 * g) & (r > 2 * b)
    blue = (b > 90) & (b > 2 * r) & (b > 1.4 * g)
    return red, blue


@pytest.mark.browser
@needs_chromium
def test_page_loads_and_seeks(tmp_path: Path) -> None:
    path = write_html(tmp_path / "walk.html", walker_scene())
    dom = _dump_dom(path.as_uri() + "#t=1.25", tmp_path)
    assert _state(dom) == "ready", _visible(dom)
    assert re.search(r'id="clock">1\.25 / 2\.00 s<', dom), _visible(dom)
    assert re.search(r'id="labels">step 2<', dom), _visible(dom)


@pytest.mark.browser
@needs_chromium
def test_without_webgl_shows_message(tmp_path: Path) -> None:
    path = write_html(tmp_path / "walk.html", walker_scene(duration=0.2))
    dom = _dump_dom(path.as_uri(), tmp_path, "--disable-3d-apis")
    assert _state(dom) == "no-webgl"
    assert "WebGL is not available" in dom


@pytest.mark.browser
@needs_chromium
def test_robot_is_drawn_and_moves(tmp_path: Path) -> None:
    path = write_html(tmp_path / "walk.html", walker_scene())
    # Fixed camera (follow=0) and no overlays (ui=0): the walker crosses the view.
    shots = {t: tmp_path / f"t{t}.png" for t in (0.3, 1.6)}
    procs = [
        _chromium(
            f"{path.as_uri()}#t={t}&follow=0&ui=0",
            f"--window-size={WIDTH},{HEIGHT}",
            "--virtual-time-budget=1000",
            f"--screenshot={png}",
            profile=tmp_path / f"profile{i}",
        )
        for i, (t, png) in enumerate(shots.items())
    ]
    for proc in procs:
        _finish(proc)
    early, late = (_read_png(p) for p in shots.values())
    assert early.shape[:2] == (HEIGHT, WIDTH)

    for img in (early, late):
        # (a) not blank: a lit 3D scene has many colours and real contrast.
        assert img.std() > 10
        assert len(np.unique(img.reshape(-1, 3), axis=0)) > 200
        red, blue = _masks(img)
        assert red.sum() > 150, "hip sphere not drawn"
        assert blue.sum() > 30, "foot spheres not drawn"

    # (b) the robot moved: the hip walked downhill (+x is to the right on screen)...
    (red0, _), (red1, _) = _masks(early), _masks(late)
    x0, x1 = np.nonzero(red0)[1].mean(), np.nonzero(red1)[1].mean()
    assert x1 - x0 > 20, f"hip moved only {x1 - x0:.1f} px"
    # ...and the pictures differ where the robot is.
    robot = red0 | red1 | _masks(early)[1] | _masks(late)[1]
    rows, cols = np.nonzero(robot)
    region = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))
    assert np.abs(early[region] - late[region]).mean() > 5
