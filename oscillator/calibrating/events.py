"""The model's event times matched to measured ones, with their exact derivatives.

One run of the model to a forcing period past the last measured time, then the tangent pass
along it (:func:`oscillator.orbits.sensitivity.tangent_pass`, or a declared system's
:func:`oscillator.orbits.chain_tangents.tangent_pass`): at each switch the switch time's
derivative ``tau = dt_s/dc = -(n . sigma- + dh/dc) / (n . f- + h_t)`` in every parameter.  Each
measured event (its kind, and its mass or element where given) is matched to the model's event
of that kind nearest in time; a kind the run does not have refuses the step.
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
from oscillator.model.chains import FrictionChain
from oscillator.orbits.sensitivity import tangent_pass
from oscillator.orbits.shooting import orbit_case

__all__ = ["Events", "chain_event_sensitivities", "event_sensitivities"]


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


def chain_event_sensitivities(chain: FrictionChain, names: Sequence[str], end: float) -> pd.DataFrame:
    """Every switch of a declared system's run to ``end`` after its start: ``t``, ``kind``,
    ``element`` and ``dt/d<name>`` for each of ``names`` (the switch time's derivative, the start
    held: ``Psi = 0`` there, as for its time series)."""
    from oscillator.hybrid.chain_run import simulate_chain
    from oscillator.orbits.chain_orbits import ORBIT_OPTIONS
    from oscillator.orbits.chain_tangents import tangent_pass as chain_pass

    names = tuple(names)
    along = chain_pass(simulate_chain(chain, t_end=end, options=ORBIT_OPTIONS), names)
    held = np.zeros((len(chain.system.state), len(names)))
    switches = [c for c in along.crossings if c.t > chain.t0]
    events = pd.DataFrame({"t": [c.t for c in switches], "kind": [str(c.kind) for c in switches]})
    events["element"] = [c.element for c in switches]
    taus = np.array([c.time_derivative(held) for c in switches]).reshape(len(switches), len(names))
    for j, name in enumerate(names):
        events[f"dt/d{name}"] = taus[:, j]
    return events


class Events:
    """``events(theta) -> (fitted, jacobian)`` over measured event times (module docstring), of
    the article's system (matched by ``mass``) or of a declared one (by ``element``)."""

    def __init__(self, model: Case | FrictionChain, measured: Measured, names: Sequence[str]) -> None:
        self.model, self.measured, self.names = model, measured, tuple(names)
        self.by = "element" if isinstance(model, FrictionChain) else "mass"
        self.evaluations = 0
        self.crossings: list[Crossing] = []
        self.notes: list[str] = []
        period = model.period if isinstance(model, FrictionChain) else model.parameters.period
        self._end = float(measured.table.t.max()) + period
        self._sequence: tuple[tuple[str, object], ...] | None = None

    def _events(self, theta: np.ndarray) -> pd.DataFrame:
        values = dict(zip(self.names, map(float, theta), strict=True))
        if isinstance(self.model, FrictionChain):
            return chain_event_sensitivities(self.model.with_values(values), self.names, self._end)
        return event_sensitivities(orbit_case(self.model, values), self.names, self._end)

    def __call__(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        events = self._events(theta)
        sequence = tuple(zip(events.kind, events[self.by], strict=True))
        if self._sequence is not None and sequence != self._sequence:
            self.crossings.append(Crossing(self.evaluations, float("nan"), len(self._sequence), len(sequence)))
        self._sequence = sequence
        table = self.measured.table
        fitted = np.empty(len(table))
        jacobian = np.empty((len(table), len(self.names)))
        columns = [f"dt/d{name}" for name in self.names]
        for k, (kind, which, t) in enumerate(zip(table.kind, table[self.by], table.t, strict=True)):
            same = events[(events.kind == kind) & ((events[self.by] == which) | (which in (0, "")))]
            if same.empty:
                of = (f" of m{which}" if self.by == "mass" else f" of {which}") if which not in (0, "") else ""
                raise SimulationFailed(
                    f"data row {k + 1}: the model has no {kind} event{of} before t = {self._end:g} s at "
                    f"{dict(zip(self.names, theta, strict=True))}",
                    reason=Reason.NO_ORBIT,
                )
            nearest = same.iloc[int(np.argmin(np.abs(same.t.to_numpy() - t)))]
            fitted[k] = nearest.t
            jacobian[k] = nearest[columns].to_numpy(dtype=float)
        return fitted, jacobian
