"""A robot that is no walker gets a floor at the lowest point it reaches, and the camera's
distance comes from the robot's own extent over the run (not its first pose)."""

import math

import numpy as np
import sympy as sp

from amble import HybridSystem, Model, simulate
from amble.viz.animate import scene_of
from amble.viz.html import write_html

L = 0.7


def _pendulum():
    m = Model("pendulum")
    (th,) = m.coordinates("th")
    l, mass, g = m.parameters(l=L, mass=1.0, g=9.81)
    m.point("pivot", (0, 0))
    m.point("bob", (l * sp.sin(th), -l * sp.cos(th)), mass=mass, link="pivot")
    m.gravity(g)
    return HybridSystem("pendulum", {"swing": m})


def test_pendulum_stands_over_a_floor_at_its_lowest_point_and_is_framed_by_its_length(tmp_path):
    tr = simulate(_pendulum(), [1.2, 0.0], t_end=1.0, sample_dt=0.01)
    scene = scene_of(tr, fps=30, series=[])
    grounds = [s for s in scene["shapes"] if s["type"] == "ground"]
    assert len(grounds) == 1
    floor = grounds[0]
    assert floor["slope"] == 0
    bob = next(s for s in scene["shapes"] if s["type"] == "sphere" and s["at"] == "bob")
    # the bob passes the bottom (|θ| from 1.2 rad through 0): its lowest height is -l cos θ at the
    # smallest |θ| among the frames, less its radius
    theta = np.interp(scene["times"], tr.t, tr.column("th"))
    lowest = -L * math.cos(float(np.min(np.abs(theta)))) - bob["radius"]
    assert abs(floor["height"] - lowest) < 5e-4  # frames interpolate positions, θ here
    assert abs(floor["height"] - (-L - bob["radius"])) < 2e-3  # it swings through the bottom
    # two points joined by a rigid link: every frame's bounding-box diagonal is the link's length
    assert abs(scene["size"] - L) < 1e-4
    html = write_html(tmp_path / "p.html", scene).read_text()
    assert "g.height" in html and "data.size" in html


def test_a_walker_keeps_its_slope_through_the_origin(compass):
    tr = simulate(compass, steps=1, sample_dt=0.02)
    ground = [s for s in scene_of(tr, fps=20, series=[])["shapes"] if s["type"] == "ground"]
    assert len(ground) == 1 and "height" not in ground[0]
