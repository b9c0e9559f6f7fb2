"""Runs end. A cap on integrator steps between transitions and in
total ends a run with a named status, a one-line message and the partial trajectory; Ctrl-C
interrupts the compiled loop with the run so far attached to the KeyboardInterrupt."""

import os
import signal
import threading
import time

import numpy as np
import pytest
from systems import guarded_pendulum, pendulum

import amble
from amble import HybridSystem, Options


def _free_pendulum() -> HybridSystem:
    m, _ = pendulum("ev-free")
    return HybridSystem("ev-free", m)


def test_steps_between_transitions_are_capped():
    tr = amble.simulate(_free_pendulum(), [0.3, 0.0], t_end=1e6,
                        options=Options(max_steps_between_events=500))
    assert tr.status == "stalled"
    assert "\n" not in tr.message and "500 integrator steps" in tr.message
    assert 0 < tr.t[-1] < 1e6 and tr.t.size > 10  # the partial trajectory is there
    # energy is conserved along it (a pendulum: ½θ̇² − g cos θ)
    e = tr.energy().sum(axis=1)
    assert np.max(np.abs(e - e[0])) < 1e-8


def test_total_integrator_steps_are_capped():
    tr = amble.simulate(_free_pendulum(), [0.3, 0.0], t_end=1e6,
                        options=Options(max_integrator_steps=300, max_steps_between_events=0))
    assert tr.status == "max_integrator_steps"
    assert "300 integrator steps" in tr.message


def test_transitions_restart_the_between_events_budget():
    # a pendulum that crosses θ = A twice per period, each crossing counted as a transition that
    # keeps the mode: 1000 steps between transitions are plenty, 1000 in total are not
    s = guarded_pendulum("ev-limits-guard")
    tr = amble.simulate(s, [0.0, 1.0], params={"A": 2.0}, t_end=50.0,
                        options=Options(max_steps_between_events=1000))
    assert tr.status == "end_time", tr.message


def test_ctrl_c_interrupts_the_compiled_loop():
    sys_ = _free_pendulum()
    amble.simulate(sys_, [0.3, 0.0], t_end=0.1)  # compile first: the timer measures the run only
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as info:
            # a coarse grid: the 512 MiB recording budget must not end the run before the signal
            amble.simulate(sys_, [0.3, 0.0], t_end=1e9, sample_dt=1.0,
                           options=Options(max_integrator_steps=0, max_steps_between_events=0))
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 5.0
    partial = info.value.trajectory
    assert partial.status == "interrupted" and partial.t[-1] > 0
    assert partial.message.startswith("interrupted at t =")
