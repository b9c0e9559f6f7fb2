"""``amble equations``: entries simplified for display (the same functions, shorter), labelled
LaTeX, and ``--standalone`` a whole LaTeX document."""

from __future__ import annotations

import json
import random
import re
import shutil
import subprocess

import sympy as sp

from amble.cli.equations import show
from amble.cli.main import main


def test_pythagoras_and_angle_sums_are_folded():
    a, b, x, y = sp.symbols("a b x y")
    assert show(a**2 * sp.sin(x) ** 2 + a**2 * sp.cos(x) ** 2) == a**2
    folded = show(a * b * (sp.sin(x) * sp.cos(y) - sp.cos(x) * sp.sin(y)) + b * sp.sin(x) ** 2 + b * sp.cos(x) ** 2)
    assert sp.count_ops(folded) <= 6 and not folded.has(sp.cos)
    assert sp.simplify(folded - (a * b * sp.sin(x - y) + b)) == 0


def _balanced(line: str) -> bool:
    depth = 0
    for c in re.sub(r"\\[{}]", "", line):
        depth += {"{": 1, "}": -1}.get(c, 0)
        if depth < 0:
            return False
    return depth == 0


def test_kneed_biped_standalone_document_is_simplified_labelled_and_equal(capsys, tmp_path):
    assert main(["equations", "kneed-biped", "--standalone", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    doc = out["document"]
    lines = doc.splitlines()
    assert lines[0].startswith(r"\documentclass") and lines[-1] == r"\end{document}"
    assert r"\begin{document}" in doc
    assert all(_balanced(ln) for ln in lines)
    assert doc.count(r"\[") == doc.count(r"\]") > 0
    assert sum(ln.startswith("M(q) = ") for ln in lines) == 2  # both modes, labelled
    assert sum(ln.startswith(r"h(q, \dot{q}) = ") for ln in lines) == 2
    # the as-derived a² sin²θ + a² cos²θ is gone from M and h, in the document and the text
    for mode in out["modes"].values():
        for key in ("M", "h"):
            assert r"\sin^{2}" not in mode["latex_parts"][key] and r"\cos^{2}" not in mode["latex_parts"][key]
        assert not any("sin(stance)**2" in e for row in mode["mass_matrix"] for e in row)
    # display only: the shown entries are the derived functions (checked at random states)
    from amble.derivation.equations import derive
    from amble.models import load

    system = load("kneed-biped").symbolic()
    rng = random.Random(3)
    for mname, mode in out["modes"].items():
        eq = derive(system.modes[mname])
        syms = sorted(eq.M.free_symbols | eq.h.free_symbols, key=str)
        local = {str(s): s for s in syms}
        shown_M = sp.Matrix([[sp.sympify(e, locals=local) for e in row] for row in mode["mass_matrix"]])
        shown_h = sp.Matrix([sp.sympify(e, locals=local) for e in mode["bias"]])
        f = sp.lambdify(syms, [shown_M - eq.M, shown_h - eq.h], "numpy")
        for _ in range(5):
            dM, dh = f(*[rng.uniform(0.2, 1.5) for _ in syms])
            assert abs(dM).max() < 1e-9 and abs(dh).max() < 1e-9
    if shutil.which("pdflatex"):
        (tmp_path / "eq.tex").write_text(doc)
        proc = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error", "eq.tex"], cwd=tmp_path,
                              capture_output=True, timeout=120)
        assert proc.returncode == 0 and (tmp_path / "eq.pdf").exists()
