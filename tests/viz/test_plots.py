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
    top, bottom, total = fig.axes
    assert [ln.get_label() for ln in top.get_lines() if not ln.get_label().startswith("_")] == ["stance", "swing"]
    assert {"kinetic", "potential (rel.)"} <= {ln.get_label() for ln in bottom.get_lines()}
    assert "total (rel., right axis)" in {ln.get_label() for ln in total.get_lines()}
    footfalls = [ln for ln in top.get_lines() if ln.get_gid() == "footfall"]
    assert len(footfalls) == 3  # one marker per heel strike
    for suffix in (".png", ".svg", ".pdf"):
        out = plot_trajectory(walk, tmp_path / f"series{suffix}")
        assert out.stat().st_size > 2000


def test_energy_plot_marks_the_loss_at_every_footfall(walk):
    """A plastic impact dissipates kinetic energy (Carnot's theorem): every footfall of the passive
    walker is marked by a dashed drop of the total energy, labelled with its (negative) value."""
    fig = plot_trajectory(walk)
    total = fig.axes[2]
    drops = [ln for ln in total.get_lines() if ln.get_gid() == "impact_loss"]
    assert len(drops) == len(walk.step_events) == 3
    for ln in drops:
        assert ln.get_linestyle() == "--"
        before, after = ln.get_ydata()
        assert after < before
    labels = [t.get_text() for t in total.texts]
    assert len(labels) == 3 and all(t.startswith("-") and t.endswith(" J") for t in labels)
    # the total's flow lines never join the two sides of a footfall, and between footfalls the
    # passive walker's energy (in the world's frame) is conserved
    flows = [ln for ln in total.get_lines() if ln.get_gid() != "impact_loss"]
    assert len(flows) == 4
    for ln in flows:
        x, y = ln.get_xdata(), ln.get_ydata()
        assert not any(x[i] == x[i + 1] for i in range(len(x) - 1))
        assert max(y) - min(y) < 1e-6


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


def test_phase_portrait_draws_jumps_dashed_and_flow_solid(compass):
    lc = find_fixed_point(compass)
    tr = lc.trajectory(2)
    ax = plot_limit_cycle(tr, cycle=lc).axes[0]
    jumps = [ln for ln in ax.get_lines() if ln.get_gid() == "jump"]
    assert len(jumps) >= 2
    assert all(ln.get_linestyle() == "--" for ln in jumps)
    ends = [tuple(zip(ln.get_xdata(), ln.get_ydata())) for ln in jumps]
    # no solid line steps from a jump's pre-impact point to its post-impact point
    for ln in ax.get_lines():
        if ln.get_linestyle() != "-" or ln.get_gid() is not None:
            continue
        pts = list(zip(ln.get_xdata(), ln.get_ydata()))
        pairs = set(zip(pts[:-1], pts[1:]))
        for a, b in ends:
            assert (a, b) not in pairs
    # the ends are marked: an open circle before the impact, a filled one after
    assert len([ln for ln in ax.get_lines() if ln.get_gid() == "jump_pre"]) == len(jumps)
    assert len([ln for ln in ax.get_lines() if ln.get_gid() == "jump_post"]) == len(jumps)
    assert "impact jump" in [ln.get_label() for ln in ax.get_lines()]


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


def _map_result(branch):
    from types import SimpleNamespace

    rows = []
    for i in range(3):
        for j in range(4):
            r = {"i": i, "j": j, "slope": 0.01 * (i + 1), "mh": 5.0 + j, "status": "ok", "max_modulus": 0.5 + 0.1 * j}
            if branch:
                r["branch"] = 1 if (i, j) in ((2, 3), (2, 2)) else 0
            rows.append(r)
    return SimpleNamespace(params=("slope", "mh"), rows=rows)


def test_stability_map_marks_cells_of_another_branch(tmp_path, saved_figures):
    from amble.viz.sweep_plots import plot_parameter_map

    figs = saved_figures
    plot_parameter_map(_map_result(True), tmp_path / "m.png")
    plot_parameter_map(_map_result(False), tmp_path / "n.png")  # no branch column: no marks, no error
    marked = [c for c in figs[0].axes[0].collections if c.get_gid() == "branch_change"]
    assert len(marked) == 1
    assert sorted(map(tuple, marked[0].get_offsets().tolist())) == [(7.0, 0.03), (8.0, 0.03)]
    assert not [c for c in figs[1].axes[0].collections if c.get_gid() == "branch_change"]


def test_stability_map_compares_branch_ids_within_a_row(tmp_path, saved_figures):
    # a map's rows are separate tasks, each starting its branch ids at its own first point: rows
    # with different ids are not different gaits; a change of id inside a row is
    from amble.viz.sweep_plots import plot_parameter_map

    res = _map_result(False)
    for r in res.rows:
        r["branch"] = 4 * r["i"] + (3 if (r["i"], r["j"]) == (1, 3) else 0)
    figs = saved_figures
    plot_parameter_map(res, tmp_path / "m.png")
    marked = [c for c in figs[0].axes[0].collections if c.get_gid() == "branch_change"]
    assert len(marked) == 1 and marked[0].get_offsets().tolist() == [[8.0, 0.02]]
