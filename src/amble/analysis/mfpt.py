"""How far a walker goes on rough ground: the mean first-passage time (MFPT) to a fall.

Floquet multipliers say whether a gait survives infinitesimal disturbances; on terrain that
changes from step to step a walker that is stable on average still falls, after a number of
steps whose mean is the MFPT (Byl & Tedrake 2009, *Metastable walking machines*).

**Terrain.** A :class:`Terrain` draws some parameters anew for every step, independently: with
``Terrain.parse("slope~normal(0.08,0.01)")`` each step runs on its own ramp — it starts just
after the impact that ended the step before and ends at the next footfall on that ramp (Byl &
Tedrake's stochastic rimless wheel and compass gait). The state carries over unchanged from one
ramp to the next: coordinates are angles from the vertical, so only the ground under the next
footfall changes.

**Monte Carlo** (:func:`mfpt`). ``runs`` walkers start from the gait at the terrain's mean and
walk one step at a time, all of them in one compiled call per step (each with its own draw,
:func:`amble.simulation.engine.walk_many`), until each falls (any end but a completed step) or
has walked ``max_steps``. A metastable walker falls at a constant rate per step once its
transient is over, so the MFPT is estimated as ``steps walked / falls`` (the maximum-likelihood
estimate of a geometric law, walkers that never fell counted as censored), with the exact
chi-square confidence interval of a Poisson rate.

Draws are reproducible: the same ``seed`` gives the same walks.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from ..backend.kernels import compiled
from ..errors import ParameterError
from ..simulation.engine import CODE, Options, walk_many
from ..simulation.simulate import parameter_vector
from .poincare import find_fixed_point

#: distributions a terrain parameter may be drawn from, and the names of their two numbers
DISTRIBUTIONS = {"normal": ("mean", "sd"), "uniform": ("low", "high")}

_DRAW = re.compile(r"^\s*([A-Za-z_]\w*)\s*~\s*([a-z]+)\s*\(\s*([^,()]+?)\s*,\s*([^,()]+?)\s*\)\s*$")


@dataclass(frozen=True)
class Terrain:
    """Parameters drawn anew for every step: name → (distribution, a, b), with ``normal``
    (mean, standard deviation) or ``uniform`` (low, high), in the parameter's own unit."""

    draws: Mapping[str, tuple[str, float, float]]

    def __post_init__(self) -> None:
        if not self.draws:
            raise ParameterError("a terrain draws at least one parameter")
        for name, (kind, a, b) in self.draws.items():
            if kind not in DISTRIBUTIONS:
                known = ", ".join(DISTRIBUTIONS)
                raise ParameterError(f"terrain {name!r}: distribution {kind!r} is not one of {known}")
            if not (math.isfinite(a) and math.isfinite(b)):
                raise ParameterError(f"terrain {name!r}: {kind}({a}, {b}) needs finite numbers")
            if kind == "normal" and b < 0 or kind == "uniform" and b < a:
                what = "a standard deviation ≥ 0" if kind == "normal" else "low ≤ high"
                raise ParameterError(f"terrain {name!r}: {kind}({a:g}, {b:g}) needs {what}")

    @classmethod
    def parse(cls, texts: str | Sequence[str]) -> Terrain:
        """``"slope~normal(0.08,0.01)"`` (or several): read with a pattern and ``float``, never evaluated."""
        draws: dict[str, tuple[str, float, float]] = {}
        for text in [texts] if isinstance(texts, str) else texts:
            m = _DRAW.match(text)
            if m is None:
                raise ParameterError(f"terrain {text!r}: write NAME~normal(MEAN,SD) or NAME~uniform(LOW,HIGH)")
            name, kind, a, b = m.groups()
            try:
                draws[name] = (kind, float(a), float(b))
            except ValueError:
                raise ParameterError(f"terrain {text!r}: {a!r} and {b!r} must be numbers") from None
        return cls(draws)

    def mean(self) -> dict[str, float]:
        """Each drawn parameter's mean."""
        return {k: a if kind == "normal" else 0.5 * (a + b) for k, (kind, a, b) in self.draws.items()}

    def sample(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` independent draws of every parameter."""
        return {k: rng.normal(a, b, n) if kind == "normal" else rng.uniform(a, b, n)
                for k, (kind, a, b) in self.draws.items()}

    def to_json(self) -> dict[str, Any]:
        return {k: {"distribution": kind, DISTRIBUTIONS[kind][0]: a, DISTRIBUTIONS[kind][1]: b}
                for k, (kind, a, b) in self.draws.items()}


@dataclass
class FirstPassage:
    """The MFPT (steps) with its confidence interval, and what it was estimated from."""

    mfpt: float
    ci_low: float
    ci_high: float
    confidence: float
    falls: int
    steps: int
    runs: int
    censored: int
    method: str
    terrain: dict[str, Any]

    def to_json(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def _rate_interval(falls: int, steps: int, confidence: float) -> tuple[float, float]:
    """Exact (Garwood) interval of a Poisson rate: ``falls`` events over ``steps`` steps."""
    from scipy.stats import chi2

    a = 1.0 - confidence
    low = chi2.ppf(a / 2, 2 * falls) / (2 * steps) if falls > 0 else 0.0
    high = chi2.ppf(1 - a / 2, 2 * falls + 2) / (2 * steps)
    return float(low), float(high)


#: the longest a walker goes without a footfall (s) where neither the options nor the system bound it
NO_FOOTFALL = 10.0


def walk_options(system: Any, opts: Options | None) -> Options:
    """``opts`` (default :class:`Options`) with a bound on the time without a footfall: the
    options' own, else the system's ``max_step_time``, else :data:`NO_FOOTFALL`. Without one, a
    walker that a drawn terrain turns round (a rimless wheel rolling back down an uphill draw)
    walks on until the integrator's step cap, minutes for a batch; with it, that walker has
    fallen when the bound passes."""
    opts = opts or Options()
    if opts.max_step_time > 0:
        return opts
    return replace(opts, max_step_time=float(getattr(system, "max_step_time", 0.0)) or NO_FOOTFALL)


def terrain_start(system: Any, terrain: Terrain, params: Mapping[str, float] | None,
                  start: Sequence[float] | None) -> tuple[Any, list[str], np.ndarray, np.ndarray, int]:
    """The compiled kernels, their parameter names, the parameter vector at the terrain's mean
    (``params`` for the rest) and the walkers' first post-impact state and mode: ``start``, else
    the gait at the terrain's mean. A terrain drawing a name that is no parameter is refused."""
    k = compiled(system)
    names = list(k.meta["params"])
    unknown = [n for n in terrain.draws if n not in names]
    if unknown:
        raise ParameterError(f"terrain draws {', '.join(map(repr, unknown))}: not parameters of {system.name!r}")
    base = {**(params or {}), **terrain.mean()}
    p0 = parameter_vector(k, base, system)
    if start is None:
        lc = find_fixed_point(system, params=base)
        return k, names, p0, np.asarray(lc.fixed_point, float), k.mode_index(lc.mode)
    return k, names, p0, np.asarray(start, float), 0


def mfpt(system: Any, terrain: Terrain, *, runs: int = 1000, max_steps: int = 1000, seed: int = 0,
         params: Mapping[str, float] | None = None, start: Sequence[float] | None = None,
         confidence: float = 0.95, threads: int = 1, opts: Options | None = None) -> FirstPassage:
    """The mean first-passage time to a fall on ``terrain`` by Monte Carlo (module docstring).

    ``params``: the other parameters; ``start``: the first post-impact state of every walker
    (default: the fixed point at the terrain's mean); ``threads``: walkers walked side by side on
    this many threads (the results do not depend on it)."""
    for name, v, low in (("runs", runs, 1), ("max_steps", max_steps, 1), ("threads", threads, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise ParameterError(f"{name} must be an integer ≥ {low}, got {v!r}")
    if not 0 < confidence < 1:
        raise ParameterError(f"confidence must be in (0, 1), got {confidence!r}")
    k, names, p0, x0, mode = terrain_start(system, terrain, params, start)
    rng = np.random.default_rng(seed)
    cols = [names.index(n) for n in terrain.draws]
    X = np.tile(x0, (runs, 1))
    alive = np.ones(runs, bool)
    walked = np.zeros(runs, np.int64)
    opts = walk_options(system, opts)
    for _ in range(max_steps):
        idx = np.flatnonzero(alive)
        if idx.size == 0:
            break
        P = np.tile(p0, (idx.size, 1))
        for c, v in zip(cols, terrain.sample(rng, idx.size).values()):
            P[:, c] = v
        out = walk_many(k, P, mode, X[idx], x0, steps=1, check_every=1, tol=-1.0, opts=opts, threads=threads)
        ok = out["code"] == CODE["STEPS_DONE"]
        walked[idx[ok]] += 1
        X[idx[ok]] = out["x"][ok, : X.shape[1]]
        alive[idx[~ok]] = False
    falls, steps = int((~alive).sum()), int(walked.sum()) + int((~alive).sum())
    low, high = _rate_interval(falls, steps, confidence)
    est = steps / falls if falls else math.inf
    return FirstPassage(mfpt=est, ci_low=1.0 / high, ci_high=1.0 / low if low > 0 else math.inf,
                        confidence=confidence, falls=falls, steps=steps, runs=runs, censored=int(alive.sum()),
                        method="montecarlo", terrain=terrain.to_json())
