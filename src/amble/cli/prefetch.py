"""Importing Matplotlib while a command computes.

Importing Matplotlib's pyplot takes 1–2 s; a command asked for a plot needs it only at the end.
Started on a thread at once, the import overlaps the command's own work — above all a first
build's wait for the C compiler, when the interpreter is otherwise idle. The command's later
import finds the module (or waits for the thread under the import lock); a failed import here is
ignored: the command's own import then reports it.
"""

from __future__ import annotations

import threading


def _import_plotting() -> None:
    try:
        from ..viz.plot import _plt

        _plt()  # the backend chosen as plotting chooses it, then pyplot
    except Exception:  # noqa: BLE001 - reported by the command's own import
        pass


def prefetch_plotting() -> threading.Thread:
    """Start importing the plotting module on a daemon thread; join it before exiting."""
    t = threading.Thread(target=_import_plotting, name="amble-import-matplotlib", daemon=True)
    t.start()
    return t


__all__ = ["prefetch_plotting"]
