"""Translation units of a generated source: the functions it marks for a unit of their own
(:data:`UNIT_BEGIN` … :data:`UNIT_END`, by the code generator) split off, and the compiler run on
several units side by side. Pure text and processes: no sympy (the cache's lookup imports this)."""

from __future__ import annotations

from ..errors import CompileError

#: Marks of a function the code generator puts in a translation unit of its own (a large kernel:
#: the two units compile in parallel). The function is declared ``AMBLE_HIDDEN`` and not static.
UNIT_BEGIN = "/* amble: own unit */\n"
UNIT_END = "/* amble: end of own unit */\n"


def split_units(src: str) -> tuple[str, str | None]:
    """``src`` without the functions marked by :data:`UNIT_BEGIN` … :data:`UNIT_END` (each left as
    its prototype), and the unit of those functions (``None`` if there are none)."""
    main, own, rest = [], [], src
    while (i := rest.find(UNIT_BEGIN)) >= 0:
        j = rest.find(UNIT_END, i)
        if j < 0:
            break
        fn = rest[i + len(UNIT_BEGIN):j]
        main += [rest[:i], fn[:fn.index("{")].rstrip() + ";\n"]
        own.append(fn)
        rest = rest[j + len(UNIT_END):]
    if not own:
        return src, None
    # the split-off functions read the same constants (NPARAM, the hoisted p[NPARAM + j], ...):
    # the unit starts with every top-level #include and #define that precedes them
    head = src[:src.find(UNIT_BEGIN)].splitlines(keepends=True)
    defines = "".join(ln for ln in head if ln.startswith(("#include", "#define")))
    return "".join(main) + rest, defines + "".join(own)


def run_compilers(cmds: list[list[str]], cc: str, what: str = "the generated model") -> None:
    """Run the compiler commands side by side (a machine's cores compile the units in parallel);
    a failure of any is a :class:`CompileError` with the compiler's first error lines (``what``:
    the code compiled, for the message)."""
    import subprocess  # here, not at import: a warm start compiles nothing

    try:
        procs = [subprocess.Popen(c, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for c in cmds]
    except OSError as e:
        raise CompileError(f"C compiler {cc!r} failed to run: {e}") from None
    results = []
    try:
        for pr in procs:
            results.append((pr, pr.communicate(timeout=600)[1]))
    except subprocess.TimeoutExpired as e:
        raise CompileError(f"C compiler {cc!r} failed to run: {e}") from None
    finally:
        for pr in procs:
            if pr.poll() is None:
                pr.kill()
                pr.wait()
    for pr, err in results:
        if pr.returncode != 0:
            lines = [ln.strip() for ln in err.splitlines() if ln.strip()]
            errors = [ln for ln in lines if "error" in ln.lower()] or lines
            said = "; ".join(errors[:3])[:500] if errors else "no output"
            raise CompileError(f"C compilation of {what} failed ({cc!r}, exit {pr.returncode}): {said}")
