"""A friction chain's switching rules, element by element (issue 51, docs/systems.md).

The article's theorems are stated for one mass on its velocity boundary and for its two stops; in a
chain each friction element, stop, contact and Jenkins slider applies them to itself, since
friction acts against the ground (or a belt) and every other force is a function of the state:

* a slipping mass reaching its floor's (or belt's) velocity passes if the field across also leaves
  the boundary, else it sticks (Thm 5.1, (5.12)/(5.13); Thm 5.2/5.3, (5.16)-(5.19));
* a stuck mass slips when the other forces on it pass ``mu_s N + P`` (the flow barrier, Thm 5.4,
  (5.28)-(5.33)); a velocity extremum within ``near`` of the boundary is a grazing (Thm 5.5);
* a stop or contact closes and opens where its gap closes and opens (Thm 5.6, (5.40)/(5.41);
  Thm 5.8, (5.50)/(5.51));
* a stuck Jenkins slider slips when its spring's force reaches ``F``, a slipping one sticks where the
  stretch's motion turns (Masing's rule).

After every event each stuck element is checked again in the new mode (rule 7), until no mode
changes.  The functions are pure: they take the chain's arrays, a time, a state and a mode and give
the new mode, the state (a stuck mass set to its belt's speed, a slider to its threshold) and the
events, each with the element, the rule and the G-function values that decided it.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, fields

import numpy as np

from oscillator.model.chain_fields import (
    CONTACT,
    FRICTION,
    JENKINS,
    STOP,
    ChainArrays,
    chain_derivative,
    forces_on,
    pack,
)

__all__ = ["RULES", "ChainEvent", "ChainEventKind", "root_directions", "start", "switch"]


class ChainEventKind(enum.StrEnum):
    """What happened to an element at an event (the values are what a person reads)."""

    PASSABLE = "passable"
    """A slipping mass passes its floor's or belt's speed (Thm 5.1)."""
    STICKS = "sticks"
    """A slipping mass sticks to its floor or belt (Thm 5.2/5.3)."""
    SLIPS = "slips"
    """A stuck mass slips through the flow barrier (Thm 5.4)."""
    GRAZING = "grazing"
    """A slipping mass's speed turns near its belt's, no switch (Thm 5.5)."""
    STOP_CLOSES = "stop_closes"
    STOP_OPENS = "stop_opens"
    CONTACT_CLOSES = "contact_closes"
    CONTACT_OPENS = "contact_opens"
    SLIDER_SLIPS = "slider_slips"
    """A stuck Jenkins slider's force reaches F."""
    SLIDER_STICKS = "slider_sticks"
    """A slipping Jenkins slider's stretch turns."""

    @property
    def rule(self) -> tuple[str, str]:
        """The theorem and equations that decide it (the article's numbering; Masing's rule for a
        slider)."""
        return RULES[self]


#: Each event kind's theorem and equations.
RULES = {
    ChainEventKind.PASSABLE: ("5.1", "(5.12)/(5.13)"),
    ChainEventKind.STICKS: ("5.2/5.3", "(5.16)-(5.19)"),
    ChainEventKind.SLIPS: ("5.4", "(5.28)-(5.33)"),
    ChainEventKind.GRAZING: ("5.5", "(5.37)/(5.38)"),
    ChainEventKind.STOP_CLOSES: ("5.6", "(5.40)"),
    ChainEventKind.STOP_OPENS: ("5.6", "(5.41)"),
    ChainEventKind.CONTACT_CLOSES: ("5.8", "(5.50)"),
    ChainEventKind.CONTACT_OPENS: ("5.8", "(5.51)"),
    ChainEventKind.SLIDER_SLIPS: ("Jenkins", "|kt (u - z)| = F"),
    ChainEventKind.SLIDER_STICKS: ("Jenkins", "u' = 0"),
}
#: How close (relative) a slider's force must be to ``F`` to be at its threshold.
AT_THRESHOLD = 1e-9
#: How many rounds of rule 7 at one instant before the run is refused as chattering.
MAX_ROUNDS = 16


