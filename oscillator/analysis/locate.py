"""Where a sweep's summary changes: bisection on the parameter, to a given width (1e-8 by default).

Both ends of the bracket are simulated first to see that they differ (sliding, period, or the
number of switches per period, which changes at a grazing); each bisection step simulates the
middle, exactly as a sweep would (:func:`oscillator.analysis.sweep_points.run_point`, or for a
declared system :func:`oscillator.analysis.chain_sweeps.run_chain_point`, where ``sliding`` is
whether an element sticks: its stickings per period).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np
import pandas as pd

from oscillator.analysis.sweep_points import PointTables, point_function
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.io.cases import Case
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SweepSettings, is_finite_number
from oscillator.text import shown

__all__ = ["INDICATORS", "Location", "locate"]

#: What ``locate`` can look for, and the summary column that tells it.
INDICATORS = {"sliding": "sliding", "period": "period", "grazing": "switches_per_period"}
#: A declared system's (:func:`~oscillator.analysis.chain_sweeps.chain_sweep_columns`).
SYSTEM_INDICATORS = INDICATORS | {"sliding": "sticks_per_period"}


@dataclasses.dataclass(frozen=True)
class Location:
    """Where a summary indicator changes between two parameter values, and the evidence."""

    param: str
    what: str
    lower: float
    upper: float
    iterations: int
    below: pd.DataFrame
    above: pd.DataFrame
    evidence_below: pd.DataFrame
    evidence_above: pd.DataFrame

    @property
    def value(self) -> float:
        """The located parameter: the middle of the final bracket."""
        return 0.5 * (self.lower + self.upper)

    @property
    def width(self) -> float:
        return self.upper - self.lower


def locate(
    case: Case | FrictionChain,
    settings: SweepSettings,
    what: str,
    between: tuple[float, float],
    *,
    tolerance: float = 1e-8,
    progress: Callable[[int, int, float, float], None] | None = None,
) -> Location:
    """Bisect ``[a, b]`` until the bracket is narrower than ``tolerance``.

    ``what`` is ``sliding`` (whether the mass rests), ``period`` (the period-n found) or
    ``grazing`` (switches of the mass per period: at a grazing bifurcation a pair of crossings
    appears or disappears).  The indicator must differ at ``a`` and ``b``; both ends are
    simulated to see it.  ``tolerance`` must be positive and at least a few units of floating
    point at the bracket (4 ulp); the bisection then takes ``ceil(log2((b - a) / tolerance))``
    steps.  ``progress(step, steps, a, b)`` is called before each simulation (the two ends are
    steps 1 and 2).
    """
    if what not in INDICATORS:
        raise InputError(f"what must be one of {', '.join(INDICATORS)}, got {shown(what)}", field="what")
    column = (SYSTEM_INDICATORS if isinstance(case, FrictionChain) else INDICATORS)[what]
    if len(between) != 2 or not all(is_finite_number(v) for v in between):
        raise InputError(f"between needs two finite values, got {shown(between)}", field="between")
    a, b = float(min(between)), float(max(between))
    if not b > a:
        raise InputError(f"between needs two different values, got {shown(between)}", field="between")
    resolution = 4 * float(np.spacing(max(abs(a), abs(b))))
    if not (is_finite_number(tolerance) and tolerance >= resolution):
        raise InputError(
            f"tolerance must be a width of at least {resolution:.2g} (4 ulp of floating point at "
            f"{settings.param} = {b:g}), got {shown(tolerance)}",
            field="tolerance",
        )
    steps = 2 + max(0, math.ceil(math.log2((b - a) / tolerance)))
    run = point_function(case)

    def evaluate(value: float, step: int) -> PointTables:
        if progress is not None:
            progress(step, steps, a, b)
        point = run(case, settings, 0, value)
        row = point.summary.iloc[0]
        if row.status != "ok":
            raise SimulationFailed(
                f"{settings.param} = {value!r}: {row.message}", reason=Reason(row.reason), field=settings.param
            )
        return point

    low, high = evaluate(a, 1), evaluate(b, 2)
    if low.summary[column].iloc[0] == high.summary[column].iloc[0]:
        raise InputError(
            f"{what} is the same at {settings.param} = {a!r} and {b!r} ({column} = {low.summary[column].iloc[0]}, "
            f"seen by simulating both ends); give two values on either side of a change (see the sweep's summary "
            f"table)",
            field="between",
        )
    iterations = 0
    while b - a > tolerance and iterations < steps - 2:
        middle = evaluate(0.5 * (a + b), iterations + 3)
        iterations += 1
        if middle.summary[column].iloc[0] == low.summary[column].iloc[0]:
            a, low = middle.value, middle
        else:
            b, high = middle.value, middle
    return Location(settings.param, what, a, b, iterations, low.summary, high.summary, low.switches, high.switches)
