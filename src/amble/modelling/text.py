"""Expressions written as text, read without running any code.

``sympy.sympify`` evaluates its input as Python: ``sympify("__import__('os').system(...)")``
runs the command. Text that reaches amble from outside a Python program (a command-line
objective, a guard written as ``"x > 0"``, a string in a model file or a JSON input) is therefore
never given to it. :func:`parse` splits it with Python's tokenizer (which only lexes) and reads
the tokens itself, building the sympy expression from a whitelist:

* names: the symbols the caller allows (a model's coordinates, velocities, parameters...), then
  the constants ``pi`` and ``E``; any other name is refused with the list of allowed ones;
* numbers: finite integer and decimal literals;
* operators: ``+ - * /``, powers written ``**`` or ``^`` (as in sympy and MATLAB);
* functions: :data:`FUNCTIONS` (``sin``, ``atan2``, ``sqrt``, ``Abs``, ``Min``...), called by
  name with positional arguments only;
* with ``condition=True`` also comparisons (``<``, ``<=``, ``>``, ``>=``, ``==``, ``!=``,
  chained as ``0 < x < 1``), ``Eq``/``Ne``, and ``&``, ``|``, ``~``, ``and``, ``or``, ``not``
  (which bind looser than comparisons: ``x > 0 & y < 1`` is ``(x > 0) & (y < 1)``).

Everything else — attributes, subscripts, strings, lambdas, keywords, calls of anything that
is not a listed function — is a one-line :class:`~amble.errors.ExpressionError`.
Sizes are bounded so that no text can exhaust the interpreter: at most :data:`MAX_LENGTH`
characters, :data:`MAX_DEPTH` levels of nesting (long flat sums and products are not nesting:
a 3000-term sum reads in milliseconds), integer powers of numbers with exponents up to
:data:`MAX_EXPONENT`.
"""

from __future__ import annotations

import ast
import io
import math
import tokenize
from collections.abc import Callable, Mapping
from typing import Any

import sympy as sp

from ..errors import ExpressionError

#: The functions text may call, by the names users write (sympy's and the common lowercase ones).
FUNCTIONS: dict[str, Callable[..., Any]] = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "asin": sp.asin, "acos": sp.acos, "atan": sp.atan,
    "atan2": sp.atan2, "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh, "exp": sp.exp, "log": sp.log,
    "sqrt": sp.sqrt, "Abs": sp.Abs, "abs": sp.Abs, "sign": sp.sign, "Min": sp.Min, "Max": sp.Max,
    "min": sp.Min, "max": sp.Max,
}
#: How many arguments each function takes (``Min``/``Max``: at least one).
_ARITY: dict[str, tuple[int, int]] = {**{k: (1, 1) for k in FUNCTIONS}, "atan2": (2, 2),
                                       **{k: (1, 64) for k in ("Min", "Max", "min", "max")}, "log": (1, 2)}
#: Named constants (a caller's symbol of the same name wins).
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "E": sp.E}
#: Comparison functions, allowed in conditions only.
_RELATIONS: dict[str, Callable[..., Any]] = {"Eq": sp.Eq, "Ne": sp.Ne}

#: The longest text read, in characters.
MAX_LENGTH = 100_000
#: The deepest nesting of calls, parentheses, unary operators and powers.
MAX_DEPTH = 100
#: The largest exponent of a power of a number (``10**10**10`` would never finish).
MAX_EXPONENT = 1000

_COMPARE: dict[str, Callable[[Any, Any], Any]] = {
    "<": sp.Lt, "<=": sp.Le, ">": sp.Gt, ">=": sp.Ge, "==": sp.Eq, "!=": sp.Ne,
}


