"""A generated source's functions of their own unit: split off, compiled beside the rest, linked
into one library; a compiler error in either unit is a CompileError."""

import ctypes

import pytest

from amble.backend.cache import _compile
from amble.backend.units import UNIT_BEGIN, UNIT_END, split_units
from amble.errors import CompileError

SRC = ('#include "amble_core.h"\n'
       + UNIT_BEGIN + "AMBLE_HIDDEN double cube(double x) {\n    return x * x * x;\n}\n" + UNIT_END
       + "static double twice(double x) { return 2.0 * x; }\n"
       + UNIT_BEGIN + "AMBLE_HIDDEN double half(double x) {\n    return 0.5 * x;\n}\n" + UNIT_END
       + "double f(double x) { return cube(x) + twice(x) + half(x); }\n")


def test_split_leaves_prototypes_in_order():
    main, own = split_units(SRC)
    assert main.index("AMBLE_HIDDEN double cube(double x);") < main.index("static double twice")
    assert "return x * x * x" not in main and "return x * x * x" in own and "return 0.5 * x" in own
    assert split_units("int g(void) { return 1; }\n") == ("int g(void) { return 1; }\n", None)


def test_units_link_into_one_library(tmp_path):
    so, _ = _compile(SRC, "unitstest", tmp_path)
    lib = ctypes.CDLL(str(so))
    lib.f.restype, lib.f.argtypes = ctypes.c_double, [ctypes.c_double]
    assert lib.f(3.0) == 27.0 + 6.0 + 1.5
    assert not hasattr(lib, "cube")  # hidden: not exported from the library


def test_error_in_own_unit_is_a_compile_error(tmp_path):
    bad = SRC.replace("return 0.5 * x;", "return 0.5 * y;")
    with pytest.raises(CompileError, match="failed"):
        _compile(bad, "unitsbad", tmp_path)


def test_own_unit_sees_the_defines_before_it(tmp_path):
    # a tree's split-off mass-matrix kernel reads hoisted parameters as p[NPARAM + j]
    src = ('#include "amble_core.h"\n#define NPARAM 2\n'
           + UNIT_BEGIN + "AMBLE_HIDDEN double last(const double *p) {\n    return p[NPARAM + 0];\n}\n" + UNIT_END
           + "double g(const double *p) { return last(p); }\n")
    _, own = split_units(src)
    assert "#define NPARAM 2" in own
    lib = ctypes.CDLL(str(_compile(src, "unitsdefines", tmp_path)[0]))
    lib.g.restype, lib.g.argtypes = ctypes.c_double, [ctypes.POINTER(ctypes.c_double)]
    assert lib.g((ctypes.c_double * 3)(1.0, 2.0, 7.0)) == 7.0
