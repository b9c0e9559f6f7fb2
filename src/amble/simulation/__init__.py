"""Simulation: run a hybrid system through its compiled kernels (:mod:`.engine`, the one place
that talks to the compiled loop), the user-facing :func:`~.simulate.simulate`, and its result
(:mod:`.trajectory`)."""
