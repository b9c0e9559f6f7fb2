"""Notebook display: registered with IPython's formatters, without the core types knowing viz."""

from __future__ import annotations

import sys
import types

import matplotlib

matplotlib.use("Agg")

import amble  # noqa: E402
from amble.analysis.poincare import find_fixed_point  # noqa: E402
from amble.viz import notebook  # noqa: E402


class _Formatter:
    def __init__(self) -> None:
        self.by_name: dict[tuple[str, str], object] = {}

    def for_type_by_name(self, module: str, name: str, func) -> None:
        self.by_name[(module, name)] = func


def test_register_is_a_no_op_outside_ipython(monkeypatch):
    monkeypatch.delitem(sys.modules, "IPython", raising=False)
    assert notebook.register() is False


def test_register_binds_the_real_types(monkeypatch):
    forms = {"text/html": _Formatter(), "image/png": _Formatter()}
    shell = types.SimpleNamespace(display_formatter=types.SimpleNamespace(formatters=forms))
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))
    assert notebook.register() is True
    ((mod, name), html_fn), = forms["text/html"].by_name.items()
    ((mod2, name2), png_fn), = forms["image/png"].by_name.items()
    # the names registered are where the types really live
    assert getattr(sys.modules[mod], name) is amble.Trajectory
    from amble.analysis.poincare import LimitCycle

    assert getattr(sys.modules[mod2], name2) is LimitCycle
    assert html_fn is notebook.trajectory_html and png_fn is notebook.cycle_png


def test_displays_render(compass):
    tr = amble.simulate(compass, steps=1, sample_dt=0.02)
    page = notebook.trajectory_html(tr)
    assert page.startswith("<iframe srcdoc=") and "amble.scene/1" in page
    png = notebook.cycle_png(find_fixed_point(compass))
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000
