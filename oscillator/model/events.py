"""Switching-event records emitted by the supervisor.

An :class:`Event` is one row of ``Result.events``: what happened to which mass, on which
boundary, which theorem and equation decided it, the G-function values that decided it and the
state at that instant.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, fields

__all__ = ["Event", "EventKind"]


class EventKind(enum.StrEnum):
    """What happened at a switching event (the values are what a person reads)."""

    PASSABLE = "passable"
    """A moving mass crosses its velocity boundary (Thm 5.1)."""
    SLIDING_ONSET = "sliding_onset"
    """A moving mass comes to rest on its velocity boundary (Thm 5.2/5.3)."""
    SLIDING_VANISH = "sliding_vanish"
    """A resting mass leaves its velocity boundary through the flow barrier (Thm 5.4)."""
    GRAZING = "grazing"
    """A flow touches a boundary and turns back (Thm 5.5; displacement boundaries: rule 6)."""
    RIGHT_CONTACT_ONSET = "right_contact_onset"
    RIGHT_CONTACT_RELEASE = "right_contact_release"
    LEFT_CONTACT_ONSET = "left_contact_onset"
    LEFT_CONTACT_RELEASE = "left_contact_release"


@dataclass(frozen=True, slots=True)
class Event:
    """One switching event of one mass.

    Attributes
    ----------
    t : float
        Event time (s).
    mass : int
        1 or 2.
    kind : EventKind
    boundary : str
        The boundary, with the article's label (``∂Ω12(2)``, ``∂Ω13(1)``, ...).
    from_domain, to_domain : int
        The mass's domain before and after (equal for grazing).
    theorem, equation : str
        The theorem and equation that decided it (``"5.4"``, ``"(5.28)"``).
    branch : str
        Which alternative of the theorem decided, where it has several (see
        :class:`oscillator.model.theorems.Decision`); else empty.
    x1, v1, x2, v2 : float
        The state at the event.
    G0_alpha, G1_alpha : float
        0th/1st-order G-function on the departure side at ``t_m-`` (for a resting mass leaving:
        the flow barrier's).
    G0_beta, G1_beta : float
        The same on the arrival side at ``t_m+`` (NaN where the theorem uses no such value).
    G_alpha, G_beta : str
        Names of those G-functions, e.g. ``F2^(0>0_1)`` and ``F2^(1)``.
    distance : float
        For grazing, the distance to the boundary (``|v_i|`` in m/s, or the gap in m); else NaN.
    state_from, state_to : str
        System states of Sec. 3.2 before and after, e.g. ``I-c`` -> ``I-a``.
    """

    t: float
    mass: int
    kind: EventKind
    boundary: str
    from_domain: int
    to_domain: int
    theorem: str
    equation: str
    branch: str
    x1: float
    v1: float
    x2: float
    v2: float
    G0_alpha: float
    G1_alpha: float
    G0_beta: float = math.nan
    G1_beta: float = math.nan
    G_alpha: str = ""
    G_beta: str = ""
    distance: float = math.nan
    state_from: str = ""
    state_to: str = ""

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        """Column names of ``Result.events``, in order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def text_columns(cls) -> tuple[str, ...]:
        """The columns that hold text (``"5.1"`` is a theorem, not a number)."""
        return tuple(f.name for f in fields(cls) if f.type in ("str", "EventKind"))
