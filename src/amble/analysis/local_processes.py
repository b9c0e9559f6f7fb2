"""Sweep tasks on local worker processes, without Dask: the default where a sweep runs.

A local Dask cluster costs 1.3–1.5 s per command to start and a scheduler round trip per task;
a sweep of a few seconds then scaled ≤ 1.3× on two cores. Here the workers are forked from the
process that holds the compiled system, so they start in milliseconds with the system, its
kernels and their loaded library already in memory: nothing is pickled but each task's own
arguments and rows. Where ``fork`` does not exist (Windows, macOS' default), the tasks run in this
process instead.

Rows are appended to the result file by this process as each task lands; on a task's error or
Ctrl-C the workers are stopped at once and the rows already appended stay (the file is resumed
by the next call).
"""

from __future__ import annotations

import multiprocessing
import warnings
from collections.abc import Callable
from typing import Any

#: The task function and the system shared by every task of the running sweep (its first
#: argument, which Dask would scatter), set before the workers are forked: they inherit both, so
#: neither is pickled (a closure serves as well as a module's function). Cleared after the sweep.
_SHARED: tuple[Callable, Any] | None = None


def _call_shared(args: tuple) -> Any:
    assert _SHARED is not None
    fn, system = _SHARED
    return fn(system, *args)


def fork_available() -> bool:
    """Whether worker processes can be forked here (POSIX ``fork`` start method)."""
    return "fork" in multiprocessing.get_all_start_methods()


class LocalProcesses:
    """``workers`` processes forked for one sweep at a time (see the module's docstring)."""

    def __init__(self, workers: int) -> None:
        self.workers = workers

    def close(self) -> None:
        pass

    def run(self, fn: Callable, tasks: list[tuple], store: Any, bar: Any,
            ignore_sigint: Callable[[], Any]) -> None:
        """``fn(*task)`` for every task on the workers; each result's rows appended to ``store``
        and counted on ``bar`` as they land. Every task's first argument is the same system.
        ``ignore_sigint``: a context in which processes started ignore SIGINT (Ctrl-C reaches the
        whole process group; only this process should answer it). A worker that dies (a crash in
        compiled code) fails the sweep with an error instead of leaving it waiting."""
        global _SHARED
        from concurrent.futures import ProcessPoolExecutor, as_completed

        _SHARED = (fn, tasks[0][0])  # kept until the end: a pool would fork any replacement worker too
        pool = ProcessPoolExecutor(min(self.workers, len(tasks)), mp_context=multiprocessing.get_context("fork"))
        try:
            with ignore_sigint(), warnings.catch_warnings():
                # the first submit forks every worker. Python ≥ 3.12 warns on fork in a process
                # with threads (a progress bar's monitor, a thread pool): a child runs only the
                # task function, which takes no lock those threads could hold
                warnings.filterwarnings("ignore", message=".*fork.*", category=DeprecationWarning)
                futures = [pool.submit(_call_shared, t[1:]) for t in tasks]
            for fut in as_completed(futures):
                rows = fut.result()
                store.append(rows)
                bar.update(len(rows))
        except BaseException:
            _stop(pool)  # a task failed or Ctrl-C: the rows appended so far are kept
            raise
        else:
            pool.shutdown()
        finally:
            _SHARED = None


def _stop(pool: Any) -> None:
    """Stop ``pool``'s workers now, running tasks included (they ignore SIGINT)."""
    stop = getattr(pool, "terminate_workers", None)  # Python ≥ 3.14
    if stop is not None:
        stop()
        return
    # before 3.14 the executor has no public way to stop a running task; its process table is
    # the one handle on the workers
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


__all__ = ["LocalProcesses", "fork_available"]
