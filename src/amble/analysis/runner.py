"""Running sweep work: local processes, Dask clients, chunked tasks, and the names of run outcomes.

Work is cut into *chunks* (a run of consecutive parameter values, one row of a 2D map, one row
of a basin grid); each chunk is one task, so a task amortises its overhead over many
return-map evaluations (~20 µs per compass-gait step) instead of one task per point. Chunk
boundaries depend only on the grid and the chunk size (never on the number of workers), so a
result does not depend on how many processes computed it. Only the client process writes the
result file (:class:`~amble.analysis.store.ResultStore`), as each task's rows land.
"""

from __future__ import annotations

import os
import threading
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..errors import ParameterError, SchedulerError, StateError
from .local_processes import LocalProcesses, fork_available
from .store import ResultStore

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


#: ``scheduler`` naming a local Dask cluster (the default is local processes without Dask)
LOCAL_DASK = "dask"


class _Serial:
    """In-process stand-in for a Dask client (``scheduler='synchronous'``): runs tasks on submit."""

    class _Done:
        def __init__(self, value: Any) -> None:
            self.value = value

        def result(self) -> Any:
            return self.value

    def submit(self, fn: Callable, *args: Any, **kw: Any) -> Any:
        return self._Done(fn(*args, **kw))

    def scatter(self, obj: Any, broadcast: bool = True) -> Any:
        return obj

    def close(self) -> None:
        pass


def open_client(scheduler: Any = None, workers: int | None = None) -> tuple[Any, Callable[[], None]]:
    """Where a sweep's tasks run, and its closer.

    ``scheduler``: ``None`` → ``workers`` local processes (default: one per core) forked from
    this one, without Dask (:mod:`.local_processes`; one worker, or no ``fork``: this process);
    ``"synchronous"`` → this process (tests, debugging); ``"dask"`` → a
    :class:`dask.distributed.LocalCluster` of ``workers`` processes with one thread each (the
    compiled integrator holds the GIL); a ``distributed.Client`` → used as is; any other string →
    the address of an existing Dask scheduler.
    """
    if scheduler == "synchronous":
        c = _Serial()
        return c, c.close
    if scheduler is None:
        n = workers_for(workers)
        c = LocalProcesses(n) if n > 1 and fork_available() else _Serial()
        return c, c.close
    if isinstance(scheduler, str) and not scheduler.strip():
        raise SchedulerError("empty scheduler address: give tcp://host:port, 'dask', 'synchronous', "
                             "or omit the option")
    from dask.distributed import Client, LocalCluster

    if isinstance(scheduler, Client):
        return scheduler, lambda: None
    if scheduler != LOCAL_DASK:
        _check_scheduler(str(scheduler))
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as e:
            raise SchedulerError(f"cannot connect to the Dask scheduler at {scheduler!r} ({e})") from None
        return client, client.close
    n = workers_for(workers)
    with _children_ignore_sigint(), warnings.catch_warnings():
        # without a dashboard the scheduler still binds an HTTP server (health, metrics) to the
        # dashboard's default port, and warns when another program holds it; nobody reads that
        # server here, so another port is as good and the warning is not the user's business
        warnings.filterwarnings("ignore", message=r"Port \d+ is already in use", category=UserWarning)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    client.register_plugin(_quiet_cancels_plugin()())  # sent by value (cloudpickle)

    def close() -> None:
        import logging

        # an interrupted or failed sweep cancels its running tasks: distributed then logs a warning
        # and a traceback per task; amble says what happened in one line of its own
        quiet = [logging.getLogger(name) for name in ("distributed", "tornado.application")]
        levels = [log.level for log in quiet]
        for log in quiet:
            log.setLevel(logging.CRITICAL)
        try:
            client.close()
            cluster.close()
        finally:
            for log, level in zip(quiet, levels):
                log.setLevel(level)

    return client, close


def cores() -> int:
    """The processor cores this process may run on (its affinity, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):  # no affinity on macOS and Windows
        return os.cpu_count() or 1


def workers_for(workers: int | None) -> int:
    """The number of local worker processes for ``workers`` (``None``: one per core).

    More processes than cores cannot run a CPU-bound sweep faster; each costs a Python with NumPy
    and the compiled model (≈ 100 MB) and seconds of start-up, so ``workers=64`` on two cores ran
    for minutes before the first task. A larger request is capped at the cores, with a warning."""
    if workers is None:
        return cores()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers must be a positive integer, got {workers!r}")
    if workers > cores():
        import warnings

        warnings.warn(f"workers={workers} is more than the {cores()} cores this process may use; "
                      f"running {cores()} worker processes", stacklevel=3)
        return cores()
    return workers


def _quiet_cancels_plugin() -> type:
    from distributed.diagnostics.plugin import WorkerPlugin

    class QuietCancels(WorkerPlugin):
        """A cancelled task (Ctrl-C, a failed sweep) makes its worker's state machine log a
        warning with the task's repr: notices of the scheduler's own bookkeeping, not for the
        user (amble says what happened in one line); the state machine's errors still show."""

        name = "amble-quiet-cancels"

        def setup(self, worker: Any) -> None:
            import logging

            logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)

    return QuietCancels


