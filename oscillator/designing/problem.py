"""A robust design problem: what varies, over which operating band, against what (docs/design.md).

A design is a choice of some parameters within bounds (``vary``).  It is judged over an
operating band of another parameter (``over``, e.g. the forcing frequency) by its **worst case**:
at each of ``band`` values across it, every attractor that ``starts`` multistart runs reach, and
the largest value of the objective among them all, so that a design good only from one start is
not good.  Constraints are bounds on response measures that must hold on every attractor at
every band value: ``"rest_m2 <= 0"`` (m2 never rests), ``"onsets_right <= 0"`` (no contact with
the right stop), ``"x_max_m1 <= 3.9"``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from oscillator.analysis.axes import admitted_box
from oscillator.errors import InputError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.parameters import Parameters, check_count, is_finite_number
from oscillator.text import shown

__all__ = ["FEASIBLE", "Constraint", "Problem", "check_constraint", "check_measure"]

#: A constraint holds within this (relative to its bound, absolute below 1): the measures are
#: computed to about 1e-9.
FEASIBLE = 1e-8
_BOUND = re.compile(r"^\s*([A-Za-z_0-9]+)\s*<=\s*([-+0-9.eE]+)\s*$")


def check_measure(name: object, field: str) -> str:
    """``name`` if it is a response measure's column (:func:`~oscillator.attractors.atlas.check_measures`)."""
    from oscillator.attractors.atlas import check_measures

    (checked,) = check_measures((name,), field)
    return checked


@dataclass(frozen=True)
class Constraint:
    """``measure <= bound`` on every attractor at every band value."""

    measure: str
    bound: float

    def __str__(self) -> str:
        return f"{self.measure} <= {self.bound:g}"


def check_constraint(text: object) -> Constraint:
    """``"measure <= bound"`` read as a :class:`Constraint` (or a Constraint as it is)."""
    if isinstance(text, Constraint):
        return Constraint(check_measure(text.measure, "constraints"), _finite(text.bound, "constraints"))
    match = _BOUND.match(text) if isinstance(text, str) else None
    if match is None:
        raise InputError(
            f"constraints: {shown(text)} is not a bound; write 'measure <= value', e.g. 'rest_m2 <= 0' (m2 never "
            "rests) or 'onsets_right <= 0' (no contact with the right stop)",
            field="constraints",
        )
    try:
        bound = float(match.group(2))
    except ValueError:
        raise InputError(
            f"constraints: {shown(text)}: {match.group(2)!r} is not a number; write 'measure <= value', e.g. "
            "'x_max_m1 <= 3.9'",
            field="constraints",
        ) from None
    return Constraint(check_measure(match.group(1), "constraints"), _finite(bound, "constraints"))


def _finite(value: object, field: str) -> float:
    if not is_finite_number(value):
        raise InputError(f"{field}: {shown(value)} is not a finite number", field=field)
    return float(value)


def _span(name: object, bounds: object, field: str) -> tuple[str, float, float]:
    name = Parameters.check_name(name, field)
    try:
        low, high = (_finite(v, field) for v in bounds)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(
            f"{field}: {name}'s range must be two numbers (low, high), got {shown(bounds)}", field=field
        ) from None
    if not low < high:
        raise InputError(f"{field}: {name}'s range ({low:g}, {high:g}) is empty; give low < high", field=field)
    return name, low, high


