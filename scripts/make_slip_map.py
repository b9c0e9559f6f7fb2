"""Render the SLIP runner's stability map in (angle of attack, leg stiffness) for the docs:
``python scripts/make_slip_map.py`` from the repository root (a few minutes on one core).

The map is the fixed-point sweep's own plot. Each row of a map is one task that starts its branch
afresh, so its branch ids say nothing from row to row; the cells are marked instead by which of
the SLIP's two gaits they hold: the running gait (apex below 1.5 m) or, where a row's search
found only that, the slow, high and unstable hopping gait (apex near 2 m)."""

import math
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from amble import sweep
from amble.models.slip import build
from amble.viz.sweep_plots import plot_parameter_map

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "img" / "slip-stability-map.png"
TABLE = Path(tempfile.gettempdir()) / "slip-stability-map.csv"  # resumed if the run is interrupted


def main() -> None:
    grid = {"k": np.linspace(14000.0, 28000.0, 15), "alpha": np.radians(np.linspace(64.0, 71.5, 16))}
    res = sweep(build(), "fixed-point", grid, scheduler="synchronous", progress=False, out=TABLE)
    rows = [{**r, "branch": "high hop" if r["status"] == "ok" and r["x_y"] > 1.5 else "run"} for r in res.records()]
    stable = sum(1 for r in rows if r["status"] == "ok" and r["stable"])
    print(f"{len(rows)} points, {stable} stable, {sum(r['status'] != 'ok' for r in rows)} without a gait")
    plot_parameter_map(SimpleNamespace(params=res.params, rows=rows), OUT,
                       title="SLIP runner: largest multiplier (white: |λ| = 1; grey: no gait)")
    print(OUT, TABLE, "alpha from", math.degrees(grid["alpha"][0]), "to", math.degrees(grid["alpha"][-1]), "deg")


if __name__ == "__main__":
    main()