@dataclass(frozen=True)
class ChainEvent:
    """One switching event of a chain: when, which element (its type, mass and ``with`` mass:
    ``""`` for the ground), what happened (:data:`RULES`), the element's mode before and after, and
    the two values that decided it (``G0``, ``G1``: docs/systems.md, "Events")."""

    t: float
    element: str
    type: str
    mass: str
    with_: str
    kind: ChainEventKind
    mode_before: int
    mode_after: int
    G0: float
    G1: float

    @property
    def theorem(self) -> str:
        return self.kind.rule[0]

    @property
    def equations(self) -> str:
        return self.kind.rule[1]

    @staticmethod
    def columns() -> tuple[str, ...]:
        names = [f.name.rstrip("_") for f in fields(ChainEvent)]
        return (*names[:6], "theorem", "equations", *names[6:])

    def row(self) -> tuple[object, ...]:
        values = [getattr(self, f.name) for f in fields(self)]
        values[5] = str(self.kind)
        return (*values[:6], self.theorem, self.equations, *values[6:])


@dataclass(frozen=True)
class Names:
    """The chain's names the events carry: its masses' and its elements'."""

    masses: tuple[str, ...]
    elements: tuple[str, ...]
    types: tuple[str, ...]


def root_directions(arrays: ChainArrays, mode: np.ndarray) -> tuple[int, ...]:
    """The directions CVODE watches each root function in (:func:`~oscillator.model.chain_fields.
    root_values`): ``+1`` rising, ``-1`` falling, ``0`` both."""
    directions: list[int] = []
    for row, code in enumerate(arrays.kind):
        s = int(mode[row])
        side = int(arrays.value[row, 0])
        if code == FRICTION or code == JENKINS:
            directions += [-s, s] if s else [1, -1]
        elif code in (STOP, CONTACT):  # open: closing, and the gap's turn toward the stop
            directions += [side, -side] if s == 0 else [-side, 0]
        else:
            directions += [0, 0]
    return tuple(directions)


def _friction(arrays: ChainArrays, row: int) -> tuple[float, float, float]:
    """A friction element's static and kinetic thresholds ``mu N + P`` (N) and its belt's speed."""
    mu_s, mu_k, normal, feedback, belt = arrays.value[row]
    return mu_s * normal + feedback, mu_k * normal + feedback, belt


def _stretch(arrays: ChainArrays, y: np.ndarray, row: int) -> tuple[float, float]:
    on, other = arrays.on[row], arrays.other[row]
    if other < 0:
        return y[2 * on], y[2 * on + 1]
    return y[2 * on] - y[2 * other], y[2 * on + 1] - y[2 * other + 1]


def _forces(arrays: ChainArrays, t: float, y: np.ndarray, mode: np.ndarray) -> np.ndarray:
    out = np.empty(len(arrays.mass))
    forces_on(t, y, pack(arrays, mode), out)
    return out


def _rates(arrays: ChainArrays, t: float, y: np.ndarray, mode: np.ndarray) -> np.ndarray:
    out = np.empty(arrays.size)
    chain_derivative(t, y[: arrays.size], out, pack(arrays, mode))
    return out


class _Instant:
    """The events of one instant, built up as the rules decide them."""

    def __init__(self, arrays: ChainArrays, names: Names, t: float, y: np.ndarray, mode: np.ndarray) -> None:
        self.arrays, self.names, self.t = arrays, names, t
        self.y, self.before, self.mode = y.copy(), mode.copy(), mode.copy()
        self.events: list[ChainEvent] = []

    def record(self, row: int, kind: ChainEventKind, after: int, g0: float, g1: float) -> None:
        arrays, names = self.arrays, self.names
        other = arrays.other[row]
        self.events.append(
            ChainEvent(
                self.t,
                names.elements[row],
                names.types[row],
                names.masses[arrays.on[row]],
                names.masses[other] if other >= 0 else "",
                kind,
                int(self.mode[row]),
                after,
                float(g0),
                float(g1),
            )
        )
        self.mode[row] = after

    def slide(self, row: int, s: int) -> None:
        """A Jenkins slider at its threshold on side ``s``: ``kt (u - z) = s F`` exactly."""
        kt, strength = self.arrays.value[row, :2]
        u, _ = _stretch(self.arrays, self.y, row)
        self.y[self.arrays.slider[row]] = u - s * strength / kt


