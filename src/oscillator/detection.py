"""Root functions that CVODE watches in each mode (detection, not decision).

One fixed layout serves every mode; a root that does not apply to the mode is held at the
constant 1 and never fires.  Directions are set per mode so that only the crossing that means a
switch is reported (a root sitting at zero just after a restart is thus not reported again).

=====  =====================================  ==================================  =========
index  root function                          active when                         direction
=====  =====================================  ==================================  =========
0      ``v1`` (velocity boundary)             m1 moves with sign s1               ``-s1``
1      ``G^(0) = F1^(delta1)`` (grazing)      m1 moves                            ``+s1``
2      ``F1^(0>0_+) = A1 - (mu_s g + p1)``    m1 rests                            +1
3      ``F1^(0>0_-) = A1 + (mu_s g + p1)``    m1 rests                            -1
4-7    the same for m2
8      ``x1 - d1`` (right stop)               always                              +1 / -1
9      ``z1 + d`` (left stop)                 always                              -1 / +1
10     ``zdot1`` (grazing of ``z1 = -d``)     a mass moves                        0
=====  =====================================  ==================================  =========

``G^(0)`` of a moving mass is zero where its speed has an extremum: a tangency with the velocity
boundary has no sign change of ``v_i``, so it is found here and judged by ``|v_i|``.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence

from oscillator.fields import flow_barrier_field, kinetic_field, non_friction_force
from oscillator.parameters import Parameters
from oscillator.phase_space import Mode

__all__ = ["NUM_ROOTS", "Root", "root_directions", "root_values"]


class Root(enum.IntEnum):
    """Index of each root function in the layout above."""

    VELOCITY_1 = 0
    GRAZING_1 = 1
    BARRIER_1_POSITIVE = 2
    BARRIER_1_NEGATIVE = 3
    VELOCITY_2 = 4
    GRAZING_2 = 5
    BARRIER_2_POSITIVE = 6
    BARRIER_2_NEGATIVE = 7
    RIGHT_STOP = 8
    LEFT_STOP = 9
    RELATIVE_VELOCITY = 10

    @property
    def mass(self) -> int:
        """The mass a per-mass root belongs to (1 or 2); 0 for the contact roots."""
        return 1 if self < 4 else (2 if self < 8 else 0)


NUM_ROOTS = len(Root)
_OFFSET = {1: 0, 2: 4}


def root_directions(mode: Mode) -> list[int]:
    """CVODE root directions for a mode (see the module table)."""
    directions = [0] * NUM_ROOTS
    for mass, base in _OFFSET.items():
        s = mode.sign(mass)
        if s:
            directions[base] = -s
            directions[base + 1] = s
        else:
            directions[base + 2] = 1
            directions[base + 3] = -1
    directions[Root.RIGHT_STOP] = -1 if mode.right else 1
    directions[Root.LEFT_STOP] = 1 if mode.left else -1
    return directions


def root_values(t: float, y: Sequence[float], p: Parameters, mode: Mode, out: list[float] | None = None) -> list[float]:
    """Evaluate every root function of the layout at ``(t, y)`` in ``mode``."""
    g = out if out is not None else [1.0] * NUM_ROOTS
    forces = non_friction_force(t, y, p, mode.left, mode.right)
    for mass, base in _OFFSET.items():
        s = mode.sign(mass)
        force = forces[mass - 1]
        if s:
            g[base] = y[2 * (mass - 1) + 1]
            g[base + 1] = kinetic_field(p, mass, s, force)
            g[base + 2] = 1.0
            g[base + 3] = 1.0
        else:
            g[base] = 1.0
            g[base + 1] = 1.0
            g[base + 2] = flow_barrier_field(p, mass, +1, force)
            g[base + 3] = flow_barrier_field(p, mass, -1, force)
    g[Root.RIGHT_STOP] = y[0] - p.d1
    g[Root.LEFT_STOP] = (y[0] - y[2]) + p.d
    # zdot1 is identically zero while both masses rest: hold it off then.
    both_rest = mode.domain1 == 0 and mode.domain2 == 0
    g[Root.RELATIVE_VELOCITY] = 1.0 if both_rest else y[1] - y[3]
    return g
