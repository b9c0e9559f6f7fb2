"""Render the README pictures: each thesis robot in the 3D viewer (headless Chromium), the
compass gait's limit cycle, and Bolt (example-robot-data) with its meshes for the URDF guide.
Run from the repository root: ``python scripts/make_readme_images.py``."""

import subprocess
import tempfile
from importlib.metadata import distribution
from pathlib import Path

import numpy as np

import amble
from amble.analysis.poincare import find_fixed_point
from amble.models import load, load_robot

OUT = Path("docs/img")
ROBOTS = ["compass-gait", "kneed-biped", "humanoid-2d", "humanoid-3d"]


def screenshot(html: Path, png: Path, t: float, view: str = "side") -> None:
    with tempfile.TemporaryDirectory() as prof:
        subprocess.run(
            ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={prof}", "--window-size=640,420", "--virtual-time-budget=4000",
             f"--screenshot={png}", f"{html.as_uri()}#t={t}&ui=0&view={view}"],
            check=True, capture_output=True, timeout=120)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as d:
        for name in ROBOTS:
            system = load(name)
            walk = amble.simulate(system, steps=4, sample_dt=0.005)
            html = amble.animate(walk, Path(d) / f"{name}.html")
            t = float(walk.step_events[2].t) - 0.03  # just before a heel strike: legs spread
            screenshot(html, OUT / f"{name}.png", t=t, view="iso" if name == "humanoid-3d" else "side")
    cycle = find_fixed_point(load("compass-gait"))
    amble.plot_limit_cycle(cycle, OUT / "compass-gait-limit-cycle.png")
    bolt_image(OUT / "bolt.png")


def bolt_image(png: Path) -> None:
    """Bolt hung from its base, legs swinging apart, as in the URDF guide's example."""
    erd = distribution("example-robot-data")
    urdf = next(erd.locate_file(f) for f in erd.files or () if str(f).endswith("bolt.urdf"))
    bolt = load_robot(urdf, fixed_base=True)
    names = bolt.state_names()[:6]
    x0 = np.zeros(12)
    x0[names.index("FL_HFE")], x0[names.index("FR_HFE")] = 0.6, -0.4
    swing = amble.simulate(bolt, x0=x0, t_end=1.0, sample_dt=0.01)
    with tempfile.TemporaryDirectory() as d:
        screenshot(amble.animate(swing, Path(d) / "bolt.html"), png, t=0.0, view="iso")


if __name__ == "__main__":
    main()
