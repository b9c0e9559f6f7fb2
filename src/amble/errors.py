"""Typed exceptions raised by amble.

Every error a user can cause derives from :class:`AmbleError`, so scripts can catch one type;
the command-line tool turns these into a one-line message and exit code 2.
"""

from __future__ import annotations


class AmbleError(Exception):
    """Base class of all errors amble raises on purpose."""


class ModelError(AmbleError, ValueError):
    """The model is ill-formed: unknown symbols, bad masses, inconsistent resets, ..."""


class ParameterError(AmbleError, ValueError):
    """A parameter name is unknown or its value is not acceptable."""


class StateError(AmbleError, ValueError):
    """A state vector has the wrong length or non-finite entries."""


class CompileError(AmbleError, RuntimeError):
    """Generated code could not be compiled (no C compiler, or the compiler failed)."""


class SimulationError(AmbleError, RuntimeError):
    """A simulation could not be carried out (as opposed to ending with a status such as ``fell``)."""


class ConvergenceError(AmbleError, RuntimeError):
    """An iterative method (e.g. the fixed-point search) did not converge."""


class OutputError(AmbleError, OSError):
    """An output path or result file cannot be used: wrong suffix, missing or unwritable directory,
    unwritable file, or a result file that holds another sweep."""


class SchedulerError(AmbleError, ConnectionError):
    """The Dask scheduler or its workers cannot be reached or used."""


class SolverError(AmbleError, RuntimeError):
    """A numerical optimisation did not succeed (infeasible, restoration failed, iteration limit);
    the message names the reason and the most violated constraint. ``gait``: for a gait
    optimisation whose last iterate satisfies every constraint (a periodic gait, not certified
    optimal), that gait; else None."""

    gait: object = None


class ExpressionError(ModelError, ParameterError):
    """Text that is not an expression amble reads (an unknown name, a construct outside the
    whitelist of :mod:`amble.modelling.text`, a syntax error). It is a :class:`ModelError` when the
    text came with a model and a :class:`ParameterError` when it came as an option, so code that
    catches either keeps working."""