class _children_ignore_sigint:
    """Worker processes started inside ignore SIGINT (they inherit the disposition, and Python
    leaves an ignored SIGINT ignored): Ctrl-C in a terminal reaches the whole process group, and
    only the client should react — it cancels the tasks and closes the cluster — instead of every
    worker printing its own traceback."""

    def __enter__(self) -> None:
        import signal

        try:
            self.saved = signal.signal(signal.SIGINT, signal.SIG_IGN)
        except ValueError:  # not the main thread
            self.saved = None

    def __exit__(self, *exc: Any) -> None:
        import signal

        if self.saved is not None:
            signal.signal(signal.SIGINT, self.saved)


#: Seconds a scheduler address gets to accept a connection and to greet it.
HANDSHAKE_TIMEOUT = 5.0


def _check_scheduler(address: str) -> None:
    """Raise :class:`SchedulerError` within a few seconds unless a Dask scheduler answers at a
    ``tcp://host:port`` (or ``host:port``) address.

    A Dask scheduler writes its handshake as soon as a connection is accepted, framed as 8-byte
    little-endian counts (total bytes, number of frames, frame lengths). Anything else — nothing
    listening, a server that stays silent (an HTTP server waits for a request), a server that
    greets in another protocol — is refused here: the Dask client would wait on it without end or
    read its bytes as a frame length."""
    import socket
    import struct
    from urllib.parse import urlsplit

    text = address if "://" in address else f"tcp://{address}"
    try:
        u = urlsplit(text)
        host, port, scheme = u.hostname, u.port, u.scheme
    except ValueError as e:
        raise SchedulerError(f"scheduler address {address!r} is malformed ({e})") from None
    if scheme != "tcp":
        return  # tls://, inproc://, ws://: left to the Dask client and its timeout
    if not host or not port:
        raise SchedulerError(f"scheduler address {address!r} needs a host and a port (tcp://host:port)")
    try:
        sock = socket.create_connection((host, port), timeout=HANDSHAKE_TIMEOUT)
    except OSError as e:
        raise SchedulerError(f"cannot connect to the Dask scheduler at {address!r} ({e.strerror or e})") from None
    with sock:
        sock.settimeout(HANDSHAKE_TIMEOUT)
        data = b""
        try:
            while len(data) < 16:
                chunk = sock.recv(16 - len(data))
                if not chunk:
                    break
                data += chunk
        except OSError:  # timeout included
            pass
    if len(data) < 16:
        raise SchedulerError(f"{address!r} is not a Dask scheduler: no handshake within {HANDSHAKE_TIMEOUT:g} s")
    total, nframes = struct.unpack("<QQ", data)
    if not (1 <= nframes <= 64 and 16 < total < 1 << 20) and not (1 <= total <= 64):
        raise SchedulerError(f"{address!r} answered, but not as a Dask scheduler")


def execute(client: Any, fn: Callable, tasks: list[tuple], store: ResultStore, progress: bool, total: int,
            desc: str, threads: int = 1) -> None:
    """Submit ``fn(*task)`` for each task; append each returned row list to the store as it lands.

    Every task's first argument is the same :class:`HybridSystem`. In this process
    (``scheduler='synchronous'``), ``threads`` > 1 runs that many tasks at once on threads of this
    process (:func:`_pooled`)."""
    if not tasks:
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit="pt", disable=not progress, leave=False)
    try:
        if isinstance(client, LocalProcesses):
            client.run(fn, tasks, store, bar, _children_ignore_sigint)
            return
        if isinstance(client, _Serial):
            if threads > 1 and len(tasks) > 1:
                _pooled(fn, tasks, store, bar, threads)
                return
            for t in tasks:
                rows = fn(*t)
                store.append(rows)
                bar.update(len(rows))
            return
        import logging

        from dask.distributed import as_completed

        # Ctrl-C inside a wait on the client makes distributed cancel that wait from its event loop,
        # where the cancel can fail on a future that has just finished; tornado then logs the failure
        # with a traceback from the loop's thread, racing amble's one-line "interrupted". Task errors
        # reach this thread through fut.result(), so the loop's own log is muted while tasks run
        # (and after a failure, until the process ends).
        loop_log = logging.getLogger("tornado.application")
        level = loop_log.level
        loop_log.setLevel(logging.CRITICAL)
        try:
            # the system (sympy expressions) is shipped and unpickled once per worker, not once per task
            shared = client.scatter(tasks[0][0], broadcast=True, hash=False)
            futures = [client.submit(fn, shared, *t[1:], pure=False) for t in tasks]
            for fut in as_completed(futures):
                rows = fut.result()
                store.append(rows)
                bar.update(len(rows))
        except BaseException:
            raise  # the cancel's log may come later from the loop's thread: the loop stays muted
        else:
            loop_log.setLevel(level)
    finally:
        bar.close()


