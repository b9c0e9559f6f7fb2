"""A basin cell walked run by run with ``engine.run``: the independent loop that basin maps and
batched walks are checked against."""

import math

import numpy as np

from amble.simulation.engine import run


def walk_cell(k, p, x, xs, opts, steps, every, tol):
    """(outcome, reason, footfalls, distance) of the walk from ``x`` in runs of ``every``
    footfalls until ``max |x − xs| < tol`` or ``steps`` footfalls (outcomes as basin maps name them)."""
    done, dist = 0, math.nan
    while done < steps:
        m = min(every, steps - done)
        r = run(k, p, 0, x, steps=m, opts=opts)
        x = r.x
        if not r.completed:
            return ("fell" if r.status == "fell" else "failed"), r.status, done + r.steps, dist
        done += m
        dist = float(np.max(np.abs(x - xs)))
        if dist < tol:
            return "converged", "", done, dist
    return "not converged", "", done, dist
