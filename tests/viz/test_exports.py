"""GIF/MP4 exports and the scene of a system without a ground: exact frame timing, a clock, an
ffmpeg looked for before any work, no file left by a failed export, progress bars, and
matplotlib's backend left as it was."""

from __future__ import annotations

import time

import numpy as np
import pytest
import sympy as sp

import amble
from amble.cli.main import main
from amble.viz import movie
from amble.viz.animate import scene_of
from amble.viz.errors import ExportError


@pytest.fixture(scope="module")
def pendulum():
    """A pendulum hanging below its pivot: a plain HybridSystem, no ground."""
    m = amble.Model("pendulum")
    (th,) = m.coordinates("th", unit="rad")
    l, mass, g = m.parameters(l=1.0, mass=1.0, g=9.81)
    m.point("pivot", (0, 0))
    m.point("bob", (l * sp.sin(th), -l * sp.cos(th)), mass=mass, link="pivot")
    m.gravity(g)
    system = amble.HybridSystem("pendulum", {"swing": m}, default_start={"swing": [0.8, 0.0]})
    system.transition("kick", "swing", amble.Guard(th, direction=1), amble.Explicit(q=[th], qd=[m.dot(th)]))
    return amble.simulate(system, t_end=1.0)


def test_plain_system_has_a_level_floor_below_it_and_no_step_label(pendulum, compass):
    scene = scene_of(pendulum, fps=30)
    (floor,) = [s for s in scene["shapes"] if s["type"] == "ground"]
    assert floor["slope"] == 0 and floor["height"] < -0.9  # below the bob, which hangs 1 m down
    assert "step" not in scene.get("labels", {})
    walk = scene_of(amble.simulate(compass, steps=2), fps=30)
    assert [s for s in walk["shapes"] if s["type"] == "ground"] and "step" in walk["labels"]


def test_gif_frames_last_one_over_fps_and_the_backend_stays(pendulum, tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    from PIL import Image

    before = matplotlib.get_backend()
    matplotlib.use("svg")
    try:
        path = amble.animate(pendulum, tmp_path / "p.gif", fps=30)
        assert matplotlib.get_backend() == "svg"
    finally:
        matplotlib.use(before)
    im = Image.open(path)
    durations = []
    for k in range(im.n_frames):
        im.seek(k)
        durations.append(im.info["duration"])
    assert movie.movie_fps(path, 30) == 25.0
    assert set(durations) == {40}  # 1/25 s exactly: plays in the trajectory's time
    assert im.n_frames == 26  # t = 0, 0.04, ..., 1.0


def test_gif_has_a_clock(pendulum, tmp_path):
    from PIL import Image

    im = Image.open(amble.animate(pendulum, tmp_path / "p.gif", fps=10))
    corner = []
    for k in (0, 5):
        im.seek(k)
        corner.append(np.asarray(im.convert("L"))[:20, :100].astype(int))
    assert (corner[0] < 128).sum() > 20  # text is drawn there
    assert np.abs(corner[0] - corner[1]).sum() > 0  # and it changes with time


def test_progress_bar_on_movie_export(pendulum, tmp_path, capsys):
    amble.animate(pendulum, tmp_path / "p.gif", fps=10, progress=True)
    assert "writing p.gif" in capsys.readouterr().err


def test_mp4_without_ffmpeg_is_refused_before_any_work(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(movie, "ffmpeg_path", lambda: None)
    t0 = time.perf_counter()
    code = main(["simulate", "compass-gait", "--steps", "200", "--animate", str(tmp_path / "w.mp4")])
    assert code == 2 and time.perf_counter() - t0 < 1.0
    err = capsys.readouterr().err
    assert "MP4 needs ffmpeg" in err and "imageio-ffmpeg" in err and err.count("\n") == 1
    assert not list(tmp_path.iterdir())


def test_failed_export_leaves_no_file(pendulum, monkeypatch, tmp_path):
    monkeypatch.setattr(movie, "ffmpeg_path", lambda: "/bin/false")
    with pytest.raises(ExportError):
        amble.animate(pendulum, tmp_path / "p.mp4", fps=10)
    assert not list(tmp_path.iterdir())


def test_mp4_through_a_pip_installed_ffmpeg(pendulum, tmp_path):
    if movie.ffmpeg_path() is None:
        pytest.skip("no ffmpeg (pip install imageio-ffmpeg)")
    path = amble.animate(pendulum, tmp_path / "p.mp4", fps=10)
    assert path.stat().st_size > 1000 and not list(tmp_path.glob(".*"))


@pytest.mark.browser
def test_viewer_of_a_plain_system_shows_no_ground_slope_or_step(pendulum, compass, tmp_path):
    import re
    import shutil
    import subprocess

    chromium = shutil.which("chromium")
    if chromium is None:
        pytest.skip("headless Chromium not found (apt-get install chromium)")

    def dom(traj, name):
        path = amble.animate(traj, tmp_path / f"{name}.html", fps=30)
        proc = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                               "--disable-dev-shm-usage", f"--user-data-dir={tmp_path / name}",
                               "--virtual-time-budget=1000", "--dump-dom", path.as_uri() + "#t=0.5"],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stderr[-2000:]
        html = re.sub(r"<script.*?</script>", "", proc.stdout, flags=re.S)
        assert 'data-amble-state="ready"' in html, html[:2000]
        return (re.search(r'id="subtitle">([^<]*)<', html).group(1), re.search(r'id="labels">([^<]*)<', html).group(1))

    subtitle, labels = dom(pendulum, "pendulum")
    assert "slope" not in subtitle and "frames" in subtitle and "step" not in labels
    subtitle, labels = dom(amble.simulate(compass, steps=2), "walker")
    assert "slope 2.86°" in subtitle and labels.startswith("step ")


@pytest.mark.browser
def test_viewer_time_series_panel_follows_the_playhead(compass, pendulum, tmp_path):
    import re
    import shutil
    import subprocess

    chromium = shutil.which("chromium")
    if chromium is None:
        pytest.skip("headless Chromium not found (apt-get install chromium)")
    walk = amble.simulate(compass, steps=2)

    def panel(path, t, extra=""):
        proc = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                               "--disable-dev-shm-usage", f"--user-data-dir={tmp_path / f'p{t}'}",
                               "--virtual-time-budget=1000", "--dump-dom", path.as_uri() + f"#t={t}{extra}"],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return re.search(r"<canvas[^>]*id=\"series\"[^>]*>", proc.stdout).group(0)

    path = amble.animate(walk, tmp_path / "walk.html", fps=30)
    for t in (0.25, 1.0):
        tag = panel(path, t)
        assert "hidden" not in tag and 'data-series="stance,swing,energy"' in tag, tag
        assert f'data-playhead="{t:.3f}"' in tag, tag
    assert "display: none" in panel(path, 0.25, "&ui=0")  # a bare figure: no overlay over the robot
    scene = scene_of(walk, fps=30, series=["swing_dot"])
    assert list(scene["series"]) == ["swing_dot"] and len(scene["series"]["swing_dot"]) == len(scene["times"])
    bare = amble.animate(pendulum, tmp_path / "bare.html", fps=30, series=[])
    assert "hidden" in panel(bare, 0.5)
    with pytest.raises(amble.viz.errors.SceneError, match="unknown column"):
        scene_of(walk, series=["nope"])