def _pooled(fn: Callable, tasks: list[tuple], store: ResultStore, bar: Any, threads: int) -> None:
    """Run the tasks on ``threads`` threads of this process, appending each one's rows from this
    thread as it finishes.

    Why tasks side by side rather than one task's walks shared by threads: the Python part of a
    task (building its states, its rows as text) holds the GIL, but it overlaps the compiled walks
    of the other tasks (which release it) instead of leaving the other core idle. Should a task
    fail (or the run be interrupted), the tasks not started are dropped, those running are
    finished and their rows appended, then the first error is raised: no finished work is lost."""
    from concurrent.futures import ThreadPoolExecutor, as_completed

    error: BaseException | None = None
    # a sweep run from a task of another (a user's embedding that maps a basin) gets a pool of its
    # own: waiting on the shared pool's threads from one of them could wait for ever
    own = threading.current_thread().name.startswith(_POOL_PREFIX)
    pool = ThreadPoolExecutor(threads, thread_name_prefix=_POOL_PREFIX) if own else _pool(threads)
    futures = [pool.submit(fn, *t) for t in tasks]
    pending = set(futures)
    while pending:
        try:
            for fut in as_completed(pending):
                pending.discard(fut)
                if fut.cancelled():
                    continue
                exc = fut.exception()
                if exc is not None:
                    raise exc
                rows = fut.result()
                store.append(rows)
                bar.update(len(rows))
        except BaseException as e:  # a task's error, Ctrl-C, or a failed append
            if error is None:
                error = e
                for f in pending:
                    f.cancel()
            elif isinstance(e, KeyboardInterrupt):  # interrupted again while finishing: stop waiting
                break
    if own:
        pool.shutdown(wait=not isinstance(error, KeyboardInterrupt), cancel_futures=True)
    elif not isinstance(error, KeyboardInterrupt):  # the shared pool stays: wait for this call's running tasks
        for fut in futures:
            if not fut.cancelled():
                fut.exception()
    if error is not None:
        raise error


#: Thread pools of :func:`_pooled` by size, with the process they were made in: starting and
#: joining the threads of a new pool on every call cost over half a millisecond, about a tenth of
#: walking a 12 × 12 basin map. At most :data:`_POOL_SIZES` sizes are kept (the oldest is shut down).
_POOLS: dict[int, tuple[int, Any]] = {}
_POOL_SIZES = 4
_POOL_PREFIX = "amble-sweep"
_POOLS_LOCK = threading.Lock()


def _pool(threads: int) -> Any:
    """This process's pool of ``threads`` threads (a pool made before a ``fork`` has no threads
    in the child: it is replaced)."""
    from concurrent.futures import ThreadPoolExecutor

    with _POOLS_LOCK:
        hit = _POOLS.get(threads)
        if hit is not None and hit[0] == os.getpid():
            return hit[1]
        if len(_POOLS) >= _POOL_SIZES:
            _POOLS.pop(next(iter(_POOLS)))[1].shutdown(wait=False)
        pool = ThreadPoolExecutor(threads, thread_name_prefix=_POOL_PREFIX)
        _POOLS[threads] = (os.getpid(), pool)
        return pool


# ---------------------------------------------------------------------------- grid helpers
def check_params(system: HybridSystem, names: Sequence[str]) -> None:
    """Raise :class:`ParameterError` unless every name is a parameter of ``system``."""
    known = list(compiled(system).meta["params"])
    for n in names:
        if n not in known:
            raise ParameterError(f"unknown parameter {n!r}; known: {', '.join(known)}")


def sweep_values(values: Sequence[float], what: str, system: HybridSystem | None = None) -> np.ndarray:
    """``values`` as a flat float array; refuses an empty or non-finite list (``what`` names it)
    and, given the ``system``, values of parameter ``what`` outside its declared domain."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        raise StateError(f"{what}: no values to sweep")
    if not np.all(np.isfinite(v)):
        raise StateError(f"{what}: values must be finite")
    if system is not None:
        for x in (v.min(), v.max()):  # a domain is an interval: its ends decide
            system.check_parameters({what: float(x)})
    return v


def chunks(idx: Sequence[int], size: int) -> list[list[int]]:
    """``idx`` cut into consecutive runs of ``size`` (the last may be shorter)."""
    return [list(idx[i:i + size]) for i in range(0, len(idx), size)]


__all__ = ["check_params", "chunks", "execute", "open_client", "sweep_values"]