@dataclass(frozen=True)
class Problem:
    """A checked design problem (module docstring); build it with :meth:`of`."""

    case: Case
    vary: tuple[tuple[str, float, float], ...]
    over: tuple[str, float, float]
    objective: str
    constraints: tuple[Constraint, ...]
    band: int
    starts: int
    #: A second objective, traded against the first along a Pareto front (empty for one).
    also: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        case: Case | str,
        vary: Mapping[str, Sequence[float]],
        over: Mapping[str, Sequence[float]],
        objective: str | Sequence[str],
        constraints: Sequence[str | Constraint] = (),
        band: int = 5,
        starts: int = 4,
    ) -> Problem:
        """Every argument checked, with the field and the fix on a bad one.  ``objective`` is one
        measure, or two traded along a Pareto front."""
        if not isinstance(vary, Mapping) or not vary:
            raise InputError("vary must map parameters to ranges, e.g. {'d1': (3.3, 4.2)}", field="vary")
        if not isinstance(over, Mapping) or len(over) != 1:
            raise InputError("over must map one parameter to its band, e.g. {'Omega': (1.4, 1.6)}", field="over")
        ranges = tuple(_span(name, bounds, "vary") for name, bounds in vary.items())
        ((band_name, band_range),) = over.items()
        band_span = _span(band_name, band_range, "over")
        if band_span[0] in {name for name, _, _ in ranges}:
            raise InputError(
                f"over: {band_span[0]} is varied too; the band is a parameter the design does not choose", field="over"
            )
        base = resolve_case(case)
        box = {name: (low, high) for name, low, high in ranges}
        fields = dict.fromkeys(box, "vary")
        admitted_box(base, box, fields, "give a range the model admits")
        fields[band_span[0]] = "over"
        admitted_box(base, box | {band_span[0]: band_span[1:]}, fields, "give a range the model admits")
        if isinstance(constraints, str):
            constraints = [constraints]
        objectives = (
            [objective] if isinstance(objective, str) else list(objective) if isinstance(objective, Sequence) else []
        )
        if not 1 <= len(objectives) <= 2 or len(set(map(str, objectives))) != len(objectives):
            raise InputError(
                "objective must be one response measure, or two different ones for a Pareto front; "
                f"got {shown(objective)}",
                field="objective",
            )
        return cls(
            case=base,
            vary=ranges,
            over=band_span,
            objective=check_measure(objectives[0], "objective"),
            constraints=tuple(check_constraint(c) for c in constraints),
            band=check_count(band, "band", 1, 1000),
            starts=check_count(starts, "starts", 1, 10_000),
            also=tuple(check_measure(name, "objective") for name in objectives[1:]),
        )

    @property
    def measures(self) -> tuple[str, ...]:
        """Every measure judged: the objectives and the constrained ones, each once."""
        return tuple(dict.fromkeys([self.objective, *self.also, *(c.measure for c in self.constraints)]))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _, _ in self.vary)

    @property
    def lower(self) -> np.ndarray:
        return np.array([low for _, low, _ in self.vary])

    @property
    def upper(self) -> np.ndarray:
        return np.array([high for _, _, high in self.vary])

    def band_values(self) -> np.ndarray:
        """The band's values judged: ``band`` evenly spaced, ends included (its middle for one)."""
        _, low, high = self.over
        return np.array([0.5 * (low + high)]) if self.band == 1 else np.linspace(low, high, self.band)

    def design(self, x: Sequence[float] | np.ndarray) -> dict[str, float]:
        """The design ``x`` (in ``vary``'s order) by name."""
        return {name: float(value) for name, value in zip(self.names, x, strict=True)}

    def check_design(self, x: object, field: str = "start") -> np.ndarray:
        """``x`` as a design within the bounds."""
        try:
            values = np.asarray([float(v) for v in x], dtype=np.float64)  # type: ignore[attr-defined]
        except (TypeError, ValueError):
            values = np.empty(0)
        if len(values) != len(self.vary) or not np.isfinite(values).all():
            raise InputError(f"{field} must give {', '.join(self.names)} as numbers, got {shown(x)}", field=field)
        outside = [
            name for name, v, (_, low, high) in zip(self.names, values, self.vary, strict=True) if not low <= v <= high
        ]
        if outside:
            raise InputError(f"{field}: {', '.join(outside)} outside the ranges of vary", field=field)
        return values

    def violation(self, worst: Mapping[str, float]) -> float:
        """How far the worst measures break the constraints (0: feasible, within :data:`FEASIBLE`
        of each bound; ``inf`` if unmeasured)."""
        total = 0.0
        for constraint in self.constraints:
            value = worst.get(constraint.measure, math.nan)
            excess = value - constraint.bound
            slack = FEASIBLE * max(abs(constraint.bound), 1.0)
            total += math.inf if not math.isfinite(value) else (excess if excess > slack else 0.0)
        return total
