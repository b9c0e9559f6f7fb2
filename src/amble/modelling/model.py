"""The equation-based model: coordinates, parameters, points, masses, energies and forces.

A :class:`Model` holds what one writes on paper for a mechanical system in one contact mode:

* generalized coordinates ``q`` (sympy symbols; their velocities are the symbols ``<name>_dot``),
* parameters with default values (they stay symbols: compiled kernels take them at run time),
* named points given as 2D ``(x, z)`` or 3D ``(x, y, z)`` position expressions of ``q``,
  optionally carrying a point mass,
* extra kinetic / potential energy terms, or ``K`` and ``V`` (or ``L``) given outright,
* generalized forces Γ(q, q̇, t), including piecewise ones,
* actuators (inputs ``u`` acting through ``B``) and their control law — see
  :mod:`amble.modelling.actuators`.

Conventions: SI units, angles in radians. The world frame has ``x`` forward, ``y`` to the left
(3D only), ``z`` up; gravity points along ``-z`` unless :meth:`Model.gravity` says otherwise.
2D models live in the x–z plane. A slope is a *rotated ground*, not a rotated gravity: positions
and angles are written against the true vertical, and the walking surface is a plane through
the stance foot descending along ``+x`` (see :mod:`amble.modelling.contact.ground`). That keeps angles in the
convention of the thesis and of Drake (from the vertical, positive in the walking direction).
"""

from __future__ import annotations

import math
from typing import Any

import sympy as sp

from ..errors import ModelError
from .actuators import Actuators
from .constrained_tree import ConstrainedTree
from .dag import dag_diff, free_symbols
from .domain import POSITIVE
from .expressions import checked_expr as _expr
from .expressions import checked_matrix as _matrix
from .geometry import t
from .limits import LimitGuard, limit_guards
from .revision import declaration
from .text import expr_of
from .tree import RigidTree


