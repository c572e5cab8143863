"""Switching-event records emitted by the supervisor.

An :class:`Event` is one row of ``Result.events``: what happened to which mass, on which
boundary, which theorem and equation decided it, the G-function values that decided it and the
state at that instant.
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from oscillator.model.phase_space import boundary_label, state_label

__all__ = ["COLUMN", "Event", "EventKind", "decode", "decode_column", "event_of_row", "one_row_per_event"]


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
    """m1 reaches the right stop ``x1 = d1`` (Thm 5.6/5.8)."""
    RIGHT_CONTACT_RELEASE = "right_contact_release"
    """m1 leaves the right stop (Thm 5.6/5.8)."""
    LEFT_CONTACT_ONSET = "left_contact_onset"
    """m1 reaches m2's stop ``z1 = -d``: both masses change domain (Thm 5.7/5.9)."""
    LEFT_CONTACT_RELEASE = "left_contact_release"
    """m1 leaves m2's stop: both masses change domain (Thm 5.7/5.9)."""

    @property
    def switches(self) -> bool:
        """Whether it changes a domain (a grazing only reports a touch)."""
        return self is not EventKind.GRAZING

    @property
    def reaches_velocity_boundary(self) -> bool:
        """A moving mass reaching ``v_i = 0``: it passes (Thm 5.1) or comes to rest (5.2/5.3)."""
        return self in (EventKind.PASSABLE, EventKind.SLIDING_ONSET)

    @property
    def starts_rest(self) -> bool:
        """A mass comes to rest on its velocity boundary (a rest interval begins)."""
        return self is EventKind.SLIDING_ONSET

    @property
    def ends_rest(self) -> bool:
        """A resting mass moves again (a rest interval ends)."""
        return self is EventKind.SLIDING_VANISH

    @property
    def contact(self) -> Literal["right", "left"] | None:
        """The stop whose contact changes, or None."""
        return _CONTACT.get(self)

    @property
    def contact_starts(self) -> bool:
        """A contact begins (``contact`` names the stop)."""
        return self in (EventKind.RIGHT_CONTACT_ONSET, EventKind.LEFT_CONTACT_ONSET)

    @property
    def both_masses(self) -> bool:
        """Written as one row per mass at one instant: the left stop moves with m2, so a left
        contact change switches both masses' fields."""
        return self.contact == "left"

    def stands_for_event(self, mass: int) -> bool:
        """Whether the row of ``mass`` stands for its event when events are counted: an event of
        both masses (:attr:`both_masses`) is written once per mass, and only its m1 row counts."""
        return not self.both_masses or mass == 1

    @classmethod
    def values_where(cls, test: Callable[[EventKind], bool]) -> list[str]:
        """The values (the ``kind`` column's text) of the kinds that pass ``test``:
        ``events.kind.isin(EventKind.values_where(lambda k: k.starts_rest))``."""
        return [kind.value for kind in cls if test(kind)]


def one_row_per_event(kinds: Iterable[str], masses: Iterable[int]) -> np.ndarray:
    """A mask of event-table rows (their ``kind`` and ``mass`` columns) that keeps one row per
    event: counting ``events[mask]`` counts each left-contact change once, not once per mass."""
    return np.array(
        [EventKind(kind).stands_for_event(int(mass)) for kind, mass in zip(kinds, masses, strict=True)], dtype=bool
    )


_CONTACT: dict[EventKind, Literal["right", "left"]] = {
    EventKind.RIGHT_CONTACT_ONSET: "right",
    EventKind.RIGHT_CONTACT_RELEASE: "right",
    EventKind.LEFT_CONTACT_ONSET: "left",
    EventKind.LEFT_CONTACT_RELEASE: "left",
}


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


# --------------------------------------------------------------------------- events as rows of numbers
#
# The compiled switching rules write each event as one row of float64 numbers, the columns of
# Event in order; the text columns hold codes (exact small integers), read by :func:`decode`.

#: Column of each field of :class:`Event` in an event row.
COLUMN = {f.name: index for index, f in enumerate(fields(Event))}
#: Number of columns of an event row.
WIDTH = len(COLUMN)
#: Event kinds by code (their order in :class:`EventKind`).
KINDS = tuple(EventKind)
#: G-function name codes: none, ``v1``, ``zdot1``; ``F{mass}^(delta)`` is ``FIELD + delta`` and
#: ``F{mass}^(0>0_delta)`` (a flow barrier) ``BARRIER + delta``.
NO_NAME, V1_NAME, ZDOT1_NAME, FIELD, BARRIER = 0, 1, 2, 10, 20


def _name_text(code: int, mass: int) -> str:
    if code >= BARRIER:
        return f"F{mass}^(0>0_{code - BARRIER})"
    if code >= FIELD:
        return f"F{mass}^({code - FIELD})"
    return ("", "v1", "zdot1")[code]


@functools.cache
def _text(column: str, code: int, mass: int) -> str:
    # the theorems' module holds compiled kernels: imported when an event is read, so that the
    # command's start, its --help and its refusals do not wait for numba
    from oscillator.model.theorems import branch_text, equation_text, theorem_text

    if column == "kind":
        return KINDS[code].value
    if column == "boundary":
        return boundary_label(code)
    if column == "theorem":
        return theorem_text(code)
    if column == "equation":
        return equation_text(code)
    if column == "branch":
        return branch_text(code)
    if column in ("G_alpha", "G_beta"):
        return _name_text(code, mass)
    return state_label(code)


def decode(column: str, code: float, mass: float) -> str:
    """The text of the code ``code`` in the column ``column`` of an event row of mass ``mass``."""
    return _text(column, int(code), int(mass))


def decode_column(column: str, codes: np.ndarray, masses: np.ndarray) -> np.ndarray:
    """The text of a coded column of event rows (``masses``: the rows' masses), as an object
    array; each distinct code is read once."""
    keys = 4 * codes.astype(np.int64) + masses.astype(np.int64)
    distinct, where = np.unique(keys, return_inverse=True)
    texts = np.array([_text(column, key // 4, key % 4) for key in distinct.tolist()] + [""], dtype=object)
    return texts[:-1][where] if len(keys) else texts[:0]


#: The columns of an event row that hold numbers, and those that hold codes.
NUMBER_COLUMNS = tuple(f.name for f in fields(Event) if f.type in ("float", "int"))
CODE_COLUMNS = tuple(f.name for f in fields(Event) if f.name not in NUMBER_COLUMNS)


def event_of_row(row: np.ndarray) -> Event:
    """The :class:`Event` an event row stands for."""
    mass = int(row[COLUMN["mass"]])
    values: dict[str, object] = {}
    for name in NUMBER_COLUMNS:
        value = float(row[COLUMN[name]])
        values[name] = int(value) if name in ("mass", "from_domain", "to_domain") else value
    for name in CODE_COLUMNS:
        values[name] = _text(name, int(row[COLUMN[name]]), mass)
    values["kind"] = EventKind(str(values["kind"]))
    return Event(**values)  # type: ignore[arg-type]
