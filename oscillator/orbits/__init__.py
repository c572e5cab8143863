"""Periodic orbits: shooting on the stroboscopic map, Floquet multipliers through every switch
(variational equations and saltation matrices), and continuation in a parameter
(docs/orbits.md)."""
