"""The model's steady responses at the measured points, with their exact derivatives.

At each distinct value of the measured parameter the model's periodic orbit is found (the first
time from the system's start after a transient, as a test rig settles; then by Newton from where
it was at the fit's previous parameters, so that the fit follows one orbit) and differentiated
through every switch (:func:`oscillator.sensitivities`): each measured row takes its measure's
value and derivatives from there.

The derivative does not exist where the orbit grazes a boundary or rests on its static threshold
(the sensitivities refuse it, ``reason = "not_differentiable"``): there the row's derivatives are
central differences of the orbit's measures, and a note says where.  Where the orbit's switching
sequence changes between two fit steps (a grazing or sticking boundary crossed), a crossing is
recorded: the sensitivities hold on each side, not across.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from oscillator.calibrating.measured import Measured
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.orbits.shooting import find_orbit
from oscillator.text import printable

__all__ = ["Crossing", "Responses"]

#: The relative step of the central differences where no derivative exists.
STEP = 1e-6


@dataclass(frozen=True)
class Crossing:
    """The orbit at ``at`` (the measured parameter's value) changed its switching sequence at
    the fit's step ``evaluation``: ``before`` and ``after`` are its switches' counts."""

    evaluation: int
    at: float
    before: int
    after: int


def _signature(switches: pd.DataFrame) -> tuple[Any, ...]:
    """The switching sequence of a return: each switch's domains (the article's system) or its
    element and kind (a declared system), in order."""
    words = switches.select_dtypes(exclude="number")
    return tuple(tuple(map(str, row)) for row in words.itertuples(index=False))


class Responses:
    """``responses(theta) -> (fitted, jacobian)`` over the rows of ``measured`` (module
    docstring); the orbits found are kept as the next call's guesses."""

    def __init__(self, system: Any, measured: Measured, names: Sequence[str], *, transient: int) -> None:
        self.system, self.measured, self.names = system, measured, tuple(names)
        self.transient = transient
        self.evaluations = 0
        self.crossings: list[Crossing] = []
        self.notes: list[str] = []
        self._guesses: dict[float, np.ndarray] = {}
        self._signatures: dict[float, tuple[Any, ...]] = {}
        table = measured.table
        self._rows = {float(v): np.flatnonzero(table[measured.over].to_numpy() == v) for v in measured.values}

    def __call__(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.evaluations += 1
        table = self.measured.table
        fitted = np.empty(len(table))
        jacobian = np.empty((len(table), len(self.names)))
        given = dict(zip(self.names, map(float, theta), strict=True))
        for at, rows in self._rows.items():
            measures = self._measures(at, given)
            for k in rows:
                name = table.measure.iloc[k]
                if name not in measures.index:
                    raise InputError(
                        f"data row {k + 1}: no response measure named {printable(name)!r}; choose one of "
                        f"{', '.join(measures.index[:8])}, ...",
                        field="measure",
                    )
                fitted[k] = measures.at[name, "value"]
                if not np.isfinite(fitted[k]):
                    raise SimulationFailed(
                        f"data row {k + 1}: the model's {name} is undefined at {self.measured.over} = {at:g} for "
                        f"{given} (no such event on its orbit); measure another response there",
                        reason=Reason.NO_ORBIT,
                    )
                jacobian[k] = measures.loc[name, [f"d/d{n}" for n in self.names]].to_numpy(dtype=float)
        return fitted, jacobian

    def _orbit(self, at: float, given: dict[str, float]) -> Any:
        overrides: dict[str, Any] = given | {self.measured.over: at}
        guess = self._guesses.get(at)
        try:
            orbit = find_orbit(self.system, guess=guess, transient=self.transient, **overrides)
        except SimulationFailed:
            if guess is None:
                raise
            orbit = find_orbit(self.system, transient=self.transient, **overrides)  # settle afresh
            self.notes.append(
                f"step {self.evaluations}, {self.measured.over} = {at:g}: Newton lost the orbit; settled afresh"
            )
        self._guesses[at] = np.asarray(orbit.state, dtype=float)
        return orbit

    def _measures(self, at: float, given: dict[str, float]) -> pd.DataFrame:
        """The orbit's measures at ``at`` and their derivatives in :attr:`names`."""
        orbit = self._orbit(at, given)
        try:
            found = orbit.sensitivities(self.names)
        except SimulationFailed as error:
            if error.reason is not Reason.NOT_DIFFERENTIABLE:
                raise
            self.notes.append(
                f"step {self.evaluations}, {self.measured.over} = {at:g}: {error}; derivatives by central differences"
            )
            return self._differences(at, given, orbit)
        signature = _signature(found.switches)
        before = self._signatures.get(at)
        if before is not None and before != signature:
            self.crossings.append(Crossing(self.evaluations, at, len(before), len(signature)))
        self._signatures[at] = signature
        return found.measures

    def _differences(self, at: float, given: dict[str, float], orbit: Any) -> pd.DataFrame:
        """The measures at ``given`` and central differences of them in each parameter."""
        table = pd.DataFrame({"value": _values(orbit)})
        for name in self.names:
            h = STEP * max(abs(given[name]), 1.0)
            sides = []
            for sign in (1, -1):
                moved: dict[str, Any] = given | {name: given[name] + sign * h, self.measured.over: at}
                sides.append(_values(find_orbit(self.system, guess=orbit.state, transient=self.transient, **moved)))
            table[f"d/d{name}"] = (sides[0] - sides[1]) / (2 * h)
        return table


def _values(orbit: Any) -> pd.Series:
    """Every response measure of an orbit of the article's system or of a declared one."""
    from oscillator.orbits.chain_orbits import ChainOrbit

    if isinstance(orbit, ChainOrbit):
        from oscillator.orbits.chain_response import orbit_measures

        return pd.Series(orbit_measures(orbit), dtype=float)
    return pd.Series(orbit.response().columns(), dtype=float)
