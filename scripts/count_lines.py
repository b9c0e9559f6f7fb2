"""Lines of code of each model module beside the thesis' Table 5 (Acumen 72, MATLAB 400 for the
compass gait). Counts non-blank lines that are neither comments nor docstrings.

Run from the repository root: ``python scripts/count_lines.py``.
"""

import ast
import io
import tokenize
from pathlib import Path

MODELS = Path("src/amble/models")
THESIS = {"compass_gait": "Acumen 72, MATLAB 400"}


def code_lines(path: Path) -> int:
    src = path.read_text()
    doc_lines: set[int] = set()
    for node in ast.walk(ast.parse(src)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(getattr(body[0], "value", None), ast.Constant) and isinstance(body[0].value.value, str):
            doc_lines.update(range(body[0].lineno, body[0].end_lineno + 1))
    lines: set[int] = set()
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type not in (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
                            tokenize.ENDMARKER):
            lines.update(range(tok.start[0], tok.end[0] + 1))
    return len(lines - doc_lines)


def main() -> None:
    print(f"{'module':<18} {'lines':>5}  thesis (Table 5)")
    for f in sorted(MODELS.glob("*.py")):
        if f.name != "__init__.py":
            print(f"{f.stem:<18} {code_lines(f):>5}  {THESIS.get(f.stem, '')}")


if __name__ == "__main__":
    main()
