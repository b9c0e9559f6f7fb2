"""The viewer's time-series plot: series grouped into panels (by unit, or by the user's titles),
each with a y axis and its unit, a shared time axis, a legend, and the values at the playhead.

The values the page shows at the playhead are checked against the trajectory's own samples
(the scene's series at that frame), and the tick labels against the range of the data.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from test_html import _chromium, _finish, needs_chromium

import amble
from amble.viz.animate import scene_of, series_groups
from amble.viz.errors import SceneError
from amble.viz.frames import frames
from amble.viz.html import write_html
from amble.viz.scene import Sphere


@pytest.fixture(scope="module")
def walk(compass):
    return amble.simulate(compass, steps=2)


def test_names_of_one_unit_share_a_panel(walk):
    scene = scene_of(walk, fps=30)
    assert scene["series_groups"] == [
        {"title": "angle", "unit": "rad", "series": ["stance", "swing"], "units": ["rad", "rad"]},
        {"title": "energy", "unit": "J", "series": ["energy"], "units": ["J"]},
    ]
    assert scene["time_unit"] == "s" and list(scene["series"]) == ["stance", "swing", "energy"]
    groups = series_groups(walk, ["stance_dot", "stance", "swing_dot", "energy"])
    assert [(g["title"], g["series"]) for g in groups] == [
        ("angular velocity", ["stance_dot", "swing_dot"]), ("angle", ["stance"]), ("energy", ["energy"])]


def test_a_mapping_names_the_panels(walk):
    scene = scene_of(walk, fps=30, series={"legs": ["stance", "swing_dot"], "E": "energy"})
    legs, energy = scene["series_groups"]
    assert legs == {"title": "legs", "unit": "", "series": ["stance", "swing_dot"], "units": ["rad", "rad/s"]}
    assert energy["title"] == "E" and energy["unit"] == "J"
    # the values are the trajectory's samples at or before each frame, whatever the grouping
    t = np.asarray(scene["times"])
    idx = np.searchsorted(walk.t, t, side="right") - 1
    np.testing.assert_allclose(scene["series"]["swing_dot"], walk.column("swing_dot")[idx], atol=1e-5)
    with pytest.raises(SceneError, match="panel 'legs' names no series"):
        scene_of(walk, fps=30, series={"legs": []})
    with pytest.raises(SceneError, match="unknown column 'nope'"):
        scene_of(walk, fps=30, series={"legs": ["nope"]})
    assert "series" not in scene_of(walk, fps=30, series=[])


def test_frames_check_the_panels_against_the_series():
    t = np.array([0.0, 0.5, 1.0])
    pts = {"a": np.zeros((3, 3))}
    scene = frames([Sphere("a", 0.1)], pts, t, series={"x": [1, 2, 3], "y": [0, 0, 1]})
    assert [g["series"] for g in scene["series_groups"]] == [["x"], ["y"]]   # one panel each
    with pytest.raises(SceneError, match="unknown series 'z'"):
        frames([Sphere("a", 0.1)], pts, t, series={"x": [1, 2, 3]}, series_groups=[{"title": "p", "series": ["z"]}])


def _panel(path, tmp_path, t: float) -> dict[str, str]:
    proc = _chromium(f"{path.as_uri()}#t={t}", "--virtual-time-budget=1000", "--dump-dom",
                     profile=tmp_path / f"p{t}")
    tag = re.search(r"<canvas[^>]*id=\"series\"[^>]*>", _finish(proc)).group(0)
    return dict(re.findall(r'data-([a-z]+)="([^"]*)"', tag))


@pytest.mark.browser
@needs_chromium
def test_the_panels_have_axes_a_legend_and_the_values_at_the_playhead(walk, tmp_path):
    spec = {"legs": ["stance", "swing"], "speed": ["stance_dot", "swing_dot"], "energy": ["energy"]}
    scene = scene_of(walk, fps=30, series=spec)
    path = write_html(tmp_path / "walk.html", scene)
    k = 30
    t = scene["times"][k]                                    # 1.0 s: on a frame
    data = _panel(path, tmp_path, t)
    assert data["groups"] == "legs [rad]|speed [rad/s]|energy [J]"
    assert data["series"] == "stance,swing,stance_dot,swing_dot,energy"
    assert data["playhead"] == f"{t:.3f}"
    # each panel's y ticks: evenly spaced numbers within the range of its curves (and its padding)
    for group, ticks in zip(spec.values(), data["yticks"].split("|")):
        v = np.array(ticks.split(), float)
        lo = min(min(x for x in scene["series"][n] if x is not None) for n in group)
        hi = max(max(x for x in scene["series"][n] if x is not None) for n in group)
        pad = 0.07 * (hi - lo)
        assert len(v) >= 2 and np.all(v >= lo - pad) and np.all(v <= hi + pad), (ticks, lo, hi)
        np.testing.assert_allclose(np.diff(v), np.diff(v)[0], rtol=1e-6)
    # the time axis: ticks in seconds from the start to the end of the run
    tt = np.array(data["tticks"].split(), float)
    assert tt[0] == pytest.approx(0.0) and tt[-1] <= scene["times"][-1] and len(tt) >= 3
    # the legend's values are the series at the playhead's frame, to the digits shown
    shown = dict(item.split("=") for item in data["values"].split(";"))
    assert set(shown) == set(scene["series"])
    for name, text in shown.items():
        digits = len(text.split(".")[1]) if "." in text else 0
        assert float(text) == pytest.approx(scene["series"][name][k], abs=0.51 * 10.0 ** -digits), name


def test_the_command_line_chooses_the_panels(tmp_path, capsys):
    import json

    from amble.cli.main import main

    page = tmp_path / "walk.html"
    args = ["simulate", "compass-gait", "--steps", "1", "--animate", str(page)]
    assert main([*args, "--series", "legs=stance,swing", "--series", "E=energy"]) == 0
    scene = json.loads(re.search(r'id="amble-scene">(.*?)</script>', page.read_text(), re.S).group(1))
    assert [(g["title"], g["series"]) for g in scene["series_groups"]] == [("legs", ["stance", "swing"]),
                                                                         ("E", ["energy"])]
    assert main([*args, "--series", "swing_dot,swing,stance_dot"]) == 0
    scene = json.loads(re.search(r'id="amble-scene">(.*?)</script>', page.read_text(), re.S).group(1))
    assert [g["series"] for g in scene["series_groups"]] == [["swing_dot", "stance_dot"], ["swing"]]
    capsys.readouterr()
    assert main([*args, "--series", "legs=stance", "--series", "energy"]) == 2
    assert main(["simulate", "compass-gait", "--steps", "1", "--series", "energy"]) == 2
    err = capsys.readouterr().err
    assert "give every panel a title" in err and "--series needs --animate FILE.html" in err
