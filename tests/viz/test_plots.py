"""Plots and movie export: files are written and hold the expected artists (not pixels)."""

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

import amble  # noqa: E402
from amble.analysis.poincare import find_fixed_point  # noqa: E402
from amble.viz.plot import plot_limit_cycle, plot_trajectory  # noqa: E402


@pytest.fixture(scope="module")
def walk(compass):
    return amble.simulate(compass, steps=3, sample_dt=0.01)


def test_time_series_has_coordinates_energies_and_footfalls(walk, tmp_path):
    fig = plot_trajectory(walk)
    top, bottom = fig.axes
    assert [ln.get_label() for ln in top.get_lines() if not ln.get_label().startswith("_")] == ["stance", "swing"]
    assert {"kinetic", "potential (rel.)", "total (rel.)"} <= {ln.get_label() for ln in bottom.get_lines()}
    footfalls = [ln for ln in top.get_lines() if ln.get_label().startswith("_")]
    assert len(footfalls) == 3  # one marker per heel strike
    for suffix in (".png", ".svg", ".pdf"):
        out = plot_trajectory(walk, tmp_path / f"series{suffix}")
        assert out.stat().st_size > 2000


def test_limit_cycle_plot_draws_impact_jumps(compass, tmp_path):
    lc = find_fixed_point(compass)
    tr = lc.trajectory(2)
    fig = plot_limit_cycle(tr, cycle=lc)
    ax = fig.axes[0]
    arrows = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None]
    assert len(arrows) >= 2  # each coordinate jumps at the heel strike
    assert "fixed point" in [ln.get_label() for ln in ax.get_lines()]
    assert "angular velocity" in ax.get_ylabel()
    assert amble.plot_limit_cycle(lc, tmp_path / "cycle.png").stat().st_size > 5000


def test_gif_export_has_frames(walk, tmp_path):
    from PIL import Image

    out = amble.animate(walk, tmp_path / "walk.gif", fps=10)
    with Image.open(out) as im:
        assert im.n_frames >= 10


def test_unknown_file_formats_are_user_errors(tmp_path) -> None:
    import matplotlib.pyplot as plt

    from amble.errors import AmbleError
    from amble.viz import animate
    from amble.viz.errors import VizError
    from amble.viz.sweep_plots import _save

    with pytest.raises(VizError, match="unknown animation format"):
        animate(None, tmp_path / "walk.txt")  # type: ignore[arg-type]
    fig = plt.figure()
    with pytest.raises(AmbleError, match="must end with"):
        _save(fig, tmp_path / "plot.txt")
    plt.close(fig)
