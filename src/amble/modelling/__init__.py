"""Modelling: what one writes on paper — coordinates, parameters, points, masses, energies, forces
(:mod:`.model`, with the vector helpers of :mod:`.geometry`), hybrid systems of modes, guards and
resets (:mod:`.hybrid`), and walkers on a slope (:mod:`.walker`). Everything here is a
declaration; nothing is derived or compiled."""
