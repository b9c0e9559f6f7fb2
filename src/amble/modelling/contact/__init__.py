"""Contact: where a body meets the ground — its geometry, its impact, its force.

Every kind of contact has its declaration here, one module each, written with the modelling
API only; what must be derived from the equations of motion lives in
:mod:`amble.derivation.contact`, and what the compiled loop does at a contact (coming to rest,
lifting off) in ``backend/_c/rest.h``.

* :mod:`.ground` — the ground plane of a walker (normal, downhill direction, height of a point);
* :mod:`.footfall` — a foot striking the ground plastically: the footfall guard and impact;
* :mod:`.round_foot` — round feet that roll without slip, and the material point of their impact;
* :mod:`.compliant` — compliant ground: a Hunt–Crossley force on a point that sinks into it;
* :mod:`.reaction` — the force and impulse the ground must supply, from the total momentum;
* :mod:`amble.derivation.contact` — unilateral contact with restitution, its resting mode, its
  contact force and lift-off.

A new contact model (several contacts at once, friction, another force law) is a new module
here that declares its points, guards, resets and forces on a :class:`~amble.modelling.model.Model`
or :class:`~amble.modelling.hybrid.HybridSystem`.
"""

from .compliant import compliant_contact
from .footfall import STEP_MARGIN, heel_strike, model_size
from .ground import distance_along_slope, height_above_slope, slope_downhill, slope_normal
from .reaction import accelerations, ground_force, linear_momentum, mass_moment, total_mass
from .round_foot import RoundFoot, rolling_centre, round_foot

__all__ = ["STEP_MARGIN", "RoundFoot", "accelerations", "compliant_contact", "distance_along_slope",
           "ground_force", "heel_strike", "height_above_slope", "linear_momentum", "mass_moment", "model_size",
           "rolling_centre", "round_foot", "slope_downhill", "slope_normal", "total_mass"]
