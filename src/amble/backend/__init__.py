"""Backend: the derived equations as generated C (:mod:`.codegen`), compiled once per model
structure and cached (:mod:`.cache`), loaded through ctypes (:mod:`.kernels`); the layout shared
by Python and C is one table (:mod:`.abi`). The C sources live in ``_c/``."""