def _crossed(instant: _Instant, row: int, slot: int, near: float) -> int | None:
    """Apply the root ``slot`` of element ``row`` that CVODE returned; a friction element reaching
    its boundary is left to :func:`_settle` (its arrival side returned)."""
    arrays, y, t = instant.arrays, instant.y, instant.t
    code, s = arrays.kind[row], int(instant.mode[row])
    on = arrays.on[row]
    if code == FRICTION:
        static, kinetic, belt = _friction(arrays, row)
        force = _forces(arrays, t, y, instant.mode)[on]
        if s and slot == 0:
            y[2 * on + 1] = belt
            return s
        if s:  # an extremum of the velocity: a grazing if it is near the boundary
            if abs(y[2 * on + 1] - belt) <= near:
                instant.events.append(_grazing(instant, row, (force - s * kinetic) / arrays.mass[on]))
            return None
        side = 1 if slot == 0 else -1
        instant.record(
            row,
            ChainEventKind.SLIPS,
            side,
            (force - side * static) / arrays.mass[on],
            (force - side * kinetic) / arrays.mass[on],
        )
    elif code in (STOP, CONTACT):
        kinds = {
            (STOP, 0): ChainEventKind.STOP_CLOSES,
            (STOP, 1): ChainEventKind.STOP_OPENS,
            (CONTACT, 0): ChainEventKind.CONTACT_CLOSES,
            (CONTACT, 1): ChainEventKind.CONTACT_OPENS,
        }
        kind = kinds[(int(code), 1 if s else 0)]
        u, rate = (y[2 * on], y[2 * on + 1]) if code == STOP else _stretch(arrays, y, row)
        instant.record(row, kind, 0 if s else 1, rate, u)
    elif code == JENKINS:
        kt = arrays.value[row, 0]
        u, rate = _stretch(arrays, y, row)
        if s == 0:
            side = 1 if slot == 0 else -1
            instant.slide(row, side)
            instant.record(row, ChainEventKind.SLIDER_SLIPS, side, kt * (u - y[arrays.slider[row]]), rate)
        else:
            instant.slide(row, s)
            instant.record(row, ChainEventKind.SLIDER_STICKS, 0, rate, kt * (u - y[arrays.slider[row]]))
    return None


def _inside(instant: _Instant, row: int) -> bool:
    """Whether an open stop or contact is past its edge (its closing was straddled by one step and
    its turn found first: it closes here)."""
    arrays, y = instant.arrays, instant.y
    side, at = arrays.value[row, :2]
    on = arrays.on[row]
    u, edge = (y[2 * on], at) if arrays.kind[row] == STOP else (_stretch(arrays, y, row)[0], side * at)
    return bool(side * (edge - u) < 0.0)


def _grazing(instant: _Instant, row: int, acceleration: float) -> ChainEvent:
    arrays, names, s = instant.arrays, instant.names, int(instant.mode[row])
    on = arrays.on[row]
    distance = abs(instant.y[2 * on + 1] - arrays.value[row, 4])
    return ChainEvent(
        instant.t,
        names.elements[row],
        names.types[row],
        names.masses[on],
        "",
        ChainEventKind.GRAZING,
        s,
        s,
        acceleration,
        distance,
    )


def _settle(instant: _Instant, arrived: dict[int, int]) -> None:
    """Rule 1 for the masses that reached their boundary, then rule 7 until no mode changes."""
    arrays = instant.arrays
    for _ in range(MAX_ROUNDS):
        changed = False
        forces = _forces(arrays, instant.t, instant.y, instant.mode)
        for row in np.flatnonzero(arrays.kind == FRICTION).tolist():
            on, mass = arrays.on[row], arrays.mass[arrays.on[row]]
            static, kinetic, _ = _friction(arrays, row)
            force = forces[on]
            if row in arrived:
                s = arrived.pop(row)
                across, here = (force + s * kinetic) / mass, (force - s * kinetic) / mass
                instant.record(
                    row,
                    ChainEventKind.PASSABLE if s * across < 0 else ChainEventKind.STICKS,
                    -s if s * across < 0 else 0,
                    across,
                    here,
                )
                changed = True
            elif instant.mode[row] == 0 and abs(force) > static:
                side = 1 if force > 0 else -1
                instant.record(
                    row, ChainEventKind.SLIPS, side, (force - side * static) / mass, (force - side * kinetic) / mass
                )
                changed = True
        for row in np.flatnonzero((arrays.kind == JENKINS) & (instant.mode == 0) & (arrays.value[:, 1] > 0)).tolist():
            changed = _hold(instant, row) or changed
        if not changed:
            return
    raise ChatterError(instant.t, [event.element for event in instant.events[-4:]])


