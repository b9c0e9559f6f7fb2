"""The in-process thread pool of sweeps: kept between calls, still whole after a task fails, and
never waited on from one of its own threads (a sweep started from inside a task gets its own)."""

from __future__ import annotations

import threading

import pytest

from amble.analysis import runner


class _Rows:
    def __init__(self) -> None:
        self.rows: list = []

    def append(self, rows: list) -> None:
        self.rows.extend(rows)


class _Bar:
    def update(self, n: int) -> None:
        pass


def _square(i: int) -> list[int]:
    return [i * i]


def test_the_pool_is_kept_and_survives_a_failed_task():
    store = _Rows()
    runner._pooled(_square, [(i,) for i in range(6)], store, _Bar(), 2)
    assert sorted(store.rows) == [i * i for i in range(6)]
    pool = runner._pool(2)

    def fails(i: int) -> list[int]:
        if i == 3:
            raise ValueError("task 3")
        return [i]

    with pytest.raises(ValueError, match="task 3"):
        runner._pooled(fails, [(i,) for i in range(6)], _Rows(), _Bar(), 2)
    again = _Rows()
    runner._pooled(_square, [(i,) for i in range(4)], again, _Bar(), 2)
    assert sorted(again.rows) == [0, 1, 4, 9] and runner._pool(2) is pool


def test_a_sweep_started_inside_a_task_gets_its_own_pool():
    def outer(i: int) -> list[int]:
        inner = _Rows()
        runner._pooled(_square, [(j,) for j in range(3)], inner, _Bar(), 2)  # both shared threads are busy
        return [i + sum(inner.rows)]

    store = _Rows()
    done = threading.Thread(target=runner._pooled, args=(outer, [(0,), (10,)], store, _Bar(), 2), daemon=True)
    done.start()
    done.join(timeout=30)
    assert not done.is_alive(), "a sweep inside a task waited on the threads running it"
    assert sorted(store.rows) == [5, 15]


def test_two_basins_at_once_share_the_pool_and_equal_one_at_a_time(compass):
    import numpy as np

    from amble import sweep

    kw = dict(steps=15, rows_per_task=1, threads=2, scheduler="synchronous", progress=False)
    grids = [{"stance": np.linspace(-0.35, -0.10, 6), "stance_dot": np.linspace(0.8, 1.4, 3)},
             {"stance": np.linspace(-0.30, -0.15, 5), "stance_dot": np.linspace(0.9, 1.2, 4)}]
    alone = [sweep(compass, "basin", g, **kw) for g in grids]
    together: list = [None, None]

    def one(i: int) -> None:
        together[i] = sweep(compass, "basin", grids[i], **kw)

    workers = [threading.Thread(target=one, args=(i,)) for i in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=60)
    for a, b in zip(alone, together):
        assert b is not None
        for name in ("outcome", "steps", "distance", "reasons"):
            np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
