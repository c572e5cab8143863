"""The features of an attractor: what the atlas's describer measures at every point.

:class:`Measured` gives each attractor its largest Lyapunov exponent without Newton's refinement
(``log |mu_1| / (n T)`` from one return's monodromy at the attractor's cycle, the derivative
through every switch, :func:`~oscillator.orbits.shooting.period_map`; for an aperiodic set the QR
average of :func:`~oscillator.attractors.lyapunov.lyapunov`) and every measure of
:data:`MEASURES` it names.  A new feature is one function ``measure(case, attractor) -> float``
registered in :data:`MEASURES`: the atlas's table gains its column.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from oscillator.attractors.finding import largest_exponent
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.lyapunov import lyapunov
from oscillator.errors import OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.orbits.shooting import period_map

__all__ = ["MEASURES", "Measured", "impact_velocity"]


def impact_velocity(case: Case, attractor: Attractor) -> float:
    """The largest approach speed at a contact onset (m/s, :func:`~oscillator.orbits.response.impact_speeds`)
    over one return from the attractor's last section point (``max(period, 1)`` forcing
    periods); 0 without contacts."""
    from oscillator.hybrid.recording import SaveAt
    from oscillator.hybrid.simulate import simulate
    from oscillator.orbits.response import impact_speeds

    if not attractor.contacts:
        return 0.0
    periods = max(attractor.period, 1)
    begin = dict(zip(case.system.state, (float(v) for v in attractor.points[-1]), strict=True))
    run = resolve_case(case, **begin)
    result = simulate(run, t_end=run.initial.t0 + periods * run.parameters.period, save=SaveAt(steps=False))
    rows = result.event_rows  # its rows, where no table was built from them yet
    speeds = np.concatenate(
        [impact_speeds(result.events if rows is None else rows, stop) for stop in ("right", "left")]
    )
    return float(np.max(speeds)) if len(speeds) else 0.0


#: The measures an attractor can carry, by name: ``measure(case, attractor) -> float``.
MEASURES: dict[str, Callable[[Case, Attractor], float]] = {"impact_velocity": impact_velocity}


@dataclass(frozen=True)
class Measured:
    """The atlas's describer: the largest exponent from one return's monodromy (periodic) or the
    QR average over ``lyapunov_periods`` (aperiodic), NaN where it cannot be computed, the
    ``measures`` named (of :data:`MEASURES`) and the ``responses`` named."""

    lyapunov_periods: int = 100
    measures: tuple[str, ...] = tuple(MEASURES)
    #: Response measures (:data:`~oscillator.orbits.response.COLUMNS`) of each attractor
    #: (:meth:`_responses`).
    responses: tuple[str, ...] = ()
    #: The cut-off (Hz) of ``force_above`` and ``a_above`` among them.
    cutoff: float = 0.0

    def __call__(self, case: Case, attractor: Attractor) -> Attractor:
        values = {name: MEASURES[name](case, attractor) for name in self.measures}
        values |= self._responses(case, attractor)
        period = case.parameters.period
        return dataclasses.replace(
            attractor, lyapunov=self._largest(case, attractor), forcing_period=period, measures=values
        )

    def _responses(self, case: Case, attractor: Attractor) -> dict[str, float]:
        """The ``responses`` named, over the run of
        :meth:`~oscillator.attractors.grouping.Attractor.window`: of a periodic attractor one
        return from its last section point (without Newton's refinement, as the exponent); of an
        aperiodic one a long-run average, its peaks the largest seen.  NaN where the run fails."""
        from oscillator.orbits.response import response

        if not self.responses:
            return {}
        try:
            point, periods = attractor.window()
            begin = dict(zip(case.system.state, (float(v) for v in point), strict=True))
            columns = response(resolve_case(case, **begin), periods, self.cutoff).columns()
        except OscillatorError:
            columns = {}
        return {name: columns.get(name, math.nan) for name in self.responses}

    def _largest(self, case: Case, attractor: Attractor) -> float:
        try:
            if attractor.period:
                image = period_map(case, case.initial.t0, attractor.points[-1], attractor.period, derivative=True)
                assert image.monodromy is not None
                span = attractor.period * case.parameters.period
                return largest_exponent(np.linalg.eigvals(image.monodromy), span)
            return lyapunov(case, guess=attractor.points[-1], transient=0, periods=self.lyapunov_periods).largest
        except OscillatorError:
            return math.nan
