"""The model's trajectory at the measured times, with its exact forward sensitivities.

One run of the model from its start to the last measured time (CVODE, its tolerances at most
1e-12 as for orbits), then the tangent equations along each of its smooth pieces and the
saltation rule with the switch times' own derivatives at each switch
(:func:`oscillator.orbits.sensitivity.tangent_pass`, the pass the orbits' sensitivities use, here
from ``sigma = 0`` at the fixed start): ``y(t_k)`` and ``dy(t_k)/dc`` at every measured time
``t_k``, through stick, slip and impact.  A declared system's run takes its own tangent pass
(:func:`oscillator.orbits.chain_tangents.tangent_pass`, from ``Psi = 0``).  Where the run's
sequence of events changes between two fit steps, a crossing is recorded: the derivatives hold
on each side, not across.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from oscillator.calibrating.measured import Measured
from oscillator.calibrating.steady import Crossing
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case
from oscillator.model.chains import FrictionChain
from oscillator.orbits.sensitivity import tangent_pass
from oscillator.orbits.shooting import orbit_case

__all__ = ["Series", "chain_trajectory_sensitivities", "trajectory_sensitivities"]

#: The run ends this share of a forcing period after the last measured time (a time must lie
#: inside a piece of the run).
_BEYOND = 1e-3


def trajectory_sensitivities(
    case: Case, names: Sequence[str], times: Sequence[float] | np.ndarray
) -> tuple[np.ndarray, np.ndarray, pd.DataFrame]:
    """``(states, derivatives, events)`` of ``case``'s run (module docstring): the state at each
    of ``times`` (n x 4), its derivatives in ``names`` (n x 4 x k), and the run's events up to
    the last of ``times`` (``t``, ``kind``, ``mass``)."""
    names, marks = tuple(names), [float(t) for t in times]
    k = len(names)
    end = max(marks) + _BEYOND * case.parameters.period
    result = simulate(case, t_end=end, save=SaveAt(steps=False, segments=True))
    along = tangent_pass(result.segments, case.parameters, names, np.zeros((4, k)), end, np.zeros(k), marks)
    states = np.array([m[:4] for m in along.marks])
    derivatives = np.array([m[4:].reshape(4, k) for m in along.marks])
    within = result.events[result.events.t <= max(marks)]
    return states, derivatives, within[["t", "kind", "mass"]].astype({"kind": str}).reset_index(drop=True)


def chain_trajectory_sensitivities(
    chain: FrictionChain, names: Sequence[str], times: Sequence[float] | np.ndarray
) -> tuple[np.ndarray, np.ndarray, pd.DataFrame]:
    """As :func:`trajectory_sensitivities` for a declared system: its run to the last of
    ``times`` (the solver stopping at each, tolerances as its orbits'), then its tangent pass
    (:func:`oscillator.orbits.chain_tangents.tangent_pass`, ``Psi = 0`` at the start); the
    events' ``mass`` is the element's name."""
    from oscillator.hybrid.chain_run import rows_at, simulate_chain
    from oscillator.orbits.chain_orbits import ORBIT_OPTIONS
    from oscillator.orbits.chain_tangents import tangent_pass as chain_pass

    marks = np.asarray(times, dtype=float)
    end = float(marks.max()) + _BEYOND * chain.period
    run = simulate_chain(chain, t_end=end, options=ORBIT_OPTIONS, at=marks)
    along = chain_pass(run, names)
    n = len(chain.system.state)
    states = run.states[rows_at(run.times, marks, chain.period)]
    derivatives = np.array([along.at(float(t))[:, n:] for t in marks])
    events = run.events
    within = events[events.t <= marks.max()]
    table = pd.DataFrame({"t": within.t, "kind": within.kind.astype(str), "mass": within.element.astype(str)})
    return states, derivatives, table.reset_index(drop=True)


class Series:
    """``series(theta) -> (fitted, jacobian)`` over the rows of a measured time series, of the
    article's system or of a declared one."""

    def __init__(self, case: Case | FrictionChain, measured: Measured, names: Sequence[str]) -> None:
        self.case, self.measured, self.names = case, measured, tuple(names)
        self.evaluations = 0
        self.crossings: list[Crossing] = []
        self.notes: list[str] = []
        table = measured.table
        self._times, self._row_time = np.unique(table.t.to_numpy(), return_inverse=True)
        self._row_variable = np.array([case.system.state.index(v) for v in table.variable])
        self._events: pd.DataFrame | None = None

    def __call__(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        given = dict(zip(self.names, map(float, theta), strict=True))
        if isinstance(self.case, FrictionChain):
            found = chain_trajectory_sensitivities(self.case.with_values(given), self.names, self._times)
        else:
            found = trajectory_sensitivities(orbit_case(self.case, given), self.names, self._times)
        states, derivatives, events = found
        before = self._events
        if before is not None and not before[["kind", "mass"]].equals(events[["kind", "mass"]]):
            self.crossings.append(Crossing(self.evaluations, _first_change(before, events), len(before), len(events)))
        self._events = events
        fitted = states[self._row_time, self._row_variable]
        return fitted, derivatives[self._row_time, self._row_variable, :]


def _first_change(before: pd.DataFrame, after: pd.DataFrame) -> float:
    """The time of the first event in which two runs' sequences differ (the later run's)."""
    n = min(len(before), len(after))
    differ = [(before.kind[i], before.mass[i]) != (after.kind[i], after.mass[i]) for i in range(n)]
    first = differ.index(True) if True in differ else n
    return float(after.t[first] if first < len(after) else before.t[first])
