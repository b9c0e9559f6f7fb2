"""Modelling: what one writes on paper — coordinates, parameters, points, masses, energies, forces
(:mod:`.model`, with the vector helpers of :mod:`.geometry`), hybrid systems of modes, guards and
resets (:mod:`.hybrid`), walkers on a slope (:mod:`.walker`) and
round feet rolling on it (:mod:`.contact`). Everything here is a
declaration; nothing is derived or compiled."""
