"""The ``amble`` command line: every command is one API call plus input/output.

Exit codes: 0 success, 2 user error (bad model name, parameter, range, path, a full disk...),
1 internal failure or a solver that did not succeed (``SolverError``), 130 interrupted, 141
standard output closed by its reader (``| head -1``; quiet, as a Unix tool ended by SIGPIPE).
Errors are one line on stderr, or ``{"error": ...}`` on stdout with ``--json``; warnings are one
line on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from ..analysis.defaults import BASIN_STEPS, RESIDUAL_TOL, SWEEP_TOL
from ..errors import AmbleError, SolverError
from .args import _Parser
from .cache import add_parser as add_cache_parser
from .doublings import EXAMPLE as DOUBLINGS_EXAMPLE
from .doublings import add_parser as add_doublings_parser
from .gait import add_parser as add_gait_parser
from .gaits import EXAMPLE as GAITS_EXAMPLE
from .gaits import add_parser as add_gaits_parser
from .limit_cycle import EXAMPLE as LIMIT_CYCLE_EXAMPLE
from .limit_cycle import add_parser as add_limit_cycle_parser
from .limit_cycle import cmd_limit_cycle as cmd_limit_cycle  # re-exported: the command's old home
from .mfpt import EXAMPLE as MFPT_EXAMPLE
from .mfpt import add_parser as add_mfpt_parser
from .mujoco import EXAMPLE as MUJOCO_EXAMPLE
from .mujoco import add_parser as add_mujoco_parser
from .prefetch import prefetch_plotting
from .robustness import EXAMPLE as ROBUSTNESS_EXAMPLE
from .robustness import add_parser as add_robustness_parser
from .simulate import EXAMPLE as SIMULATE_EXAMPLE
from .simulate import add_parser as add_simulate_parser
from .simulate import cmd_simulate as cmd_simulate  # re-exported: the command's old home

MODEL_HELP = ("a library model (see 'amble models'), a model file path/to/file.py[:callable]: the callable, "
              "else the file's build(), else the one HybridSystem it defines, or a robot file path/to/robot.urdf "
              "(floating base, or --fixed-base) or MuJoCo's path/to/robot.xml (as the file says, or --fixed-base)")

# ---------------------------------------------------------------------- commands
def _plain(doc: str | None) -> str:
    """The first line of a docstring without reStructuredText markup (````w```` → ``w``, roles)."""
    import re

    line = (doc or "").strip().splitlines()[0] if (doc or "").strip() else ""
    line = re.sub(r":[a-z]+:`~?([^`]*)`", r"\1", line)
    return re.sub(r"``([^`]*)``", r"\1", line)


def cmd_models(args: argparse.Namespace) -> dict[str, Any]:
    from ..models import load, names

    rows = []
    for name in names():
        s = load(name)
        first = s.mode_names[0]
        rows.append({"name": name, "dims": s.dims, "modes": s.mode_names, "state_names": s.state_names(first),
                     "parameters": s.parameters, "summary": _plain(s.doc)})
    if not args.json:
        width = max((len(r["name"]) for r in rows), default=0)  # the longest name sets the column
        for r in rows:
            n = len(r["state_names"]) // 2
            count = f"{n} coordinate{'' if n == 1 else 's'}"
            print(f"{r['name']:<{width}}  {r['dims']}D  {count:<14} {r['summary']}")
    return {"models": rows}


def cmd_equations(args: argparse.Namespace) -> dict[str, Any]:
    from .equations import cmd_equations as run  # SymPy's printers: only for this command

    return run(args)


def cmd_sweep(args: argparse.Namespace) -> dict[str, Any]:
    # options are checked (UsageError, exit 2) in sweep_cli before any file is touched or work starts
    from .sweep import sweep_cli

    return sweep_cli(args)


# ---------------------------------------------------------------------- parser
EXAMPLES = {
    "models": "amble models --json",
    "equations": "amble equations compass-gait --latex",
    "simulate": SIMULATE_EXAMPLE,
    "limit-cycle": LIMIT_CYCLE_EXAMPLE,
    "sweep": "amble sweep compass-gait --param slope=0.01:0.08:50 --out sweep.csv --plot branch.png",
    "optimize-gait": "amble optimize-gait compass-gait --set slope=0.0524 --out gait.json",
    "gaits": GAITS_EXAMPLE,
    "doublings": DOUBLINGS_EXAMPLE,
    "mfpt": MFPT_EXAMPLE,
    "robustness": ROBUSTNESS_EXAMPLE,
    "mujoco": MUJOCO_EXAMPLE,
    "cache": "amble cache clear --older-than 30 --dry-run",
}


class _HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """argparse's raw-description formatter, measuring the terminal only when it lays out text.

    argparse makes a formatter for every ``add_argument`` (to check the metavar) and each one asks
    ``shutil.get_terminal_size()`` for the width at once: importing :mod:`shutil` (and with it
    ``bz2``, ``lzma``, ``zlib``) costs a warm start ~2 ms for a width nobody reads. Here the widths
    are those argparse's own formatter computes (same arguments), worked out on first use."""

    def __init__(self, prog: str, indent_increment: int = 2, max_help_position: int = 24,
                 width: int | None = None) -> None:
        self._asked, self._sizes = (indent_increment, max_help_position, width), None
        super().__init__(prog, indent_increment, max_help_position, width=80)  # 80: ignored (below)

    def _measure(self) -> tuple[int, int]:
        if self._sizes is None:
            real = argparse.RawDescriptionHelpFormatter(self._prog, *self._asked)
            self._sizes = (real._width, real._max_help_position)
        return self._sizes

    # argparse's __init__ assigns both; the assignments are dropped for the measured values
    _width = property(lambda self: self._measure()[0], lambda self, value: None)
    _max_help_position = property(lambda self: self._measure()[1], lambda self, value: None)


