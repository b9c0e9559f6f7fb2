"""Notebook behaviour in a real Jupyter kernel (nbclient): plots still show after a GIF export,
and a trajectory displays as the inline viewer of bounded size."""

from __future__ import annotations

import os

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

CELLS = [
    "%matplotlib inline\nimport amble\nfrom amble.models import load\ncg = load('compass-gait')\n"
    "short = amble.simulate(cg, steps=2)\nlong = amble.simulate(cg, steps=100)",
    "amble.animate(short, 'x.gif', fps=10)\nimport matplotlib\nprint(matplotlib.get_backend())",
    "import matplotlib.pyplot as plt\nplt.plot([0, 1], [1, 0])\nplt.show()",
    "short",
    "long",
]


def test_plots_show_after_a_gif_export_and_the_viewer_is_bounded(tmp_path):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in CELLS])
    env = {"AMBLE_CACHE_DIR": os.environ.get("AMBLE_CACHE_DIR", "")}
    os.environ.update({k: v for k, v in env.items() if v})
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outs = [c.outputs for c in nb.cells]
    assert (tmp_path / "x.gif").stat().st_size > 1000
    backend = "".join(o.get("text", "") for o in outs[1]).strip().lower()
    assert backend != "agg" and "inline" in backend, backend
    assert any("image/png" in o.get("data", {}) for o in outs[2]), outs[2]  # the plot is shown
    sizes = []
    for cell in outs[3:]:
        html = next(o["data"]["text/html"] for o in cell if "text/html" in o.get("data", {}))
        assert html.startswith("<iframe srcdoc=")
        sizes.append(len(html))
    # a 100-step walk (73 s) embeds little more than a 2-step one: frames are capped
    assert sizes[1] < 1.15 * sizes[0] and sizes[1] < 1_000_000, sizes
