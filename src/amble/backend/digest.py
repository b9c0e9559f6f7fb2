"""SHA-256 without OpenSSL's start-up: the interpreter's own implementation when it has one.

``hashlib.sha256`` is OpenSSL's (``_hashlib``), whose import initialises the OpenSSL library —
a few milliseconds of a warm start that hashes well under a megabyte (the index lookup and the
library check of :mod:`amble.backend.index`). CPython's built-in SHA-256 (``_sha2`` from 3.12,
``_sha256`` before; the module ``hashlib`` itself falls back to) gives the same digests and
imports in microseconds. An interpreter built without it uses ``hashlib``.
"""

from __future__ import annotations

try:  # the same digests as hashlib.sha256: only the implementation differs
    from _sha2 import sha256  # type: ignore[import-not-found]  # CPython ≥ 3.12
except ImportError:
    try:
        from _sha256 import sha256  # type: ignore[import-not-found,no-redef]  # CPython ≤ 3.11
    except ImportError:
        from hashlib import sha256  # type: ignore[assignment]  # built without the builtin hashes

__all__ = ["sha256"]