class Model(Actuators):
    """A mechanical system in one mode, written as positions, masses and energies.

    Parameters
    ----------
    name:
        A short identifier (used in messages and cache keys).
    dims:
        2 for planar models (points are ``(x, z)``), 3 for spatial ones (``(x, y, z)``).
    time_unit:
        Unit of time (``"s"``; a scaled model may say e.g. ``"√(l/g)"``). Velocities are in
        ``<coordinate unit>/<time unit>``.
    """

    def __init__(self, name: str, dims: int = 2, time_unit: str = "s") -> None:
        if dims not in (2, 3):
            raise ModelError(f"model {name!r}: dims must be 2 or 3, got {dims!r}")
        super().__init__(name, time_unit)
        self.dims = dims
        self.points: dict[str, sp.Matrix] = {}
        self.masses: dict[str, sp.Expr] = {}
        self.links: list[tuple[str, str]] = []
        self._k_terms: list[sp.Expr] = []
        self._k_added: list[sp.Expr] = []  # the add_kinetic terms among them (not rotational inertia)
        #: each body_inertia's body angular velocity ω (body axes, in q and q̇), inertia and its
        #: term ½ ωᵀ I ω of _k_terms: the derivation takes these by their Jacobians (Kane's form)
        self._spins: list[tuple[sp.Matrix, sp.Matrix, sp.Expr]] = []
        self._v_terms: list[sp.Expr] = []
        self._k_override: sp.Expr | None = None
        self._v_override: sp.Expr | None = None
        self._l_override: sp.Expr | None = None
        self._forces: list[sp.Matrix] = []
        self._force_vectors: list[tuple[str, sp.Matrix]] = []
        self._g: sp.Expr = sp.Integer(0)
        self._g_dir: sp.Matrix = self._down()
        self.tree: RigidTree | ConstrainedTree | None = None  # bodies and joints, if declared (:meth:`rigid_tree`)
        #: holonomic constraints φ(q) = 0 of this mode by name (:meth:`holonomic`), and the
        #: Baumgarte gains (α, β) of each set (1/time units; (0, 0): none)
        self.holonomic_constraints: dict[str, list[sp.Expr]] = {}
        self.baumgarte: dict[str, tuple[float, float]] = {}
        #: coordinates held constant in this mode (:meth:`hold`), in declaration order
        self.held: list[sp.Symbol] = []

    def dt(self, expr: Any) -> Any:
        """Total time derivative of an expression (or vector) of q and t, by the chain rule
        (the velocity of a point on a rigid-body tree comes from the tree, undifferentiated)."""
        if isinstance(expr, sp.MatrixBase):
            if self.tree is not None:
                for name, pos in self.points.items():
                    if pos is expr and name in self.tree.point_velocities:
                        return self.tree.point_velocities[name]
            return expr.applyfunc(self.dt)
        if not isinstance(expr, sp.Basic):  # text or a number (this runs often: sympy values pass as they are)
            expr = expr_of(expr, self.symbol_table(), what=f"model {self.name!r}: dt")
        out = self.diff(expr, t)
        for qi, vi in zip(self.q, self.qd):
            d = self.diff(expr, qi)
            if d != 0:
                out += d * vi
        return out

    def diff(self, expr: Any, symbol: sp.Symbol) -> sp.Expr:
        """``∂expr/∂symbol`` (a tree model's shared subexpressions visited once: ``dag_diff``)."""
        return sp.diff(expr, symbol) if self.tree is None else dag_diff(expr, symbol, self._dag_memo(symbol))

    def jacobian(self, expr: Any) -> sp.Matrix:
        """``∂expr/∂q`` of a vector expression (e.g. a point's position), one column per coordinate."""
        v = sp.Matrix(expr)
        return v.jacobian(self.q) if self.tree is None else sp.Matrix(
            v.rows, len(self.q), lambda i, j: dag_diff(v[i], self.q[j], self._dag_memo(self.q[j])))

    def _dag_memo(self, symbol: sp.Symbol) -> dict:
        # one memo per symbol for the model's life: the points of a tree share their parents'
        # kinematics, so each shared part is differentiated once for all of them (and the
        # derivatives share as the positions do)
        memos = self.__dict__.setdefault("_dag_memos", {})
        return memos.setdefault(symbol, {})

    def point_jacobian(self, name: str) -> sp.Matrix:
        """``∂p/∂q`` of a named point (dims × n): its velocity is ``J q̇`` (for control laws)."""
        if name not in self.points:
            raise ModelError(f"model {self.name!r}: no point named {name!r}")
        return self.jacobian(self.points[name])

    def point_velocity(self, name: str) -> sp.Matrix:
        """Velocity (m/s, world axes) of a named point, an expression of q and q̇."""
        if name not in self.points:
            raise ModelError(f"model {self.name!r}: no point named {name!r}")
        return self.dt(self.points[name])

    # ------------------------------------------------------------------ geometry
    @declaration
    def point(self, name: str, position: Any, mass: Any = None, link: str | None = None) -> sp.Matrix:
        """Name a point at ``position`` (2 or 3 components); optionally put a point mass there and
        draw a rigid link to an earlier point (``link``).

        Returns the position as a column vector so that later points can be built from it.
        """
        pos = _matrix(self, position, f"position of point {name!r}")
        if pos.shape != (self.dims, 1):
            raise ModelError(
                f"model {self.name!r}: point {name!r} has {len(pos)} components, "
                f"expected {self.dims} for a {self.dims}D model"
            )
        if name in self.points:
            raise ModelError(f"model {self.name!r}: point {name!r} defined twice")
        self._check_symbols(pos, f"position of point {name!r}")
        self.points[name] = pos
        if mass is not None:
            self.mass(name, mass)
        if link is not None:
            self.link(link, name)
        return pos

    @declaration
    def mass(self, point: str, m: Any) -> None:
        """Put a point mass ``m`` (kg) at the named point."""
        if point not in self.points:
            raise ModelError(f"model {self.name!r}: mass placed at unknown point {point!r}")
        m = _expr(self, m, f"mass at {point!r}")
        self._check_symbols(m, f"mass at {point!r}")
        self._check_mass(m, f"mass at point {point!r}", zero=False)
        self.masses[point] = self.masses.get(point, sp.Integer(0)) + m

    @declaration
    def link(self, a: str, b: str) -> None:
        """Declare a rigid link between two named points (used for drawing)."""
        for p in (a, b):
            if p not in self.points:
                raise ModelError(f"model {self.name!r}: link to unknown point {p!r}")
        self.links.append((a, b))

    @declaration
    def rigid_tree(self) -> RigidTree:
        """The model's kinematic tree of rigid bodies and joints (created on first use; 3D only):
        ``model.rigid_tree().body(...)`` — see :mod:`amble.modelling.tree`."""
        if self.tree is None:
            self.tree = RigidTree(self)
        return self.tree

    def limit_guards(self) -> list[LimitGuard]:
        """The joint limits of the model's rigid-body tree as guards: for each coordinate with a
        finite bound, ``q − lower`` and ``upper − q`` (rad or m), positive inside the range and
        firing where they cross zero from positive; none for a mimic or continuous joint or a
        model without a tree — see :mod:`amble.modelling.limits`."""
        return limit_guards(self)

    @classmethod
    def from_urdf(cls, path: Any, base: str | None = None, contact_points: Any = None,
                  name: str | None = None, allow_massless: bool = False, gravity: float = 9.81,
                  base_joint: Any = None, base_coordinate: str = "base", parameters: Any = False,
                  pivot: str | None = None) -> Model:
        """The robot of a URDF file with the link ``base`` fixed to the world (or attached by
        ``base_joint``), ``contact_points``, and with ``parameters`` (``True`` or kinds among
        ``mass``, ``com``, ``inertia``, ``length``) its numbers as named run-time parameters, and
        the base joint centred at the contact point ``pivot`` — see :mod:`amble.modelling.urdf`."""
        from .urdf import build_model

        return build_model(cls, path, base=base, contact_points=contact_points, name=name,
                           allow_massless=allow_massless, gravity=gravity, base_joint=base_joint,
                           base_coordinate=base_coordinate, parameters=parameters, pivot=pivot)

    @classmethod
    def from_mjcf(cls, path: Any, name: str | None = None, fixed_base: bool = False,
                  contact_points: Any = None) -> Model:
        """The robot of a MuJoCo MJCF file, read by MuJoCo's own compiler: bodies, joints (hinge,
        slide, ball, free), inertias, gravity, joint damping, stiffness and armature; free bodies
        welded where the file places them with ``fixed_base`` — see :mod:`amble.modelling.mjcf`."""
        from .mjcf import build_model

        return build_model(cls, path, name=name, fixed_base=fixed_base, contact_points=contact_points)

    @declaration
    def inertia(self, angle: Any, moment: Any) -> None:
        """Rotational inertia of a planar body turning with ``angle``: adds ``I·(dangle/dt)²/2``."""
        moment = _expr(self, moment, "moment of inertia")
        self._k_terms.append(sp.Rational(1, 2) * moment * self.dt(_expr(self, angle, "inertia angle")) ** 2)

    @declaration
    def body_inertia(self, rotation: Any, inertia: Any) -> None:
        """Rotational inertia of a 3D body with orientation ``rotation`` (3×3, body → world).

        Adds ``½ ωᵀ I ω`` with the body angular velocity ``ω`` from ``[ω]ₓ = Rᵀ Ṙ`` and the
        inertia tensor ``I`` (kg·m², body axes, about the body's centre of mass — whose mass is
        declared with :meth:`point`).
        """
        Rm = _matrix(self, rotation, "body rotation")
        Im = _matrix(self, inertia, "body inertia")
        if Rm.shape != (3, 3) or Im.shape != (3, 3):
            raise ModelError(f"model {self.name!r}: body_inertia needs a 3×3 rotation and a 3×3 inertia")
        W = Rm.T * self.dt(Rm)
        w = sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])
        self._k_terms.append(sp.Rational(1, 2) * (w.T * Im * w)[0, 0])
        self._spins.append((w, Im, self._k_terms[-1]))

    # ------------------------------------------------------------------ energies
    @declaration
    def gravity(self, g: Any, direction: Any = None) -> None:
        """Uniform gravity of magnitude ``g`` (m/s²) along ``direction`` (default: down, -z)."""
        self._g = _expr(self, g, "gravity")
        if direction is not None:
            d = _matrix(self, direction, "gravity direction")
            if d.shape != (self.dims, 1):
                raise ModelError(f"model {self.name!r}: gravity direction needs {self.dims} components")
            self._g_dir = d
        self._check_symbols(self._g, "gravity")

    @declaration
    def add_kinetic(self, expr: Any) -> None:
        """Add a kinetic-energy term (J) in q and the velocity symbols."""
        self._k_terms.append(_expr(self, expr, "kinetic energy term"))
        self._k_added.append(self._k_terms[-1])

    @declaration
    def add_potential(self, expr: Any) -> None:
        """Add a potential-energy term (J) in q, e.g. a spring ``k*(q1 - q2)**2/2``."""
        self._v_terms.append(_expr(self, expr, "potential energy term"))

    @declaration
    def hold(self, *coordinates: Any) -> None:
        """Hold coordinates constant in this mode: their equations of motion become ``q̈ᵢ = 0``.

        A held coordinate is a value that a domain carries from the state it was entered in, such
        as where a foot landed: the reset into the mode sets it, with its velocity zero, and it
        stays there (its velocity keeps the value the reset gives it). The other coordinates'
        equations see it as a constant: no mass, force or input acts along it, and the mass
        matrix has a unit row and column there. Energies may depend on it (a spring to the held
        foot); with its velocity zero it carries no kinetic energy, so a conservative mode stays
        conservative. ``coordinates``: symbols of this model's coordinates or their names.
        """
        for c in coordinates:
            name = str(c)
            match = [qi for qi in self.q if str(qi) == name]
            if not match:
                raise ModelError(f"model {self.name!r}: cannot hold {name!r}: it is not a coordinate")
            if match[0] not in self.held:
                self.held.append(match[0])

    @property
    def K(self) -> sp.Expr:
        """Kinetic energy: Σ ½ mᵢ |ṗᵢ|² plus added terms, unless given outright."""
        if self._k_override is not None:
            return self._k_override
        k = sp.Integer(0) if self.tree is None else self.tree.kinetic()
        for name, m in self.masses.items():
            if self.tree is not None and name in self.tree.com_points:
                continue
            v = self.dt(self.points[name])
            k += sp.Rational(1, 2) * m * (v.T * v)[0, 0]
        return k + sum(self._k_terms, sp.Integer(0))

    @K.setter
    def K(self, expr: Any) -> None:
        self._k_override = _expr(self, expr, "K")

    @property
    def V(self) -> sp.Expr:
        """Potential energy: Σ −mᵢ g·pᵢ plus added terms, unless given outright."""
        if self._v_override is not None:
            return self._v_override
        v = sp.Integer(0)
        gvec = self.gravity_vector
        if self.tree is not None:
            v = self.tree.potential(gvec)
        for name, m in self.masses.items():
            if self.tree is not None and name in self.tree.com_points:
                continue
            v += -m * (gvec.T * self.points[name])[0, 0]
        return v + sum(self._v_terms, sp.Integer(0))

    @V.setter
    def V(self, expr: Any) -> None:
        self._v_override = _expr(self, expr, "V")

    @property
    def L(self) -> sp.Expr:
        """The Lagrangian ``K − V`` (or the one given outright)."""
        if self._l_override is not None:
            return self._l_override
        return self.K - self.V

    @L.setter
    def L(self, expr: Any) -> None:
        self._l_override = _expr(self, expr, "L")

    @property
    def gravity_vector(self) -> sp.Matrix:
        """Gravity acceleration vector (m/s²) in world coordinates."""
        return self._g * self._g_dir

    # ------------------------------------------------------------------ forces
    @declaration
    def force(self, generalized: Any) -> None:
        """Add a generalized force vector Γ (one entry per coordinate; may depend on q, q̇, t)."""
        v = _matrix(self, generalized, "generalized force")
        if v.shape != (len(self.q), 1):
            raise ModelError(
                f"model {self.name!r}: generalized force needs {len(self.q)} entries, got {len(v)}"
            )
        self._forces.append(v)

    @declaration
    def torque(self, tau: Any, angle: Any) -> None:
        """A torque ``tau`` (N·m) doing work on ``angle`` (an expression of q, e.g. a joint angle).

        By virtual work its generalized force is ``tau · ∂angle/∂q``: a hip torque between two
        absolute leg angles is ``model.torque(tau, swing - stance)``.
        """
        angle = _expr(self, angle, "torque angle")
        tau = _expr(self, tau, "torque")
        self._forces.append(sp.Matrix([tau * sp.diff(angle, qi) for qi in self.q]))

    @declaration
    def point_force(self, point: str, force: Any) -> None:
        """A force (N, world frame) applied at a named point; Γ = Jᵀ F."""
        if point not in self.points:
            raise ModelError(f"model {self.name!r}: force on unknown point {point!r}")
        f = _matrix(self, force, f"force on point {point!r}")
        jac = self.jacobian(self.points[point])
        self._forces.append(jac.T * f)

    @property
    def generalized_force(self) -> sp.Matrix:
        """Γ(q, q̇, t): the sum of all declared forces (zeros if none)."""
        out = sp.zeros(len(self.q), 1)
        for f in self._forces:
            out += f
        return out

    @declaration
    def holonomic(self, name: str, constraints: Any, baumgarte: tuple[float, float] | None = None) -> None:
        """Holonomic constraints ``φ(q) = 0`` (``m`` equations, expressions or text of the
        coordinates and parameters) that hold throughout this mode: a closed kinematic loop (a
        four-bar leg) or feet held on the ground (double support). The coordinates stay
        independent symbols; the mode's dynamics become the index-1 system

        ``M q̈ = Γ − h + Jᵀλ``,  ``J q̈ = γ``,  ``J = ∂φ/∂q``,  ``γ = −J̇ q̇``,

        solved for ``q̈`` and the constraint forces ``λ`` (one per equation, in the units of
        ``Γ`` per unit of ``φ``: a force for a length, a torque for an angle). ``Jᵀλ`` is the
        generalized force the constraint exerts, so for ``φ`` = a foot's height ``λ`` is the
        ground's normal force, positive while it pushes (``Kernels.constraint_forces``).

        Start states must satisfy ``φ(q) = 0`` and ``J q̇ = 0``; the integration keeps them to
        its tolerance. ``baumgarte=(α, β)`` (1/time unit, default none) adds the feedback
        ``−2α J q̇ − β² φ`` to ``γ``, which pulls a drifting state back at the cost of the exact
        flow (energy is then not conserved to the integrator's tolerance).
        """
        if not isinstance(name, str) or not name:
            raise ModelError(f"model {self.name!r}: a holonomic constraint needs a name, got {name!r}")
        if name in self.holonomic_constraints:
            raise ModelError(f"model {self.name!r}: holonomic constraint {name!r} is already declared")
        rows = list(constraints) if isinstance(constraints, (list, tuple, sp.MatrixBase)) else [constraints]
        if not rows:
            raise ModelError(f"model {self.name!r}: holonomic constraint {name!r} has no equations")
        exprs = [_expr(self, e, f"holonomic constraint {name!r}") for e in rows]
        for e in exprs:
            self._check_symbols(e, f"holonomic constraint {name!r}")
            # rheonomic constraints (φ of t) would need ∂²φ/∂t² in γ: not supported
            syms = free_symbols(e)  # a tree's positions are shared graphs: each part visited once
            if t in syms or not (syms & set(self.q)):
                raise ModelError(f"model {self.name!r}: holonomic constraint {name!r}: {e} must depend on the "
                                 "coordinates and not on time")
        gains = (0.0, 0.0) if baumgarte is None else tuple(float(g) for g in baumgarte)
        if len(gains) != 2 or not all(math.isfinite(g) and g >= 0 for g in gains):
            raise ModelError(f"model {self.name!r}: baumgarte gains of {name!r} must be two finite numbers ≥ 0, "
                             f"got {baumgarte!r}")
        self.holonomic_constraints[name] = exprs
        self.baumgarte[name] = gains  # type: ignore[assignment]

    @property
    def constraint_names(self) -> list[str]:
        """One name per constraint equation, in the order of ``λ``: ``<name>`` for a single
        equation, ``<name>[i]`` for the i-th of several."""
        out = []
        for name, exprs in self.holonomic_constraints.items():
            out += [name] if len(exprs) == 1 else [f"{name}[{i}]" for i in range(len(exprs))]
        return out

    # ------------------------------------------------------------------ derived models
    def constrained(self, name: str, substitutions: dict[Any, Any]) -> Model:
        """A copy of this model with some coordinates tied to the others (e.g. a locked knee:
        ``{shank: thigh}``), for a mode with fewer coordinates.

        Positions, energies and masses are substituted; generalized forces are mapped by virtual
        work, ``Γ_new = (∂q/∂q_new)ᵀ Γ``, so a torque declared once acts correctly in both modes.
        A rigid-body tree stays one (:mod:`amble.modelling.constrained_tree`): its equations are
        the source tree's, projected.
        """
        table, what = self.symbol_table(), f"model {self.name!r}: constrained {name!r}"
        subs = {expr_of(k, table, what=what): expr_of(v, table, what=what) for k, v in substitutions.items()}
        for k in subs:
            if k not in self.q:
                raise ModelError(f"model {self.name!r}: {k} is not a coordinate and cannot be eliminated")
        out = Model(name, self.dims, self.time_unit)
        keep = [i for i, qi in enumerate(self.q) if qi not in subs]
        out.q = [self.q[i] for i in keep]
        out.qd = [self.qd[i] for i in keep]
        out.params, out.units, out.descriptions = dict(self.params), dict(self.units), dict(self.descriptions)
        out.domains = dict(self.domains)
        for qi, v in subs.items():
            bad = v.free_symbols - set(out.q) - set(self.params) - {t}
            if bad:
                raise ModelError(f"model {self.name!r}: {qi} = {v} uses {', '.join(map(str, bad))}")
        vsubs = dict(subs)
        vsubs.update({self.dot(qi): out.dt(v) for qi, v in subs.items()})
        if self.tree is not None:  # shared expression graphs: each shared part substituted once
            out.tree = ConstrainedTree(self.tree, out, vsubs)
            put = out.tree.replace
        else:
            put = lambda e: e.subs(vsubs)  # noqa: E731
        out.points = {n: put(p) for n, p in self.points.items()}
        out.masses = dict(self.masses)
        out.links = list(self.links)
        out._k_terms = [put(e) for e in self._k_terms]
        out._k_added = [put(e) for e in self._k_added]
        out._spins = [(w.applyfunc(put), Im, put(e)) for w, Im, e in self._spins]
        out._v_terms = [put(e) for e in self._v_terms]
        for attr in ("_k_override", "_v_override", "_l_override"):
            e = getattr(self, attr)
            setattr(out, attr, None if e is None else put(e))
        full = sp.Matrix([subs.get(qi, qi) for qi in self.q])
        jac = full.jacobian(out.q)
        out._forces = [jac.T * put(f) for f in self._forces]
        out._g, out._g_dir = self._g, self._g_dir
        if any(e.free_symbols & set(self.derived_placeholders) for e in self._laws.values()):
            raise ModelError(f"model {self.name!r}: a control law written with mass_and_bias() cannot be carried "
                             "into a constrained model; declare it on that model")
        self._copy_actuators(out, subs, vsubs)
        out.holonomic_constraints = {k: [put(e) for e in v] for k, v in self.holonomic_constraints.items()}
        out.baumgarte = dict(self.baumgarte)
        out.held = [qi for qi in self.held if qi in out.q]
        return out

    # ------------------------------------------------------------------ helpers
    def _down(self) -> sp.Matrix:
        return sp.Matrix([0, -1]) if self.dims == 2 else sp.Matrix([0, 0, -1])

    def _check_symbols(self, expr: Any, what: str) -> None:
        allowed = set(self.q) | set(self.params) | {t}
        free = free_symbols(expr)
        bad = sorted(str(s) for s in free - allowed)
        if bad:
            raise ModelError(
                f"model {self.name!r}: {what} uses {', '.join(bad)}, which "
                f"{'is' if len(bad) == 1 else 'are'} neither a coordinate nor a parameter"
            )

    def _check_mass(self, m: sp.Expr, what: str, zero: bool) -> None:
        """A mass (kg) as declared: a number must be finite and positive (``zero``: or zero, a
        massless frame of a rigid-body tree), else :class:`ModelError` naming ``what``.

        A mass that is one parameter, or one parameter times a positive number, makes that
        parameter's domain positive (unless one was declared, or its default is not: then
        :meth:`validate` names the mass): a negative value given at run time would otherwise
        reach the integrator as a mass matrix that is not positive definite, and end the run as
        ``singular_mass`` instead of being refused as the input it is."""
        if m.is_number:
            v = float(m)
            if not (math.isfinite(v) and (v > 0 or (zero and v == 0))):
                need = "non-negative" if zero else "positive"
                raise ModelError(f"model {self.name!r}: {what} must be a finite {need} number, got {v:g}")
            return
        coeff, rest = m.as_coeff_Mul()
        if rest in self.params and coeff > 0 and str(rest) not in self.domains \
                and self.params[rest] in POSITIVE:
            self.domains[str(rest)] = POSITIVE

    def validate(self) -> None:
        """Check the model is complete and physically sensible at the default parameters."""
        if not self.q:
            raise ModelError(f"model {self.name!r} has no coordinates")
        defaults = {s: v for s, v in self.params.items()}
        for name, m in self.masses.items():
            try:
                val = float(m.subs(defaults))
            except TypeError:
                raise ModelError(f"model {self.name!r}: mass at {name!r} is not a constant") from None
            if not val > 0:
                raise ModelError(
                    f"model {self.name!r}: mass at point {name!r} must be positive, got {val:g}"
                )
        allowed_kv = set(self.q) | set(self.qd) | set(self.params) | {t}
        for label, expr in (("K", self.K), ("V", self.V), ("L", self.L)):
            bad = sorted(str(s) for s in free_symbols(expr) - allowed_kv)
            if bad:
                raise ModelError(
                    f"model {self.name!r}: {label} uses {', '.join(bad)}, which is neither a "
                    "coordinate, a velocity nor a parameter"
                )
        if any(s in free_symbols(self.V) for s in self.qd):
            raise ModelError(f"model {self.name!r}: the potential energy V depends on velocities")
        bad = sorted(str(s) for s in free_symbols(self.generalized_force) - allowed_kv)
        if bad:
            raise ModelError(f"model {self.name!r}: forces use unknown symbols {', '.join(bad)}")

    def __repr__(self) -> str:
        return (
            f"Model({self.name!r}, dims={self.dims}, q=[{', '.join(map(str, self.q))}], "
            f"params=[{', '.join(self.parameter_names)}])"
        )

