"""Render the README pictures: each thesis robot in the 3D viewer (headless Chromium) and the
compass gait's limit cycle. Run from the repository root: ``python scripts/make_readme_images.py``."""

import subprocess
import tempfile
from pathlib import Path

import amble
from amble.analysis.poincare import find_fixed_point
from amble.models import load

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


if __name__ == "__main__":
    main()
