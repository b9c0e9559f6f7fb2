"""Virtual constraints of hybrid zero dynamics (HZD): outputs ``y = h₀(q) − h_d(θ(q), α)``.

One output per input: ``h₀(q)`` are the controlled quantities (typically the actuated joint
angles) and ``h_d`` their desired evolution, Bézier polynomials of degree ``M`` in the
normalised phase ``s = (θ − θ⁺)/(θ⁻ − θ⁺)`` of a phase variable ``θ(q)`` that increases
monotonically over a step (Westervelt, Grizzle, Chevallereau, Choi & Morris, *Feedback Control
of Dynamic Bipedal Robot Locomotion*, 2007, ch. 6):

    h_d,i(s) = Σ_k α_{i,k} · C(M, k) s^k (1 − s)^{M−k}.

Every coefficient ``α_{i,k}``, the phase range ``θ⁺`` (``phase_start``) and ``θ⁻``
(``phase_end``), and the gains ``epsilon``, ``kp``, ``kd`` of the output dynamics
``ÿ = −kd ẏ/ε − kp y/ε²`` are *parameters* of the model: a new gait or gain recompiles nothing.
:func:`amble.derive` turns the constraints into the input–output linearising law
(:mod:`amble.derivation.hzd`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from math import comb
from typing import Any

import sympy as sp

from ..errors import ModelError
from .expressions import checked_expr


@dataclass
class VirtualConstraints:
    """Outputs ``h₀`` (nu × 1), phase ``θ``, coefficients ``alpha`` (nu × (M+1) parameter
    symbols), phase range and gains (parameter symbols)."""

    outputs: sp.Matrix
    phase: sp.Expr
    alpha: sp.Matrix
    phase_start: sp.Symbol
    phase_end: sp.Symbol
    epsilon: sp.Symbol
    kp: sp.Symbol
    kd: sp.Symbol

    @property
    def degree(self) -> int:
        return self.alpha.cols - 1

    def s(self, theta: Any = None) -> sp.Expr:
        """Normalised phase ``s = (θ − θ⁺)/(θ⁻ − θ⁺)`` (of ``θ(q)`` unless ``theta`` is given)."""
        th = self.phase if theta is None else theta
        return (th - self.phase_start) / (self.phase_end - self.phase_start)

    def desired(self, theta: Any = None) -> sp.Matrix:
        """``h_d`` at the phase (of ``q``, or of a given ``theta``)."""
        s, m = self.s(theta), self.degree
        basis = [comb(m, k) * s**k * (1 - s) ** (m - k) for k in range(m + 1)]
        return sp.Matrix([sum((self.alpha[i, k] * basis[k] for k in range(m + 1)), sp.Integer(0))
                          for i in range(self.alpha.rows)])

    @property
    def y(self) -> sp.Matrix:
        """The outputs ``y(q) = h₀(q) − h_d(θ(q))``."""
        return self.outputs - self.desired()


def declare(model: Any, outputs: Sequence[Any], phase: Any, alpha: Any, phase_range: tuple[float, float],
            epsilon: float = 0.1, kp: float = 1.0, kd: float = 2.0, prefix: str = "") -> VirtualConstraints:
    """Declare the virtual constraints on ``model`` (see :meth:`Model.virtual_constraints`)."""
    outs = [checked_expr(model, o, "virtual-constraint output") for o in outputs]
    ph = checked_expr(model, phase, "phase variable")
    if len(outs) != len(model.inputs) or not outs:
        raise ModelError(f"model {model.name!r}: {len(outs)} virtual-constraint output(s) for "
                         f"{len(model.inputs)} input(s); HZD needs one output per input")
    for e, what in [*((o, "output") for o in outs), (ph, "phase variable")]:
        bad = sorted(str(s) for s in e.free_symbols - set(model.q) - set(model.params))
        if bad:
            raise ModelError(f"model {model.name!r}: virtual-constraint {what} {e} uses {', '.join(bad)}; "
                             "it must be a function of the coordinates")
    rows = [list(r) for r in alpha]
    if len(rows) != len(outs) or len({len(r) for r in rows}) != 1 or len(rows[0]) < 2:
        raise ModelError(f"model {model.name!r}: alpha needs {len(outs)} rows of equal length ≥ 2 "
                         "(one Bézier polynomial per output)")
    if model._laws:
        raise ModelError(f"model {model.name!r}: virtual constraints set the control law; it has one already")
    syms = [[model.parameter(f"{prefix}alpha_{i}_{k}", v, f"Bézier coefficient {k} of output {i}", "rad")
             for k, v in enumerate(r)] for i, r in enumerate(rows)]
    th0, th1 = phase_range
    if not float(th0) != float(th1):
        raise ModelError(f"model {model.name!r}: the phase range must have two different ends")
    vc = VirtualConstraints(
        sp.Matrix(outs), ph, sp.Matrix(syms),
        model.parameter(f"{prefix}phase_start", th0, "phase variable just after the footfall θ⁺"),
        model.parameter(f"{prefix}phase_end", th1, "phase variable at the footfall θ⁻"),
        model.parameter("epsilon", epsilon, "time scale of the output dynamics ε", "s"),
        model.parameter("kp", kp, "proportional gain of the output dynamics"),
        model.parameter("kd", kd, "derivative gain of the output dynamics"))
    model.virtual = vc
    return vc
