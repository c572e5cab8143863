"""The axes of the global analyses' grids, checked once.

One value type, :class:`Axis` (a name and ``count`` values from ``low`` to ``high``), serves the
state planes of the basins (the name a state component) and the parameter planes of the atlas
(the name a parameter).  :func:`state_plane` and :func:`parameter_plane` check a pair of axes for
each use: for a parameter plane the model's own validation admits its four corners (the
constraints on the parameters are intervals, so the whole rectangle is admitted), with no text
round trip.  Each refusal is one :class:`~oscillator.errors.InputError` naming the axis (``x`` or
``y``), which the command line shows as its flag.
"""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import Parameters
from oscillator.model.system import ARTICLE
from oscillator.text import printable, shown

__all__ = ["MAX_COUNT", "STATE", "Axis", "admitted_box", "chain_plane", "parameter_plane", "state_plane"]

#: The state components, in the order of a state vector.
STATE: tuple[str, ...] = ARTICLE.state
#: The most values along one axis.
MAX_COUNT = 2000


@dataclass(frozen=True)
class Axis:
    """One axis of a grid: a state component or a parameter, and ``count`` values from ``low``
    to ``high`` (both included, evenly spaced)."""

    name: str
    low: float
    high: float
    count: int

    def __post_init__(self) -> None:
        if self.name not in STATE and self.name not in Parameters.names() and not _of_a_system(self.name):
            raise InputError(
                f"axis {shown(self.name)} is neither a state component ({', '.join(STATE)}; a declared system's "
                "x:<mass>, v:<mass> or z:<slider>) nor a parameter (a declared system's <element>.<field>)",
                field="axis",
            )
        for end in (self.low, self.high):
            if not (isinstance(end, numbers.Real) and not isinstance(end, bool) and math.isfinite(end)):
                raise InputError(f"axis {self.name}: its ends must be finite numbers, got {shown(end)}", field="axis")
        if not self.low < self.high:
            raise InputError(
                f"axis {self.name}: from {self.low:g} to {self.high:g} is empty; give the lower end first", field="axis"
            )
        if isinstance(self.count, bool) or not isinstance(self.count, numbers.Integral):
            raise InputError(
                f"axis {self.name}: its count must be a whole number, got {shown(self.count)}", field="axis"
            )
        if not 2 <= self.count <= MAX_COUNT:
            raise InputError(
                f"axis {self.name}: its count must be from 2 to {MAX_COUNT}, got {shown(self.count)}", field="axis"
            )

    @property
    def values(self) -> np.ndarray:
        return np.linspace(self.low, self.high, self.count)


def _of_a_system(name: object) -> bool:
    """Whether ``name`` reads as a declared system's state component (``x:<mass>``, ``v:<mass>``,
    ``z:<slider>``) or number (``<element>.<field>``, ``<mass>.m``); which system has it is
    checked where the axis is used."""
    if not isinstance(name, str):
        return False
    return (name[:2] in ("x:", "v:", "z:") and len(name) > 2) or "." in name.strip(".")


def _check_pair(x: object, y: object) -> tuple[Axis, Axis]:
    for field, axis in (("x", x), ("y", y)):
        if not isinstance(axis, Axis):
            raise InputError(f"{field} must be an Axis(name, low, high, count), got {shown(axis)}", field=field)
    assert isinstance(x, Axis) and isinstance(y, Axis)
    if x.name == y.name:
        raise InputError(f"y: both axes are {x.name}; give two different ones", field="y")
    return x, y


def chain_plane(chain: FrictionChain, x: object, y: object) -> tuple[Axis, Axis]:
    """Two axes of a friction chain's numbers (:meth:`~oscillator.model.chains.FrictionChain.parameter_names`),
    checked: both its numbers, different, and every corner admitted (the chain with the two values:
    its checks are intervals, so the whole rectangle is admitted)."""
    known = chain.parameter_names()
    for field, axis in (("x", x), ("y", y)):
        if isinstance(axis, Axis) and axis.name not in known:
            raise InputError(
                f"{field}: axis {shown(axis.name)} is no number of the system; "
                f"give one of {printable(', '.join(known))}",
                field=field,
            )
    x, y = _check_pair(x, y)
    for a, b in itertools.product((x.low, x.high), (y.low, y.high)):
        chain.with_values({x.name: a, y.name: b}).checked()
    return x, y


def state_plane(x: object, y: object, state: tuple[str, ...] = STATE) -> tuple[Axis, Axis]:
    """Two axes of components of ``state`` (a slice of the state space; the article's system's by
    default, a friction chain's ``system.state``), checked."""
    for field, axis in (("x", x), ("y", y)):
        if isinstance(axis, Axis) and axis.name not in state:
            raise InputError(
                f"{field}: axis {shown(axis.name)} is not a state component; give one of {', '.join(state)}",
                field=field,
            )
    return _check_pair(x, y)


def parameter_plane(case: Case, x: object, y: object) -> tuple[Axis, Axis]:
    """Two axes of parameters, checked: both parameters, different, and every corner of the
    rectangle admitted by the model (``case`` with the two values)."""
    for field, axis in (("x", x), ("y", y)):
        if isinstance(axis, Axis):
            Parameters.check_name(axis.name, field, label=f"{field}: axis")
    x, y = _check_pair(x, y)
    ranges = {x.name: (x.low, x.high), y.name: (y.low, y.high)}
    admitted_box(case, ranges, {x.name: "x", y.name: "y"}, "give an axis inside the parameter's range")
    return x, y


#: Beyond this many parameters, a box's ends are checked one parameter at a time, not at every corner.
CORNERS_UP_TO = 10


def admitted_box(
    case: Case | FrictionChain, ranges: Mapping[str, tuple[float, ...]], fields: Mapping[str, str], fix: str
) -> None:
    """Every corner of the box of parameter ``ranges`` admitted by the model (``case``, or a
    declared system, with those values): each end alone, then every corner (the model's
    constraints are intervals or orderings of two parameters, so the whole box is then admitted).  A refusal is an
    :class:`~oscillator.errors.InputError` naming the values, with ``fields`` of the refused
    corner's last parameter (``"x"``, ``"vary"``) and ``fix``."""
    names = list(ranges)
    ends = [[(name, float(end)) for end in ranges[name]] for name in names]
    trials: list[tuple[tuple[str, float], ...]] = [(end,) for each in ends for end in each]
    if 1 < len(names) <= CORNERS_UP_TO:
        trials += list(itertools.product(*ends))
    for trial in trials:
        try:
            case.with_values(dict(trial)) if isinstance(case, FrictionChain) else resolve_case(case, **dict(trial))
        except OscillatorError as error:
            where = ", ".join(f"{name} = {value:g}" for name, value in trial)
            field = fields[trial[-1][0]]
            raise InputError(f"{field}: the model refuses {where} ({error}); {fix}", field=field) from None
