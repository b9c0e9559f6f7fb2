# the collocated periodic step is the fixed-point search's last resort; it registers itself
# (amble.analysis.global_starts) so that the search does not import the optimiser that imports it
from . import collocation_guess as _collocation_guess  # noqa: F401
