"""Visualisation: matplotlib plots, a 3D scene API (Sphere / Cylinder / Box / Ground) and an
offline browser animation."""

from .scene import Box, Cylinder, Ground, Sphere, default_look

__all__ = ["Box", "Cylinder", "Ground", "Sphere", "default_look"]
