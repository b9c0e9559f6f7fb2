"""Files of the compile cache: written so that no reader ever sees a partial one, and hashed.

Several processes may build and read one cache directory at once: a file is written under a
temporary name of this process and renamed into place (a rename within a directory is atomic), and
a library or runtime object is trusted only if its bytes have the SHA-256 recorded beside it.
"""

from __future__ import annotations

import os
from pathlib import Path

from .digest import sha256


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    return sha256(path.read_bytes()).hexdigest()


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file of this process and a rename."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)