def _hold(instant: _Instant, row: int) -> bool:
    """Rule 7 for a stuck slider: it slips when its spring's force is past ``F``, or at ``F`` with
    the stretch moving on (its rate, or at a turn its acceleration, on the force's side); held at
    its threshold it is set a relative 1e-12 inside, so that CVODE sees its root function start
    on the holding side.  Whether it slipped."""
    arrays, y = instant.arrays, instant.y
    kt, strength = arrays.value[row, :2]
    u, rate = _stretch(arrays, y, row)
    pull = kt * (u - y[arrays.slider[row]])
    side = 1 if pull > 0 else -1
    if abs(pull) < strength * (1.0 - AT_THRESHOLD):
        return False
    if rate == 0.0:
        rates = _rates(arrays, instant.t, y, instant.mode)
        on, other = arrays.on[row], arrays.other[row]
        rate = rates[2 * on + 1] - (rates[2 * other + 1] if other >= 0 else 0.0)
    if abs(pull) > strength * (1.0 + AT_THRESHOLD) or side * rate > 0:
        instant.slide(row, side)
        instant.record(row, ChainEventKind.SLIDER_SLIPS, side, pull, rate)
        return True
    y[arrays.slider[row]] = u - side * strength * (1.0 - 1e-12) / kt
    return False


class ChatterError(RuntimeError):
    """The rules did not settle at one instant (:data:`MAX_ROUNDS` rounds)."""

    def __init__(self, t: float, elements: list[str]) -> None:
        super().__init__(f"the switching rules do not settle at t = {t!r} s (elements {', '.join(elements)})")
        self.t, self.elements = t, elements


def switch(
    arrays: ChainArrays,
    names: Names,
    t: float,
    y: np.ndarray,
    mode: np.ndarray,
    fired: tuple[int, ...],
    near: float,
) -> tuple[np.ndarray, np.ndarray, list[ChainEvent]]:
    """The mode and state after the roots ``fired`` (indices of :func:`~oscillator.model.
    chain_fields.root_values`) at ``t``, and the events, in the order decided."""
    instant = _Instant(arrays, names, t, y, mode)
    arrived: dict[int, int] = {}
    for index in fired:
        row, slot = divmod(index, 2)
        if slot == 1 and arrays.kind[row] in (STOP, CONTACT) and (index - 1 in fired or not _inside(instant, row)):
            continue  # the gap's turn, outside the stop (or with its closing found too): no event
        side = _crossed(instant, row, slot, near)
        if side is not None:
            arrived[row] = side
    _settle(instant, arrived)
    return instant.mode, instant.y, instant.events


def _closed(side: int, gap_left: float, rate: float, pull: float) -> bool:
    """Whether a stop or contact ``gap_left`` from closing (``<= 0``: at or past) is closed at a
    start: inside, or on its edge moving in (or at rest there and pushed in)."""
    if gap_left != 0.0:
        return gap_left < 0.0
    inward = -side * rate if rate != 0.0 else -side * pull
    return inward < 0.0


def start(
    arrays: ChainArrays, names: Names, t: float, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[ChainEvent]]:
    """The mode a chain starts in at ``t`` (rule 8): a mass moving against its floor or belt slips
    that way; one at the belt's speed rests unless the other forces pass ``mu_s N + P`` (then it
    leaves at once, an event at ``t``); a stop or contact is closed inside its gap, or on its edge
    moving in; a slider holds (one with ``F = 0`` slips: it never holds)."""
    mode = np.zeros(len(arrays.kind), dtype=np.int64)
    for row in np.flatnonzero(arrays.kind == JENKINS).tolist():
        mode[row] = 1 if arrays.value[row, 1] == 0.0 else 0
    for row in np.flatnonzero(arrays.kind == FRICTION).tolist():
        relative = y[2 * arrays.on[row] + 1] - arrays.value[row, 4]
        mode[row] = int(np.sign(relative))
    open_rates = _rates(arrays, t, y, mode)
    for row in np.flatnonzero((arrays.kind == STOP) | (arrays.kind == CONTACT)).tolist():
        side, at = arrays.value[row, :2]
        on, other = arrays.on[row], arrays.other[row]
        if arrays.kind[row] == STOP:
            u, rate, pull = y[2 * on], y[2 * on + 1], open_rates[2 * on + 1]
            edge = at
        else:
            u, rate = _stretch(arrays, y, row)
            pull = open_rates[2 * on + 1] - (open_rates[2 * other + 1] if other >= 0 else 0.0)
            edge = side * at
        mode[row] = int(_closed(int(side), side * (edge - u), rate, pull))
    instant = _Instant(arrays, names, t, y, mode)
    _settle(instant, {})
    return instant.mode, instant.y, instant.events
