"""Derivation: equations of motion ``M q̈ + h = Γ`` from a model (:mod:`.equations`) and the
impulsive reset maps of impacts and joint locks (:mod:`.impact`), as sympy expressions."""
