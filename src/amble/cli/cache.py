"""``amble cache info|list|clear``: see and clear the compile cache (:mod:`amble.backend.cache_admin`,
:mod:`amble.backend.cache_clear`). Each action is one API call plus its printing."""

from __future__ import annotations

import argparse
import math
import os
from typing import Any

from .args import UsageError, _float

EXAMPLES = {
    "info": "amble cache info --json",
    "list": "amble cache list",
    "clear": "amble cache clear --model compass-gait --dry-run",
}


def add_parser(add: Any) -> None:
    """Register ``cache`` with the parser (``add(name, help)`` makes a subparser)."""
    c = add("cache", "see and clear the compile cache: the compiled model libraries and the shared runtime objects")
    c.epilog = "examples:\n  " + "\n  ".join(EXAMPLES.values())  # one per action
    sub = c.add_subparsers(dest="action", metavar="ACTION", required=True, parser_class=type(c),
                           help="info, list or clear")

    def action(name: str, help_: str) -> argparse.ArgumentParser:
        sp = sub.add_parser(name, help=help_, description=help_, epilog=f"example:\n  {EXAMPLES[name]}",
                            formatter_class=c.formatter_class)
        # SUPPRESS: '--json' given before the action (amble cache --json list) is not reset here
        sp.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print a JSON object on stdout")
        return sp

    action("info", "the cache directory, its entries counted, their size, and the compiler and flags "
                   "a build uses").set_defaults(func=cmd_info)
    action("list", "one row per compiled model library and per runtime object").set_defaults(func=cmd_list)
    clear = action("clear", "remove compiled libraries (with their index entries) and, with --all or "
                            "--older-than, runtime objects; files of a build in progress are kept, and only "
                            "amble's own files are ever removed (a directory without amble's CACHEDIR.TAG is refused)")
    which = clear.add_mutually_exclusive_group(required=True)
    which.add_argument("--all", action="store_true", dest="everything", help="every entry")
    which.add_argument("--older-than", metavar="DAYS", dest="older_than",
                       help="libraries and runtime objects last used more than DAYS days ago")
    which.add_argument("--model", metavar="NAME",
                       help="the libraries of one model: its name in 'amble cache list', or its MODEL spec")
    clear.add_argument("--dry-run", action="store_true", dest="dry_run", help="remove nothing; show what would go")
    clear.set_defaults(func=cmd_clear)


def size(n: int) -> str:
    """Bytes in decimal units (``1.5 MB``)."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} B"


def _when(iso: str) -> str:
    return iso.replace("T", " ").removesuffix("Z")[:16] + " UTC"


def cmd_info(args: argparse.Namespace) -> dict[str, Any]:
    from ..backend.cache_admin import info

    out = info()
    if not args.json:
        cc = out["compiler"]
        said = f"{cc['command']} ({cc['version']})" if cc["command"] else f"none ({cc['error']})"
        lines = [("directory", out["directory"] + ("" if out["usable"] else f" — not usable: {out['reason']}")),
                 ("model libraries", out["models"]), ("runtime objects", out["runtimes"]),
                 ("index entries", out["index_entries"]), ("builds in progress", out["builds_in_progress"]),
                 ("total size", f"{size(out['bytes'])} ({out['bytes']} bytes)"), ("compiler", said),
                 ("flags", " ".join(out["cflags"]) + ("  ($AMBLE_CFLAGS)" if "AMBLE_CFLAGS" in os.environ
                                                       else "  (default: code for this processor)"))]
        for k, v in lines:
            print(f"{k + ':':<20}{v}")
    return out


def cmd_list(args: argparse.Namespace) -> dict[str, Any]:
    from ..backend.cache_admin import scan

    c = scan()
    models = sorted(c.models, key=lambda e: (e.name or "", -e.last_used))
    out = {"directory": str(c.directory), "models": [e.to_json() for e in models],
           "runtimes": [e.to_json() for e in sorted(c.runtimes, key=lambda e: e.capacity or 0)]}
    if not args.json:
        print(f"cache {c.directory}")
        rows = [(r["name"] or "(not recorded)", r["key"], {True: "yes", False: "no", None: "?"}[r["derivatives"]],
                 size(r["bytes"]), _when(r["last_used"])) for r in out["models"]]
        rows += [(f"runtime, capacity {r['capacity'] or '?'}", r["key"], "", size(r["bytes"]), _when(r["last_used"]))
                 for r in out["runtimes"]]
        if not rows:
            print("no compiled models")
        head = ("model", "key", "derivatives", "size", "last used")
        widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(5)]
        for r in [head, *rows] if rows else []:
            print("  ".join(f"{v:>{w}}" if i == 3 else f"{v:<{w}}" for i, (v, w) in enumerate(zip(r, widths))).rstrip())
    return out


def cmd_clear(args: argparse.Namespace) -> dict[str, Any]:
    from ..backend.cache_clear import clear

    days = None
    if args.older_than is not None:
        days = _float(args.older_than, "--older-than")
        if days < 0 or not math.isfinite(days):
            raise UsageError(f"--older-than must be a number of days, at least 0, got {args.older_than!r}")
    r = clear(everything=args.everything, older_than=days, model=args.model, dry_run=args.dry_run)
    out = r.to_json()
    if not args.json:
        verb = "would remove" if r.dry_run else "removed"
        for e in r.removed:
            what = {"model": f"{e.name or '(not recorded)'} {e.key}" + (" (derivatives)" if e.derivatives else ""),
                    "runtime": f"runtime object {e.key} (capacity {e.capacity or '?'})",
                    "index": f"index entry of {e.name or '(unreadable)'}"}.get(e.kind, f"{e.kind} {e.key}")
            print(f"{verb} {what}: {len(e.files)} file{'s' * (len(e.files) != 1)}, {size(e.bytes)}")
        for path, why in r.kept:
            print(f"kept {path.name}: {why}")
        freed = f"{size(r.bytes_freed)} ({r.bytes_freed} bytes) in {r.files_removed} files"
        print(f"dry run: nothing removed; would free {freed}" if r.dry_run else f"freed {freed}")
    return out
