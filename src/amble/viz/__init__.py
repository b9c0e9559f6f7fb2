"""Visualisation: matplotlib plots, a 3D scene API (Sphere / Cylinder / Box / Ground / Mesh), an
offline browser animation, and rich display in notebooks."""

from .animate import animate
from .notebook import register as _register_notebook
from .plot import plot_limit_cycle, plot_trajectory
from .scene import Box, Cylinder, Ground, Mesh, Sphere, default_look

_register_notebook()

__all__ = ["Box", "Cylinder", "Ground", "Mesh", "Sphere", "animate", "default_look", "plot_limit_cycle",
           "plot_trajectory"]
