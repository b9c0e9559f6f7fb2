"""The derived equations of motion of the compass gait, as sympy expressions and as LaTeX.

``derive`` turns the model's points, masses and gravity into ``M(q) q̈ + h(q, q̇) = Γ``. The mass
matrix can be compared entry by entry with the thesis' Eq. 17 (with ``l = a + b``). The LaTeX goes to
``compass_gait_equations.tex`` in the current directory.

Run: ``python examples/equations_latex.py``.
"""

import sympy as sp

from amble import derive
from amble.models import load

walker = load("compass-gait")
model = walker.modes["compass-gait"]  # the single mode of this walker
eq = derive(model)

# The derivation never expands or simplifies (that keeps large models tractable); for reading a
# small model, sympy's simplify gives the textbook form.
M, G = sp.simplify(eq.M), sp.simplify(eq.G)
print("coordinates:", model.q)
print("mass matrix M(q):")
sp.pprint(M)
print("gravity term G(q) = ∂V/∂q:")
sp.pprint(G)
print("operations to evaluate M, h, Γ (shared subexpressions):", eq.count_ops())

with open("compass_gait_equations.tex", "w", encoding="utf-8") as f:
    f.write(f"M(q) = {sp.latex(M)}\n\nG(q) = {sp.latex(G)}\n\n")
    f.write(eq.latex(display=True) + "\n")  # the full M q̈ + h = Γ as derived
print("wrote compass_gait_equations.tex")