class _Unused:
    """Stands in for the parser of a command that is not being run: every call is accepted and
    does nothing (building every command's parser costs more than a warm limit cycle's search)."""

    def __getattr__(self, name: str) -> Any:
        return lambda *a, **k: self


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command-line parser; ``only``: build that command's sub-parser alone (the one being run)."""
    p = _Parser(prog="amble", description="Equation-based modeling and simulation of walking robots.",
                formatter_class=_HelpFormatter,
                epilog="examples:\n  " + "\n  ".join(EXAMPLES.values()))
    p.add_argument("--version", action="version", version=f"amble {_version()}")
    sub = p.add_subparsers(dest="command", parser_class=_Parser, required=True)

    def add(name: str, help_: str) -> argparse.ArgumentParser:
        if only is not None and name != only:
            return _Unused()  # type: ignore[return-value]
        sp = sub.add_parser(name, help=help_, description=help_, epilog=f"example:\n  {EXAMPLES[name]}",
                            formatter_class=_HelpFormatter)
        sp.add_argument("--json", action="store_true", help="print a JSON object on stdout")
        return sp

    def robot_args(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("--base", metavar="LINK", help="a robot file: the base link (default: the file's root link)")
        sp.add_argument("--fixed-base", action="store_true",
                        help="a robot file: the base link fixed to the world (default: floating, six coordinates)")

    def model_args(sp: argparse.ArgumentParser, tol: float | None) -> None:
        """``tol=None``: the tolerances default to the API's default of the chosen kind."""
        sp.add_argument("model", help=MODEL_HELP)
        robot_args(sp)
        sp.add_argument("--set", action="append", metavar="NAME=VALUE", help="override a parameter (repeatable)")
        said = (f"{tol:g}" if tol is not None else
                "the kind's: " + ", ".join(f"{kind} {v:g}" for kind, v in SWEEP_TOL.items()))
        sp.add_argument("--rtol", type=float, default=tol, help=f"relative tolerance (default {said})")
        sp.add_argument("--atol", type=float, default=tol, help=f"absolute tolerance (default {said})")

    add("models", "list the model library").set_defaults(func=cmd_models)
    e = add("equations", "show the derived equations of motion, and the guards and derived impact and lock maps "
                        "of the transitions")
    e.add_argument("model", help=MODEL_HELP)
    robot_args(e)
    e.add_argument("--latex", action="store_true",
                   help="LaTeX instead of plain text (with --json: LaTeX fields beside the plain ones)")
    e.add_argument("--standalone", action="store_true",
                   help="a whole LaTeX document (implies --latex; with --json: the field 'document')")
    e.set_defaults(func=cmd_equations)
    add_simulate_parser(add, model_args)
    add_limit_cycle_parser(add, model_args)
    sw = add("sweep", "parameter sweep (fixed points, continuation, bifurcation diagram) or basin of attraction, "
                      "on local worker processes or Dask")
    model_args(sw, None)
    sw.add_argument("--kind", choices=("fixed-point", "continuation", "bifurcation", "basin"), default="fixed-point",
                    help="the fixed point on a grid of parameter values (default), pseudo-arclength "
                         "continuation with folds, period doublings and the period-doubled branches "
                         "(continuation), post-transient iterates (bifurcation), or which initial "
                         "post-impact states walk into the gait (basin)")
    sw.add_argument("--param", action="append", metavar="NAME=START:STOP:COUNT",
                    help="swept parameter: give one for a branch or bifurcation diagram, two for a 2D map "
                         "(fixed-point and bifurcation kinds); --kind continuation: NAME=START:STOP[:STEPS], "
                         "STEPS (default 50) bounding the parameter change per step by |STOP-START|/STEPS")
    sw.add_argument("--x", action="append", metavar="NAME=START:STOP:COUNT",
                    help="--kind basin: a coordinate of the initial post-impact state, give exactly two "
                         "(e.g. --x stance=-0.4:0:100 --x stance_dot=0.5:1.6:100); the other coordinates "
                         "come from the fixed point, the dependent ones from the post-impact section")
    sw.add_argument("--tol", type=float, default=None,
                    help=f"--kind fixed-point or continuation: the fixed-point tolerance, the largest residual "
                         f"|P(x) - x| of each gait (default {RESIDUAL_TOL:g})")
    sw.add_argument("--steps", type=int, default=None,
                    help=f"--kind basin: footfalls walked from each initial state at most (default {BASIN_STEPS})")
    sw.add_argument("--out", help="result file FILE.csv|.parquet (resumed if it exists)")
    sw.add_argument("--plot", help="write a plot FILE.png|.svg|.pdf")
    sw.add_argument("--scheduler",
                    help="where the tasks run (default: local worker processes forked from this one, "
                         "without Dask): 'synchronous' in this process (small runs, debugging); 'dask' a "
                         "local Dask cluster; or the address of an existing Dask scheduler, e.g. "
                         "tcp://host:8786")
    sw.add_argument("--workers", type=int, default=None,
                    help="local worker processes, or a local Dask cluster's (default: cores)")
    sw.add_argument("--threads", type=int, default=None,
                    help="--kind basin: threads per process — with --scheduler synchronous, tasks run side by "
                         "side on this many threads of this process; on Dask, each task's walks share them "
                         "(default 1)")
    sw.set_defaults(func=cmd_sweep)

    def model_arg(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("model", help=MODEL_HELP)
        sp.add_argument("--set", action="append", metavar="NAME=VALUE", help="override a parameter (repeatable)")

    add_gait_parser(add, model_arg)
    add_gaits_parser(add, model_arg)
    add_doublings_parser(add, model_arg)
    add_mfpt_parser(add, model_arg)
    add_robustness_parser(add, model_arg)
    add_mujoco_parser(add, model_arg)
    add_cache_parser(add)
    return p


def _version() -> str:
    from ..version import __version__

    return __version__


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            return _main(argv)
        except BrokenPipeError:
            # the reader went away (``amble models | head -1``), perhaps while an error was being
            # reported: stop quietly, as Unix tools do when SIGPIPE ends them, and keep Python from
            # complaining again when it flushes standard output at exit
            _quiet_stdout()
            return 141


def _main(argv: list[str]) -> int:
    want_json = "--json" in argv
    try:
        # only the command named first is built (--help, --version and mistakes get the whole parser)
        first = argv[0] if argv and argv[0] in EXAMPLES and not {"-h", "--help"} & set(argv) else None
        args = build_parser(first).parse_args(argv)
        # only for commands that start no worker processes: a fork while a thread holds an import
        # lock could leave the child waiting on it
        plotting = prefetch_plotting() if getattr(args, "plots_in_process", False) and args.plot else None
        try:
            result = args.func(args)
        finally:
            if plotting is not None:  # not cut short at exit
                plotting.join()
        if args.json:
            print(json.dumps(result, default=_jsonable))
        sys.stdout.flush()  # a closed pipe is found here, not at interpreter exit
        return 0
    except BrokenPipeError:
        raise  # handled in main()
    except SolverError as e:  # the numbers did not work out (not a user error): one line, exit 1
        if want_json:
            print(json.dumps({"error": str(e), "type": type(e).__name__}))
        print(f"amble: {e}", file=sys.stderr)
        return 1
    except AmbleError as e:
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        if want_json:
            print(json.dumps({"error": msg, "type": type(e).__name__}))
        print(f"amble: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("amble: interrupted", file=sys.stderr)
        return 130
    except SystemExit as e:  # --help / --version
        return int(e.code or 0)
    except Exception as e:  # an internal failure: say so in one line, keep exit code 1
        if want_json:
            print(json.dumps({"error": f"internal error: {type(e).__name__}: {e}", "type": "InternalError"}))
        print(f"amble: internal error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1


def _quiet_stdout() -> None:
    """Point standard output at ``/dev/null`` (the pipe it wrote to is closed)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # stdout replaced by an object without a descriptor
        pass


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                      file: Any = None, line: str | None = None) -> None:
    """A warning as one line on standard error (no source file and line of amble's code)."""
    text = str(message).splitlines()[0] if str(message) else category.__name__
    try:
        print(f"amble: warning: {text.removeprefix('amble: ')}", file=sys.stderr)
    except OSError:
        pass


def _jsonable(o: Any) -> Any:
    import numpy as np

    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, complex):
        return [o.real, o.imag]
    return str(o)


if __name__ == "__main__":
    sys.exit(main())
