"""The C side of the Python↔C interface is generated from amble.backend.abi and checked at load."""

import re

import pytest

from amble.backend import abi, cache
from amble.backend.kernels import Kernels, build
from amble.errors import CompileError


def _defines(text: str) -> dict[str, int]:
    return {m[1]: int(m[2]) for m in re.finditer(r"^#define (\w+) (-?\d+)(?:LL)?$", text, re.M)}


def test_header_equals_the_tables():
    d = _defines(abi.c_header())
    assert {k[3:]: v for k, v in d.items() if k.startswith("ST_")} == {n: c for c, n, _ in abi.STATUS}
    cx = {k[3:]: v for k, v in d.items() if k.startswith("CX_")}
    assert cx == {**abi.CTX, "X": abi.CTX_X}
    assert {k[3:]: v for k, v in d.items() if k.startswith("OP_")} == abi.OPT
    assert {k[3:]: v for k, v in d.items() if k.startswith("IO_")} == abi.IOPT
    assert d["IOPT_LEN"] == len(abi.IOPT)  # what a C copy of the integer options covers
    assert d["AMBLE_LAYOUT"] == abi.LAYOUT
    assert "#include <stdint.h>" in abi.c_header()


def test_engine_sources_define_no_interface_codes():
    for f in cache.C_DIR.iterdir():
        text = f.read_text()
        assert not re.search(r"^\s*#\s*define\s+((ST|CX|OP|IO|SENS)_\w+|AMBLE_LAYOUT)", text, re.M), f.name


def test_generated_unit_carries_the_header(compass):
    k = build(compass)
    src = k.path.with_suffix(".c").read_text()
    head, tail, _ = src.partition('#include "model_tail.h"')
    assert tail and abi.c_header() in head


def test_compiled_library_reports_the_layout(compass):
    assert build(compass).layout == abi.LAYOUT


def test_library_with_another_layout_is_refused(compass, monkeypatch):
    k = build(compass)
    monkeypatch.setattr(abi, "LAYOUT", abi.LAYOUT + 1)
    with pytest.raises(CompileError, match="clear the cache"):
        Kernels(k.path, k.meta)


def test_sensitivity_layout_is_the_tables():
    """The C offsets, evaluated for a library's NXMAX and SC, are those Python lays out: the
    state block, then one row of dτ, then the two column counts, then the end of the buffer."""
    text = abi.c_header()
    exprs = {m[1]: m[2] for m in re.finditer(r"^#define SENS_(\w+) (.+)$", text, re.M)}
    for nxm, sc in ((4, 4), (4, 7), (14, 20)):
        c = {name: eval(e, {"NXMAX": nxm, "SC": sc}) for name, e in exprs.items()}  # C arithmetic of ints
        assert c == abi.sens_layout(nxm, sc)
        assert c == {"S": 0, "TAU": nxm * sc, "NCS": nxm * sc + sc, "NCP": nxm * sc + sc + 1,
                     "SIZE": (nxm + 1) * sc + 2}
