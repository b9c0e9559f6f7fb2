"""The ``amble`` command line: a thin layer where every command is one API call plus I/O."""

from .main import main

__all__ = ["main"]
