"""The result of a simulation: samples, events, outcome — and views of it (energy, points, tables).

Rows are samples in time order: the initial state, states on a fixed output grid (or at every
integration step), and at each event the pre-event and post-event states at the same time.
States of different modes have different lengths; rows are padded with NaN to the longest.
Point positions are in the stance-foot frame of each step; :meth:`Trajectory.world_points`
accumulates the footholds so a walk can be drawn on its slope.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import AmbleError
from . import inputs as _inputs

if TYPE_CHECKING:
    from ..backend.library import Kernels


@dataclass(slots=True)
class Event:
    """One transition: when, which, and the state just before and just after it (views of
    the run's own event rows)."""

    t: float
    name: str
    source: str
    target: str
    x_pre: np.ndarray
    x_post: np.ndarray


class Events(Sequence):
    """The events of a run, in time order: a read-only sequence of :class:`Event`, made from the
    run's event rows when first read (a walk of hundreds of footfalls whose events nobody reads
    pays nothing for them). ``kinds[tr]``: transition ``tr``'s name, source and target mode and
    their state lengths; ``nxm``: the padded row length."""

    __slots__ = ("_t", "_tr", "_pre", "_post", "_kinds", "_nxm", "_items")

    def __init__(self, t: np.ndarray, tr: np.ndarray, pre: np.ndarray, post: np.ndarray,
                 kinds: Sequence[tuple[str, str, str, int, int]], nxm: int) -> None:
        self._t, self._tr, self._pre, self._post, self._kinds, self._nxm = t, tr, pre, post, kinds, nxm
        self._items: list[Event] | None = None

    def _list(self) -> list[Event]:
        if self._items is None:
            nxm, kinds, items = self._nxm, self._kinds, []
            # an event's states are views of the run's own event rows (made in C, no copies)
            for t, tr, pre, post in zip(self._t.tolist(), self._tr.tolist(), list(self._pre), list(self._post)):
                name, source, target, ns, nt = kinds[tr]
                items.append(Event(t, name, source, target, pre if ns == nxm else pre[:ns],
                                   post if nt == nxm else post[:nt]))
            self._items = items
        return self._items

    def __len__(self) -> int:
        return len(self._t) if self._items is None else len(self._items)

    def last_post(self, transitions: frozenset[int]) -> np.ndarray | None:
        """A copy of the post-event state of the last event of one of these ``transitions`` (by
        index), or ``None``: read from the event rows, without making the Event objects (the
        command line's summary of a long walk read them all for its last footfall)."""
        tr, kinds = self._tr, self._kinds
        for i in range(len(tr) - 1, -1, -1):  # a walk usually ends at a footfall: one row read
            j = int(tr[i])
            if j in transitions:
                nt = kinds[j][4]
                return self._post[i, :nt].copy()
        return None

    def __getitem__(self, i: Any) -> Any:
        return self._list()[i]

    def __iter__(self) -> Iterator[Event]:
        return iter(self._list())

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and list(self) == list(other)

    def __repr__(self) -> str:
        return repr(self._list())

    def __reduce__(self) -> tuple:  # pickles (Dask, multiprocessing) as a plain list
        return (list, (self._list(),))


@dataclass
class Trajectory:
    """A simulated run. ``status`` is ``completed`` (all steps done), ``end_time``, ``fell``,
    ``zeno``, ``integrator_failure``, ``singular_mass``, ``reset_failed`` or ``max_events``."""

    t: np.ndarray
    mode: np.ndarray
    x: np.ndarray
    events: Sequence[Event]
    status: str
    message: str
    steps: int
    params: np.ndarray
    kernels: Kernels
    final_state: np.ndarray
    final_mode: str
    system: Any = field(default=None, repr=False)
    _world: dict[str, np.ndarray] | None = field(default=None, repr=False)

    # ------------------------------------------------------------------ basic views
    @property
    def mode_names(self) -> list[str]:
        return list(self.kernels.meta["modes"])

    @property
    def parameters(self) -> dict[str, float]:
        return dict(zip(self.kernels.meta["params"], self.params.tolist()))

    def state_names(self, mode: str | None = None) -> list[str]:
        return list(self.kernels.meta["state_names"][mode or self.mode_names[0]])

    @property
    def step_events(self) -> list[Event]:
        """Events that are footfalls (transitions declared with ``step=True``)."""
        steps = {tr["name"] for tr in self.kernels.meta["transitions"] if tr["step"]}
        return [e for e in self.events if e.name in steps]

    @property
    def final_post_impact_state(self) -> np.ndarray | None:
        """State just after the last footfall (the Poincaré section of a walker), if any."""
        if isinstance(self.events, Events):
            steps = frozenset(i for i, tr in enumerate(self.kernels.meta["transitions"]) if tr["step"])
            return self.events.last_post(steps)
        ev = self.step_events
        return ev[-1].x_post.copy() if ev else None

    def column(self, name: str) -> np.ndarray:
        """Samples of one state variable by name (NaN in rows of modes that lack it)."""
        out = np.full(len(self.t), np.nan)
        for mi, mname in enumerate(self.mode_names):
            names = self.state_names(mname)
            if name in names:
                rows = self.mode == mi
                out[rows] = self.x[rows, names.index(name)]
        if np.all(np.isnan(out)) and not any(name in self.state_names(m) for m in self.mode_names):
            raise AmbleError(f"no state variable named {name!r}")
        return out

    def energy(self) -> np.ndarray:
        """Kinetic and potential energy per row, shape (N, 2), in J."""
        return self.kernels.energy_rows(self.t, self.mode, self.x, self.params)

    def constraint_forces(self) -> dict[str, np.ndarray]:
        """Constraint equation name → its force ``λ`` per row (``M q̈ + h = Γ + Jᵀλ``, ``J = ∂φ/∂q``:
        N for a length, N·m for an angle; :meth:`amble.Model.holonomic`), NaN in rows of a mode
        that does not hold it; empty if no mode has holonomic constraints."""
        k, out = self.kernels, {}
        for mi in range(k.n_modes):
            names, rows = k.constraint_names(mi), np.nonzero(self.mode == mi)[0]
            if not names or not rows.size:
                continue
            nx = k.meta["nx"][mi]
            lam = k.constraint_forces_many(mi, self.t[rows], self.x[rows, :nx], self.params)
            for j, name in enumerate(names):
                out.setdefault(name, np.full(len(self.t), np.nan))[rows] = lam[:, j]
        return out

    def inputs(self) -> dict[str, np.ndarray]:
        """Input name → value per sample (N·m or N) from the closed-loop law; empty without
        actuators (see :mod:`amble.simulation.inputs`)."""
        return _inputs.inputs(self)

    def joint_power(self) -> dict[str, np.ndarray]:
        """Input name → mechanical power ``u_j ω_j`` per sample (W)."""
        return _inputs.joint_power(self)

    def work_per_step(self, absolute: bool = False) -> dict[str, np.ndarray]:
        """Input name → work per step (J; ``absolute``: of ``|P|``)."""
        return _inputs.work_per_step(self, absolute)

    def cost_of_transport(self) -> float:
        """Mechanical cost of transport ``Σ∫|P| dt / (m g d)`` of the run."""
        return _inputs.cost_of_transport(self)

    def points(self) -> dict[str, np.ndarray]:
        """Positions of named points per row in the current stance frame, (N, 3) each."""
        pos, _ = self.kernels.kinematics_rows(self.t, self.mode, self.x, self.params)
        return {n: pos[:, i, :] for i, n in enumerate(self.kernels.meta["points"])}

    def world_points(self) -> dict[str, np.ndarray]:
        """Point positions in the world frame: each transition's frame change
        (:meth:`HybridSystem.frame_change <amble.modelling.hybrid.HybridSystem.frame_change>`)
        accumulates — a footfall moves the origin to the new foothold (and a walker whose legs
        swap sides reflects the lateral axis)."""
        if self._world is None:
            pos, _ = self.kernels.kinematics_rows(self.t, self.mode, self.x, self.params)
            origins, frames = self.world_frames(pos)
            world = np.einsum("rij,rpj->rpi", frames, pos) + origins[:, None, :]
            self._world = {n: world[:, i, :] for i, n in enumerate(self.kernels.meta["points"])}
        return self._world

    def world_frames(self, pos: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Per row, the origin ``(N, 3)`` (m) and axes ``(N, 3, 3)`` of the row's model frame in
        the world: ``world = axes @ model + origin`` (see :meth:`world_points`); ``pos``: the
        rows' point positions, if already computed."""
        if pos is None:
            pos, _ = self.kernels.kinematics_rows(self.t, self.mode, self.x, self.params)
        return self._frames_per_row(pos)

    def _frames_per_row(self, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        meta = self.kernels.meta
        pidx = {n: i for i, n in enumerate(meta["points"])}
        changes = {tr["name"]: self.system.frame_change(tr["name"]) for tr in meta["transitions"]}
        origin, frame = np.zeros(3), np.eye(3)
        origins, frames = np.zeros((len(self.t), 3)), np.zeros((len(self.t), 3, 3))
        ev_iter = iter(self.events)
        ev = next(ev_iter, None)
        n = len(self.t)

        def moved(at: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
            """The frame after ``ev``: ``at``, the points where it happened (else from its state)."""
            shift, flip = changes[ev.name]
            o = origin
            if shift is not None:
                if at is None:
                    at = self.kernels.kinematics_rows([ev.t], [self.kernels.mode_index(ev.source)],
                                                      ev.x_pre, self.params)[0][0]
                o = origin + frame @ at[pidx[shift]]
            return o, frame @ np.diag(flip)

        for i in range(n):
            # events between rows (a run recorded without samples keeps only its ends): their
            # frame changes still accumulate, from each event's own pre-impact state
            while ev is not None and (ev.t < self.t[i] or self._lone_post_row(i, ev)):
                origin, frame = moved(None)
                ev = next(ev_iter, None)
            origins[i], frames[i] = origin, frame
            # an event writes a pre row then a post row at the same time
            if ev is not None and i + 1 < n and self.t[i] == ev.t and self.t[i + 1] == ev.t:
                origin, frame = moved(pos[i])
                ev = next(ev_iter, None)
        return origins, frames

    def _lone_post_row(self, i: int, ev: Any) -> bool:
        """Whether row ``i`` is ``ev``'s post-impact state without its pre row (the last row of a
        run recorded without samples, which ends just after a footfall)."""
        if self.t[i] != ev.t or (i + 1 < len(self.t) and self.t[i + 1] == ev.t):
            return False
        post = np.asarray(ev.x_post, float)
        return post.size <= self.x.shape[1] and np.array_equal(self.x[i, : post.size], post)

    # ------------------------------------------------------------------ resampling & export
    def resample(self, fps: float) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """World point positions at a fixed frame rate (for animation): (times, points)."""
        if fps <= 0:
            raise AmbleError("frame rate must be positive")
        wp = self.world_points()
        times = np.arange(self.t[0], self.t[-1] + 1e-12, 1.0 / fps)
        idx = np.searchsorted(self.t, times, side="right") - 1
        idx = np.clip(idx, 0, len(self.t) - 1)
        nxt = np.clip(idx + 1, 0, len(self.t) - 1)
        dt = self.t[nxt] - self.t[idx]
        same = (self.mode[nxt] == self.mode[idx]) & (dt > 0)
        w = np.where(same, (times - self.t[idx]) / np.where(dt > 0, dt, 1.0), 0.0)
        out = {}
        for name, arr in wp.items():
            a, b = arr[idx], arr[nxt]
            interp = a + (b - a) * w[:, None]
            out[name] = np.where(np.isfinite(interp), interp, a)
        return times, out

    def unit(self, name: str) -> str:
        """Unit of a column of :meth:`table` (``""`` for ``mode`` and undeclared names)."""
        if name == "t":
            return self.system.time_unit if self.system is not None else "s"
        if name in ("kinetic_energy", "potential_energy"):
            return "J" if self.system is None or self.system.time_unit == "s" else ""
        if name.startswith("power_") and self.system is not None and name[6:] in _inputs.input_names(self.system):
            return "W" if self.system.time_unit == "s" else ""
        return self.system.unit(name) if self.system is not None else ""

    def table(self, extra: Mapping[str, tuple[np.ndarray, str]] | None = None) -> dict[str, np.ndarray]:
        """Columns: ``t``, ``mode``, every state variable of every mode (NaN where absent), the
        energies, then every input ``u`` and its power ``power_<input>`` (W), then the ``extra``
        columns (name → (values per sample, unit); e.g. the ground reaction of
        :func:`amble.analysis.trajectory_physics.physics_columns`)."""
        cols: dict[str, np.ndarray] = {"t": self.t, "mode": np.array([self.mode_names[m] for m in self.mode])}
        for m in self.mode_names:
            for name in self.state_names(m):
                if name not in cols:
                    cols[name] = self.column(name)
        e = self.energy()
        cols["kinetic_energy"], cols["potential_energy"] = e[:, 0], e[:, 1]
        if self.system is not None and _inputs.input_names(self.system):
            u, power = self.inputs(), self.joint_power()
            cols.update(u)
            cols.update({f"power_{k}": v for k, v in power.items()})
        for name, (values, _) in (extra or {}).items():
            if name in cols:
                raise AmbleError(f"extra column {name!r} would replace a column of the trajectory")
            values = np.asarray(values)
            if values.shape != self.t.shape:
                raise AmbleError(f"extra column {name!r} has {values.shape} values for {len(self.t)} samples")
            cols[name] = values
        return cols

    def save(self, path: str | Path, extra: Mapping[str, tuple[np.ndarray, str]] | None = None) -> Path:
        """Write the samples (:meth:`table`, with the ``extra`` columns) to ``.csv``, ``.parquet``
        or ``.npz`` (chosen by suffix).

        A CSV ends with an ``event`` column: ``NAME:pre`` and ``NAME:post`` on the two rows of
        transition ``NAME``. Units travel with the columns: CSV headers read ``name [unit]``,
        Parquet fields carry a ``unit`` metadata entry, an ``.npz`` holds ``units`` (one
        per column, in order)."""
        path = Path(path)
        cols = self.table(extra)
        extra_units = {k: u for k, (_, u) in (extra or {}).items()}
        units = [extra_units[c] if c in extra_units else self.unit(c) for c in cols]
        suffix = path.suffix.lower()
        if suffix == ".npz":
            ev = {
                "event_t": np.array([e.t for e in self.events]),
                "event_name": np.array([e.name for e in self.events]),
            }
            with path.open("wb") as f:  # a file object: np.savez would append ".npz" to "walk.NPZ"
                np.savez(f, **cols, **ev, columns=np.array(list(cols)), units=np.array(units))
        elif suffix == ".csv":
            import csv

            with path.open("w", newline="") as f:
                wr = csv.writer(f)
                wr.writerow([f"{c} [{u}]" if u else c for c, u in zip(cols, units)] + ["event"])
                for row, mark in zip(zip(*cols.values()), self._event_marks()):
                    wr.writerow([v if isinstance(v, str) else repr(float(v)) for v in row] + [mark])
        elif suffix == ".parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            fields = [pa.field(k, pa.array(v).type, metadata={"unit": u} if u else None)
                      for (k, v), u in zip(cols.items(), units)]
            pq.write_table(pa.table({k: pa.array(v) for k, v in cols.items()}, schema=pa.schema(fields)), path)
        else:
            raise AmbleError(f"unknown output format {path.suffix!r}: use .csv, .parquet or .npz")
        return path

    def _event_marks(self) -> list[str]:
        """The CSV ``event`` column: ``NAME:pre`` on the row just before transition ``NAME``,
        ``NAME:post`` on the row just after it (same time), empty elsewhere."""
        marks = [""] * len(self.t)
        i = 0
        for ev in self.events:
            while i < len(self.t) and self.t[i] < ev.t:
                i += 1
            if i >= len(self.t):
                break
            marks[i] = f"{ev.name}:pre"
            if i + 1 < len(self.t) and self.t[i + 1] == ev.t:
                marks[i + 1] = f"{ev.name}:post"
                i += 1
            i += 1
        return marks

    def summary(self) -> dict[str, Any]:
        """JSON-friendly summary of the run (the CLI's ``--json`` output)."""
        post = self.final_post_impact_state
        return {
            "status": self.status,
            "message": self.message,
            "steps": self.steps,
            "events": len(self.events),
            "time": float(self.t[-1]) if len(self.t) else float("nan"),
            "state_names": self.state_names(self.mode_names[0]),
            "final_post_impact_state": None if post is None else post.tolist(),
            "final_state": self.final_state.tolist(),
            "final_mode": self.final_mode,
            "parameters": self.parameters,
        }
