"""Errors the visualisation raises on purpose (the command-line tool reports them as user errors)."""

from __future__ import annotations

from ..errors import AmbleError

__all__ = ["ExportError", "SceneError", "VizError"]


class VizError(AmbleError, ValueError):
    """A plot or animation cannot be made from what was asked: e.g. an unknown file format."""


class SceneError(VizError):
    """A shape, a scene or the data for a scene is not acceptable: bad radius, unknown point, ..."""


class ExportError(AmbleError, RuntimeError):
    """An animation could not be written because a tool it needs is missing or failed (e.g. ffmpeg)."""
