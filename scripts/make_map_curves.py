"""Render the compass gait's stability map over (slope, hip mass) with its period-doubling curve for
the docs: ``python scripts/make_map_curves.py`` from the repository root (a few seconds).

The curve is drawn where the largest multiplier of neighbouring cells of one branch passes −1
(:func:`amble.analysis.map_bifurcations.map_crossings`, the system deciding whether two rows'
cells are one branch)."""

from pathlib import Path

import numpy as np

from amble import sweep
from amble.analysis.map_bifurcations import map_crossings
from amble.models import load
from amble.viz.sweep_plots import plot_parameter_map

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "img" / "stability-map-curves.png"


def main() -> None:
    walker = load("compass-gait")
    grid = {"mh": np.linspace(5.0, 20.0, 16), "slope": np.linspace(0.06, 0.09, 16)}
    res = sweep(walker, "fixed-point", grid, scheduler="synchronous", progress=False)
    found = map_crossings(res, walker)
    print(len(res.rows), "cells,", len(found), "crossings:", sorted({c.kind for c in found}))
    plot_parameter_map(res, OUT, crossings=found,
                       title="Compass gait: largest multiplier and its period-doubling curve")
    print(OUT)


if __name__ == "__main__":
    main()
