"""``amble equations``: guards, the derived impact and lock maps in matrix form, typeset LaTeX names,
the same simplification in text and LaTeX, and ``--json --latex`` carrying both."""

from __future__ import annotations

import json

import sympy as sp

from amble.cli.main import main
from amble.derivation.equations import derive, latex_names

PENDULUM = """
from amble import HybridSystem, Model, Explicit, Guard
m = Model("pendulum")
(th,) = m.coordinates("th")
l, mass, g = m.parameters(l=1.0, mass=1.0, g=9.81)
m.point("pivot", (0, 0))
m.point("bob", (l * __import__("sympy").sin(th), -l * __import__("sympy").cos(th)), mass=mass, link="pivot")
m.gravity(g)
system = HybridSystem("pendulum", {"swing": m})
system.transition("kick", "swing", Guard(th, direction=1), Explicit(q=[th], qd=[-m.dot(th)]))
"""


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_text_shows_guard_and_derived_impact_map(capsys):
    code, out, _ = run(capsys, "equations", "compass-gait")
    assert code == 0
    assert "guard: (-a - b)*cos(slope - swing) + (a + b)*cos(slope - stance)" in out and "falling through 0" in out
    assert "impact of swing_foot: M_e (qd_e+ - qd_e-) = J^T lambda" in out
    assert "qd_e = (stance_dot, swing_dot, base_x_dot, base_y_dot)" in out
    assert "M_e[2] = [(a*m + a*mh + 2*b*m + b*mh)*cos(stance), -a*m*cos(swing), 2*m + mh, 0]" in out
    assert "J[0] = [(a + b)*cos(stance), (-a - b)*cos(swing), 1, 0]" in out
    assert "relabel: stance <- swing, swing <- stance" in out


def test_json_impact_map_is_the_derived_one(capsys, compass):
    from amble.derivation.impact import impulse_data

    code, out, _ = run(capsys, "equations", "compass-gait", "--json")
    heel = next(t for t in json.loads(out)["transitions"] if t["name"] == "heel_strike")
    mode = compass.modes[heel["source"]]
    tr = next(t for t in compass.transitions if t.name == "heel_strike")
    data = impulse_data(mode, derive(mode), tr.reset, compass.modes[tr.target])
    Me = sp.Matrix([[sp.sympify(e, locals={str(s): s for s in data.Me.free_symbols}) for e in row]
                    for row in heel["map"]["Me"]])
    assert sp.simplify(Me - data.Me) == sp.zeros(4, 4)
    assert heel["map"]["velocity_map"] == [["0", "1"], ["1", "0"]]
    assert "latex" not in heel["map"]


def test_lock_map_of_the_kneed_biped(capsys):
    code, out, _ = run(capsys, "equations", "kneed-biped")
    assert code == 0
    assert "lock -shank + thigh = 0" in out or "lock shank - thigh = 0" in out
    assert "relabel: stance <- stance, thigh <- thigh" in out


def test_latex_names_are_typeset(capsys):
    code, out, _ = run(capsys, "equations", "compass-gait", "--latex")
    assert code == 0
    assert r"\ddot{\theta}_{\mathrm{stance}}" in out and r"\dot{\theta}_{\mathrm{swing}}" in out
    assert r"\ddot{stance}" not in out and r"\mathrm{slope}" in out
    assert r"\mathrm{a1}" not in run(capsys, "equations", "kneed-biped", "--latex")[1]


def test_latex_and_text_are_simplified_alike_and_json_latex_gives_both(capsys, tmp_path):
    f = tmp_path / "pendulum.py"
    f.write_text(PENDULUM, encoding="utf-8")
    raw = derive(__import__("amble.models", fromlist=["load_file"]).load_file(str(f)).modes["swing"])
    assert "sin" in str(raw.M[0, 0])  # as derived: m l² (sin² + cos²)
    code, out, _ = run(capsys, "equations", f, "--json", "--latex")
    assert code == 0
    d = json.loads(out)
    mode = d["modes"]["swing"]
    assert mode["mass_matrix"] == [["l**2*mass"]]
    assert r"\mathrm{mass} l^{2}" in mode["latex"] and r"\sin" not in mode["latex"].split(r"\,")[0]
    kick = d["transitions"][0]
    assert kick["map"]["velocities"] == {"th_dot": "-th_dot"}
    assert kick["map"]["latex"]["velocities"] == r"\left[\begin{matrix}- \dot{\theta}_{\mathrm{th}}\end{matrix}\right]"
    assert kick["guard_detail"]["latex"] == r"\theta_{\mathrm{th}}"


def test_latex_names_rules(compass):
    import amble

    m = amble.Model("x")
    x, th, q1 = m.coordinates("x_stance theta_1 q1")
    m.declare_units(x_stance="m")
    k, slope = m.parameters(k_T=1.0, slope=0.1)
    names = {str(a): str(b) for a, b in latex_names(m).items()}
    assert names["x_stance"] == r"x_{\mathrm{stance}}" and names["theta_1"] == r"\theta_{1}"
    assert names["theta_1_dot"] == r"\dot{\theta}_{1}" and names["q1"] == "q_{1}"
    assert names["k_T"] == "k_{T}" and names["slope"] == r"\mathrm{slope}"
