"""The model's event times matched to measured ones, with their exact derivatives.

One run of the model to a forcing period past the last measured time, then the tangent pass
along it (:func:`oscillator.orbits.sensitivity.tangent_pass`): at each switch the switch time's
derivative ``tau = dt_s/dc = -(n . sigma- + dh/dc) / (n . f- + h_t)`` in every parameter.  Each
measured event (its kind, and its mass where given) is matched to the model's event of that kind
nearest in time; a kind the run does not have refuses the step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from oscillator.calibrating.measured import Measured
from oscillator.calibrating.steady import Crossing
from oscillator.errors import Reason, SimulationFailed
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case
from oscillator.orbits.sensitivity import tangent_pass
from oscillator.orbits.shooting import orbit_case

__all__ = ["Events", "event_sensitivities"]


def event_sensitivities(case: Case, names: Sequence[str], end: float) -> pd.DataFrame:
    """Every switching event of ``case``'s run to ``end`` after its start: ``t``, ``kind``,
    ``mass`` and ``dt/d<name>`` for each of ``names`` (the switch time's derivative)."""
    names = tuple(names)
    k = len(names)
    result = simulate(case, t_end=end, save=SaveAt(steps=False, segments=True))
    along = tangent_pass(result.segments, case.parameters, names, np.zeros((4, k)), end, np.zeros(k))
    times = np.array([s.t for s in along.switches])
    taus = np.array([s.tau for s in along.switches]).reshape(len(times), k)
    events = result.events[["t", "kind", "mass"]].astype({"kind": str}).reset_index(drop=True)
    events = events[events.t > case.initial.t0].reset_index(drop=True)
    at = np.clip(np.searchsorted(times, events.t.to_numpy() - 1e-12 * np.maximum(1.0, events.t.abs())), 0, None)
    held = (at < len(times)) & np.isclose(times[np.minimum(at, len(times) - 1)], events.t.to_numpy(), rtol=1e-12)
    events = events[held].reset_index(drop=True)
    at = at[held]
    for j, name in enumerate(names):
        events[f"dt/d{name}"] = taus[at, j]
    return events


class Events:
    """``events(theta) -> (fitted, jacobian)`` over measured event times (module docstring)."""

    def __init__(self, case: Case, measured: Measured, names: Sequence[str]) -> None:
        self.case, self.measured, self.names = case, measured, tuple(names)
        self.evaluations = 0
        self.crossings: list[Crossing] = []
        self.notes: list[str] = []
        self._end = float(measured.table.t.max()) + case.parameters.period
        self._sequence: tuple[tuple[str, int], ...] | None = None

    def __call__(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        case = orbit_case(self.case, dict(zip(self.names, map(float, theta), strict=True)))
        events = event_sensitivities(case, self.names, self._end)
        sequence = tuple(zip(events.kind, events.mass, strict=True))
        if self._sequence is not None and sequence != self._sequence:
            self.crossings.append(Crossing(self.evaluations, float("nan"), len(self._sequence), len(sequence)))
        self._sequence = sequence
        table = self.measured.table
        fitted = np.empty(len(table))
        jacobian = np.empty((len(table), len(self.names)))
        columns = [f"dt/d{name}" for name in self.names]
        for k, (kind, mass, t) in enumerate(zip(table.kind, table.mass, table.t, strict=True)):
            same = events[(events.kind == kind) & ((events.mass == mass) | (mass == 0))]
            if same.empty:
                raise SimulationFailed(
                    f"data row {k + 1}: the model has no {kind} event{f' of m{mass}' if mass else ''} before "
                    f"t = {self._end:g} s at {dict(zip(self.names, theta, strict=True))}",
                    reason=Reason.NO_ORBIT,
                )
            nearest = same.iloc[int(np.argmin(np.abs(same.t.to_numpy() - t)))]
            fitted[k] = nearest.t
            jacobian[k] = nearest[columns].to_numpy(dtype=float)
        return fitted, jacobian