def parse(text: str, names: Mapping[str, sp.Basic], *, what: str = "expression",
          condition: bool = False) -> Any:
    """``text`` as a sympy expression (or, with ``condition``, a sympy boolean) in ``names``.

    ``what`` starts every error message (``"objective"``, ``"guard of mode 'walk'"``). Raises
    :class:`~amble.errors.ExpressionError` (one line) for anything outside the whitelist of the
    module docstring; nothing in ``text`` is ever executed."""
    if not isinstance(text, str):
        raise ExpressionError(f"{what}: expected text, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"{what}: text of {len(text)} characters, more than the {MAX_LENGTH} read")
    if "\x00" in text:
        raise ExpressionError(f"{what}: text holds a NUL character")
    out = _Reader(names, what, condition, text).read_all()
    if not condition and not isinstance(out, sp.Expr):
        raise ExpressionError(f"{what}: {_shown(text)} is a condition, not an expression")
    if condition and (isinstance(out, sp.Expr) or not isinstance(out, sp.logic.boolalg.Boolean)):
        raise ExpressionError(f"{what}: {_shown(text)} is not a condition (a comparison such as 'x > 0')")
    if out.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ExpressionError(f"{what}: {_shown(text)} is not finite (a division by zero?)")
    return out


def expr_of(value: Any, names: Mapping[str, sp.Basic] | None = None, *, what: str = "expression",
            condition: bool = False) -> Any:
    """A value given to the modelling API as a sympy object: text through :func:`parse` (with
    ``names``; without them text is refused), numbers and sympy objects as they are.

    This is the one door by which values become expressions: unlike ``sympy.sympify`` it never
    evaluates text, and it refuses containers (whose strings ``sympify`` would evaluate)."""
    if isinstance(value, str):
        if names is None:
            raise ExpressionError(f"{what}: text {_shown(value)} is not read here; write it with the "
                                  "model's sympy symbols")
        return parse(value, names, what=what, condition=condition)
    if isinstance(value, (sp.Basic, sp.MatrixBase)):
        return value
    if isinstance(value, (list, tuple, set, dict)) or hasattr(value, "dtype") and getattr(value, "ndim", 0):
        raise ExpressionError(f"{what} must be one expression, got a {type(value).__name__}")
    try:
        return sp.sympify(value, strict=True)  # numbers (Python, NumPy) and objects defining _sympy_
    except (sp.SympifyError, TypeError, ValueError):
        raise ExpressionError(f"{what} must be an expression, got {type(value).__name__} {_shown(repr(value))}"
                              ) from None


def _small_power(base: sp.Expr, exponent: sp.Expr) -> bool:
    """Whether sympy may evaluate ``base**exponent`` of two numbers: it computes powers of
    rationals exactly, so ``(10**999)**999**...`` would run out of memory."""
    try:
        e = abs(complex(exponent))
    except (TypeError, ValueError):
        return True  # an undefined exponent (zoo, nan) is refused as not finite afterwards
    if e > MAX_EXPONENT:
        return False
    if isinstance(base, sp.Rational):
        return max(abs(base.p).bit_length(), base.q.bit_length()) * e <= 100_000
    return True


def _shown(text: str, most: int = 60) -> str:
    """Text quoted for a one-line message: shortened, control characters escaped."""
    t = text if len(text) <= most else text[: most - 3] + "..."
    return repr(t)


_BINARY = {"+", "-", "*", "/", "**", "^", "(", ")", ",", "<", "<=", ">", ">=", "==", "!=", "&", "|", "~"}
_WORDS = {"and", "or", "not"}


def _tokens(text: str, fail: Callable[[str], ExpressionError]) -> list[tuple[str, str]]:
    """``(kind, text)`` tokens, ``kind`` one of ``"number"``, ``"name"``, ``"op"``; anything else
    (strings, ``.``, ``[``, ``:``, ``@``...) is refused here, before any meaning is given."""
    out: list[tuple[str, str]] = []
    flat = " ".join(text.split())  # newlines and tabs are spaces: one logical line
    try:
        for tok in tokenize.generate_tokens(io.StringIO(flat).readline):
            if tok.type in (tokenize.NEWLINE, tokenize.NL, tokenize.ENDMARKER, tokenize.INDENT,
                            tokenize.DEDENT) or tok.string.isspace():
                continue
            if tok.type == tokenize.NUMBER:
                out.append(("number", tok.string))
            elif tok.type == tokenize.NAME:
                out.append(("op" if tok.string in _WORDS else "name", tok.string))
            elif tok.type == tokenize.OP and tok.string in _BINARY:
                out.append(("op", tok.string))
            elif tok.type == tokenize.STRING:
                raise fail("text literals (quotes) cannot be used in an expression")
            elif tok.type == tokenize.OP:
                raise fail(f"{tok.string!r} cannot be used in an expression")
            else:
                raise fail(f"cannot read {tok.string!r}")
    except ExpressionError:
        raise
    except (tokenize.TokenError, SyntaxError, ValueError) as e:
        raise fail(f"{e.args[0] if e.args else type(e).__name__}") from None
    return out


class _Reader:
    """A precedence-climbing reader of the token list (see the module docstring), building the
    sympy value as it goes. Runs of the same level (``a + b - c ...``, ``a * b / c ...``,
    ``p & q & ...``) are read by loops and built as one flat sympy node; only real nesting
    (parentheses, calls, unary operators, powers) recurses, bounded by :data:`MAX_DEPTH`.

    Precedence, loosest first: ``|``/``or``; ``&``/``and``; ``~``/``not``; comparisons; ``+ -``;
    ``* /``; unary ``- +``; ``** ^`` (right to left, so ``-x**2`` is ``-(x**2)``). Unlike Python,
    ``&`` and ``|`` bind looser than comparisons, as in C and MATLAB: ``x > 0 & y < 1`` means
    ``(x > 0) & (y < 1)``."""

    def __init__(self, names: Mapping[str, sp.Basic], what: str, condition: bool, text: str) -> None:
        self.names, self.what, self.condition, self.text = names, what, condition, text
        self.toks: list[tuple[str, str]] = []
        self.i = 0

    def fail(self, why: str) -> ExpressionError:
        return ExpressionError(f"{self.what}: cannot read {_shown(self.text)}: {why}")

    def read_all(self) -> Any:
        self.toks = _tokens(self.text, self.fail)
        if not self.toks:
            raise self.fail("empty")
        out = self.disjunction(0)
        if self.i < len(self.toks):
            raise self.fail(f"unexpected {self.toks[self.i][1]!r}")
        return out

    # -- tokens
    def peek(self) -> str | None:
        return self.toks[self.i][1] if self.i < len(self.toks) and self.toks[self.i][0] == "op" else None

    def take(self, *ops: str) -> str | None:
        op = self.peek()
        if op in ops:
            self.i += 1
            return op
        return None

    def expect(self, op: str) -> None:
        if self.take(op) is None:
            got = repr(self.toks[self.i][1]) if self.i < len(self.toks) else "the end"
            raise self.fail(f"expected {op!r}, found {got}")

    # -- conditions
    def disjunction(self, depth: int) -> Any:
        parts = [self.conjunction(depth)]
        while self.take("|", "or"):
            parts.append(self.conjunction(depth))
        return parts[0] if len(parts) == 1 else sp.Or(*map(self.boolean, parts))

    def conjunction(self, depth: int) -> Any:
        parts = [self.negation(depth)]
        while self.take("&", "and"):
            parts.append(self.negation(depth))
        return parts[0] if len(parts) == 1 else sp.And(*map(self.boolean, parts))

    def negation(self, depth: int) -> Any:
        if self.take("~", "not"):
            self.deeper(depth)
            return sp.Not(self.boolean(self.negation(depth + 1)))
        return self.comparison(depth)

    def comparison(self, depth: int) -> Any:
        sides, ops = [self.sum(depth)], []
        while (op := self.take(*_COMPARE)) is not None:
            ops.append(op)
            sides.append(self.sum(depth))
        if not ops:
            return sides[0]
        if not self.condition:
            raise self.fail("comparisons belong in conditions")
        return sp.And(*[_COMPARE[op](self.number(a), self.number(b)) for op, a, b in zip(ops, sides, sides[1:])])

    def boolean(self, v: Any) -> Any:
        if not self.condition:
            raise self.fail("'&', '|', '~', 'and', 'or', 'not' belong in conditions")
        if isinstance(v, sp.Expr) or not isinstance(v, sp.logic.boolalg.Boolean):
            raise self.fail("'&', '|', '~', 'and', 'or', 'not' join comparisons, not numbers")
        return v

    # -- arithmetic
    def sum(self, depth: int) -> Any:
        terms = [self.product(depth)]
        while (op := self.take("+", "-")) is not None:
            t = self.number(self.product(depth))
            terms.append(-t if op == "-" else t)
        return terms[0] if len(terms) == 1 else sp.Add(*map(self.number, terms))

    def product(self, depth: int) -> Any:
        factors = [self.unary(depth)]
        while (op := self.take("*", "/")) is not None:
            f = self.number(self.unary(depth))
            factors.append(1 / f if op == "/" else f)
        return factors[0] if len(factors) == 1 else sp.Mul(*map(self.number, factors))

    def unary(self, depth: int) -> Any:
        if (op := self.take("-", "+")) is not None:
            self.deeper(depth)
            v = self.number(self.unary(depth + 1))
            return -v if op == "-" else v
        return self.power(depth)

    def power(self, depth: int) -> Any:
        base = self.atom(depth)
        if self.take("**", "^") is None:
            return base
        self.deeper(depth)
        base, exponent = self.number(base), self.number(self.unary(depth + 1))
        if base.is_number and exponent.is_number and not _small_power(base, exponent):
            raise self.fail(f"a power of a number too large to compute (exponents up to {MAX_EXPONENT}, "
                            "results up to 100000 bits)")
        return sp.Pow(base, exponent)

    def number(self, v: Any) -> sp.Expr:
        if not isinstance(v, sp.Expr):
            raise self.fail("a condition cannot be used as a number")
        return v

    def deeper(self, depth: int) -> None:
        if depth + 1 > MAX_DEPTH:
            raise self.fail(f"nested more than {MAX_DEPTH} levels deep")

    # -- atoms
    def atom(self, depth: int) -> Any:
        if self.i >= len(self.toks):
            raise self.fail("ends too early")
        kind, tok = self.toks[self.i]
        self.i += 1
        if kind == "number":
            return self.literal(tok)
        if kind == "name":
            if self.peek() == "(":
                return self.call(tok, depth)
            return self.name(tok)
        if tok == "(":
            self.deeper(depth)
            v = self.disjunction(depth + 1)
            self.expect(")")
            return v
        raise self.fail(f"unexpected {tok!r}")

    def literal(self, tok: str) -> sp.Expr:
        try:
            v = ast.literal_eval(tok)  # one number token: literal_eval of it evaluates nothing else
        except (ValueError, SyntaxError) as e:
            raise self.fail(f"cannot read the number {_shown(tok, 20)} ({e.args[0] if e.args else e})") from None
        if isinstance(v, complex):
            raise self.fail("complex numbers cannot be used")
        if isinstance(v, float) and not math.isfinite(v):
            raise self.fail("a number too large to be finite")
        return sp.Integer(v) if isinstance(v, int) else sp.Float(v)

    def name(self, tok: str) -> sp.Basic:
        if tok in self.names:
            return self.names[tok]
        if tok in CONSTANTS:
            return CONSTANTS[tok]
        if tok in FUNCTIONS or tok in _RELATIONS:
            raise self.fail(f"{tok} is a function: call it as {tok}(...)")
        allowed = [*self.names, *CONSTANTS]
        shown = ", ".join(allowed[:40]) + (", ..." if len(allowed) > 40 else "")
        raise self.fail(f"unknown name {tok!r} (allowed: {shown})")

    def call(self, fname: str, depth: int) -> Any:
        table = {**FUNCTIONS, **(_RELATIONS if self.condition else {})}
        if fname not in table or fname in self.names:
            raise self.fail(f"{fname!r} is not a function that can be called (functions: {', '.join(FUNCTIONS)})")
        self.deeper(depth)
        self.expect("(")
        args: list[sp.Expr] = []
        if self.take(")") is None:
            while True:
                args.append(self.number(self.disjunction(depth + 1)))
                if self.take(")") is not None:
                    break
                self.expect(",")
        lo, hi = _ARITY.get(fname, (2, 2))
        if not lo <= len(args) <= hi:
            raise self.fail(f"{fname}() takes {lo if lo == hi else f'{lo} to {hi}'} argument(s), got {len(args)}")
        return table[fname](*args)


__all__ = ["CONSTANTS", "FUNCTIONS", "MAX_DEPTH", "MAX_EXPONENT", "MAX_LENGTH", "expr_of", "parse"]
