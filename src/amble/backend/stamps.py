"""A content hash of files, reused while the files' status says they are unchanged.

The warm-start index (:mod:`amble.backend.index`) keys its entries by a hash of some 70 source
files (about half a megabyte): hashing them is a few milliseconds of every warm start. A stamp,
``stamp-<id>.json`` in the cache directory, records the digest with each file's size, mtime,
ctime, inode and device; while all of these are unchanged the digest is taken from the stamp.

Why that is safe: every write to a file sets its ctime to the current time, and ctime cannot be
set back (``touch -d`` and ``os.utime`` set mtime, and update ctime); replacing a file changes
its inode. The one gap is a file written twice within one tick of a coarse file-system clock
(one or two seconds on some file systems): a stamp is therefore written only when every file's
mtime and ctime are at least :data:`RACY_NS` older than the moment the stamp's status was taken,
so a later write lands in a later tick (the "racily clean" rule of Git's index). A stamp that
cannot be read, or whose status differs in anything, makes the digest computed afresh (and the
stamp rewritten).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from .digest import sha256

#: A file's status counts as settled this long (ns) after its last change: above the 2 s tick of
#: the coarsest file-system clock in use (FAT).
RACY_NS = 3_000_000_000


def _status(f: Path) -> list[int]:
    st = os.stat(f)
    return [st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev]


def stamped_digest(d: Path, ident: str, files: Sequence[Path], compute: Callable[[], str]) -> str:
    """``compute()`` (a digest of ``files`` and of whatever ``ident`` names), or the digest a stamp
    in directory ``d`` recorded for ``ident`` while every file's status is unchanged (see the
    module docstring). :class:`OSError` if a file cannot be read, as ``compute`` would raise."""
    now = time.time_ns()  # before the status is taken: a change after it is never older than this
    status = [_status(f) for f in files]
    path = d / f"stamp-{sha256(ident.encode()).hexdigest()[:32]}.json"
    try:
        rec = json.loads(path.read_text())
        if rec["ident"] == ident and rec["status"] == status and isinstance(rec["digest"], str):
            return rec["digest"]
    except (OSError, ValueError, KeyError, TypeError):
        pass  # no stamp yet, or one of another content: computed below
    digest = compute()
    if all(max(s[1], s[2]) <= now - RACY_NS for s in status):
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            tmp.write_text(json.dumps({"ident": ident, "status": status, "digest": digest}))
            os.replace(tmp, path)
        except OSError:  # a stamp is an optimisation: without it the digest is computed next time
            pass
    return digest
