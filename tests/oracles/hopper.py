"""Independent vertical one-legged hopper: SciPy and NumPy only.

A body of mass ``m`` on a massless leg: a linear spring ``k`` with a damper ``c`` in parallel.
In flight the leg is held at its rest length ``L`` below the body; it touches the ground when the
body falls through the height ``L``. In stance the body moves on the spring and damper (gravity
``g``); at the bottom (the body's velocity rising through zero) the leg's actuator lengthens the
spring's rest length by ``delta`` (the thrust), and the foot leaves the ground when the ground's
force ``k (L + delta − y) − c ẏ`` falls to zero. The thrust puts in the energy the damper takes
out, so the hopper settles on a limit cycle.

The apex-to-apex map: apex height ``y`` (m) → next apex height. Nothing here is imported from amble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


@dataclass(frozen=True)
class Hopper:
    m: float = 10.0
    L: float = 0.5
    k: float = 4000.0
    c: float = 80.0
    delta: float = 0.05
    g: float = 9.81

    def _stance(self, y0: float, v0: float, rest: float, event) -> tuple[float, float, float]:
        """Integrate m ÿ = k (rest − y) − c ẏ − m g from (y0, v0) to ``event``: (time, y, ẏ)."""
        k, c, m, g = self.k, self.c, self.m, self.g

        def rhs(_t, s):
            return [s[1], (k * (rest - s[0]) - c * s[1]) / m - g]

        event.terminal = True
        sol = solve_ivp(rhs, (0.0, 5.0), [y0, v0], method="DOP853", rtol=1e-13, atol=1e-13, events=event,
                        first_step=1e-7)
        if sol.status != 1:
            raise ValueError("the stance phase did not end")
        y, v = sol.y_events[0][0]
        return float(sol.t_events[0][0]), float(y), float(v)

    def stride(self, y: float) -> dict:
        """One hop from an apex at height ``y``: event times from the apex and the next apex."""
        g, L, k, c = self.g, self.L, self.k, self.c
        if y <= L:
            raise ValueError("apex below the touchdown height")
        t_td = math.sqrt(2 * (y - L) / g)
        v_td = -g * t_td

        def bottom(_t, s):
            return s[1]

        bottom.direction = 1.0
        t1, yb, vb = self._stance(L, v_td, L, bottom)

        def liftoff(_t, s):
            return k * (L + self.delta - s[0]) - c * s[1]

        liftoff.direction = -1.0
        t2, ylo, vlo = self._stance(yb, 0.0, L + self.delta, liftoff)
        if vlo <= 0:
            raise ValueError("lift-off while falling")
        apex = ylo + vlo**2 / (2 * g)
        return {"t_td": t_td, "t_bottom": t_td + t1, "t_lo": t_td + t1 + t2, "t_apex": t_td + t1 + t2 + vlo / g,
                "y_bottom": yb, "y_lo": ylo, "v_lo": vlo, "y_next": apex}

    def apex_map(self, y: float) -> float:
        return self.stride(y)["y_next"]

    def fixed_point(self, lo: float, hi: float, n: int = 20) -> list[float]:
        """Apex heights in [lo, hi] where P(y) = y (grid of n, refined by brentq)."""
        ys = np.linspace(lo, hi, n)
        fs = [self.apex_map(v) - v for v in ys]
        return [brentq(lambda v: self.apex_map(v) - v, ys[i], ys[i + 1], xtol=1e-14, rtol=1e-14)
                for i in range(n - 1) if fs[i] * fs[i + 1] < 0]

    def multiplier(self, y: float, h: float = 1e-5) -> float:
        """dP/dy by a five-point central difference (error ~ h⁴)."""
        P = self.apex_map
        return (8 * (P(y + h) - P(y - h)) - (P(y + 2 * h) - P(y - 2 * h))) / (12 * h)
