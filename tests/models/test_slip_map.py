"""The SLIP's self-stable running region in the (leg stiffness k, angle of attack alpha) plane:
amble's fixed-point sweep against the independent SciPy runner (tests/oracles/slip.py).

Seyfarth et al. 2002 found self-stable running in a narrow band of angles of attack whose
position rises with the leg stiffness. At every point of the grid: a gait amble finds is a
fixed point of the oracle's apex-to-apex map with the same multiplier, amble calls it stable
exactly when the oracle's multiplier is inside the unit circle, and where amble finds no gait
the oracle has no stable one either. (The oracle also finds unstable gaits the sweep, which
follows the default gait, does not report: the partner born with the running gait at its fold,
and a slow hop with its apex near 2 m.)"""

import math

import numpy as np
import pytest
from oracles.slip import Slip

from amble import sweep
from amble.models.slip import build

RUN = {"scheduler": "synchronous", "progress": False}


def _check_rows(rows, scan: bool) -> dict:
    """Compare each sweep row with the oracle; where amble found no gait the oracle's apex
    heights are scanned for a stable one, and with ``scan`` also where amble found one (for a
    second stable gait)."""
    seen = {"stable": 0, "unstable": 0, "failed": 0}
    for r in rows:
        o = Slip(k=r["k"], alpha=r["alpha"])
        where = f"k = {r['k']:.0f} N/m, alpha = {math.degrees(r['alpha']):.2f} deg"
        if r["status"] == "ok":
            y = o.root_near(r["x_y"])
            assert y is not None, f"{where}: amble's gait at y = {r['x_y']} is not one of the oracle's"
            assert abs(r["x_y"] - y) <= 1e-9, where
            mu = o.multiplier(y)
            assert abs(r["max_modulus"] - abs(mu)) <= 1e-5 * max(1.0, abs(mu)), where
            assert r["stable"] == (abs(mu) < 1), where
            seen["stable" if r["stable"] else "unstable"] += 1
            others = o.gaits() if scan else []
            assert all(abs(mu_) > 1 for y_, mu_ in others if abs(y_ - y) > 1e-6), f"{where}: a second stable gait"
        else:
            seen["failed"] += 1
            stable = [(y_, mu_) for y_, mu_ in o.gaits() if abs(mu_) < 1]
            assert not stable, f"{where}: amble found no gait where the oracle has the stable {stable}"
    return seen


GRID = {"k": np.linspace(16000.0, 28000.0, 5), "alpha": np.radians(np.linspace(66.0, 70.0, 5))}


@pytest.fixture(scope="module")
def stable_region():
    """The 5 × 5 fixed-point map over 16–28 kN/m and 66–70° (about 5 s)."""
    return sweep(build(), "fixed-point", GRID, **RUN).records()


def test_stable_region_map_matches_oracle(stable_region):
    seen = _check_rows(stable_region, scan=False)
    assert sum(seen.values()) == 25
    # the band: stable gaits, gaits past the flip (|μ| > 1), and falls below the fold
    assert seen["stable"] >= 8 and seen["unstable"] >= 4 and seen["failed"] >= 5


@pytest.mark.slow
def test_the_stable_gait_is_the_only_stable_one(stable_region):
    _check_rows(stable_region, scan=True)
