"""A solver running in this process and the terminal: its progress lines go to stderr (stdout may
carry JSON), and Ctrl-C stays an interrupt although the solver catches it."""

from __future__ import annotations

import os
import signal
import sys
from typing import Any


class Interrupts(list):
    """Notes a Ctrl-C (SIGINT) during the solve (the list is non-empty afterwards) and raises it as
    usual. CasADi catches the ``KeyboardInterrupt`` inside IPOPT's iteration and reports a
    ``NonIpopt_Exception_Thrown`` failure, which would read as a result of the numbers."""

    def __enter__(self) -> Interrupts:
        def note(signum: int, frame: Any) -> None:
            self.append(signum)
            raise KeyboardInterrupt

        self.saved = None
        if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
            return self  # a process started to ignore Ctrl-C (a background job) keeps ignoring it
        try:
            self.saved = signal.signal(signal.SIGINT, note)
        except ValueError:  # not the main thread: signals are not delivered here anyway
            pass
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.saved is not None:
            signal.signal(signal.SIGINT, self.saved)


class StdoutToStderr:
    """Solver progress belongs on stderr (stdout may carry JSON). CasADi hands IPOPT's lines to
    Python's ``sys.stdout``, and C code may print to the process's descriptor 1: both go to stderr."""

    def __init__(self, active: bool) -> None:
        self.active = active

    def __enter__(self) -> None:
        if self.active:
            sys.stdout.flush()
            self.saved_py = sys.stdout
            sys.stdout = sys.stderr
            self.saved = os.dup(1)
            os.dup2(2, 1)

    def __exit__(self, *exc: Any) -> None:
        if self.active:
            sys.stdout.flush()
            sys.stdout = self.saved_py
            try:
                import ctypes

                ctypes.CDLL(None).fflush(None)  # C-level buffers go to stderr before fd 1 is restored
            except (OSError, AttributeError):  # pragma: no cover - no C library handle
                pass
            os.dup2(self.saved, 1)
            os.close(self.saved)


__all__ = ["Interrupts", "StdoutToStderr"]
