"""Noise measures of a periodic motion of the article's system: what engineers who fight rattle
read off a motion, per contact and per mass (docs/noise.md).

Over one return of ``n`` forcing periods (``nT`` seconds), per contact (``right``: m1 on the
stop at ``x1 = d1``; ``left``: m1 on m2's stop, ``z1 = -d``), with ``F`` the contact force,
compressive positive (``K6 (x1 - d1)`` on the right, ``-(K3 (x1 - x2 + d) + C3 (v1 - v2))`` on
the left) and ``N`` the contacts begun in the return:

* ``rate`` (1/s): impacts per second, ``N / nT``;
* ``impulse`` (N s): the mean impulse of an impact, ``integral F dt / N``; ``impulse_rate`` (N):
  ``rate * impulse``, the contact's mean force;
* ``energy`` (J): the energy an impact loses, ``integral C3 (v1 - v2)^2 dt / N`` on the left
  (its damper) and 0 on the right (``K6`` has no damper: its impacts are elastic);
* ``power`` (W): ``rate * energy``, the power the contact dissipates (the response's ``contact``
  energy per period over ``T``: the energy audit; ``rate``, ``impulse``, ``energy`` and ``power``
  are the response measures' own, :func:`~oscillator.orbits.response.impacts`);
* ``force``: the contact force's spectrum over the return, harmonic ``k`` at ``k / nT`` Hz
  (:class:`~oscillator.orbits.spectra.Spectrum`, exact on each smooth piece), levels in dB re
  1 N;

and per mass ``i``: ``acceleration``, the spectrum of ``a_i`` (the mode's field, 0 at rest;
levels in dB re 1e-6 m/s^2, ISO 1683), and the steps of ``a_i`` where the mass sticks or slips
(``slips``: how many in the return; ``step_max``: the largest, m/s^2; the jerk there is an
impulse of that size).

Each smooth piece is integrated again from its start as the response measures integrate it
(:mod:`oscillator.orbits.pieces`, DOP853 at 1e-12, compiled) and its dense output is read at the
quadrature's nodes: the measures come from the motion's own pieces, not from samples.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oscillator.compiled import njit
from oscillator.errors import InputError
from oscillator.hybrid.record import Segment
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, not_a_case
from oscillator.model.fields import D1, K6, coefficients
from oscillator.model.kernels import rates
from oscillator.model.parameters import check_count
from oscillator.model.phase_space import Mode
from oscillator.orbits.pieces import IntegratedPiece, mode_flags
from oscillator.orbits.response import Response, above, branch_points, integrated, left_force, measured
from oscillator.orbits.spectra import (
    ACCELERATION_REFERENCE,
    FORCE_REFERENCE,
    HARMONICS,
    Piece,
    Spectrum,
    fourier_coefficients,
    spectra_table,
)
from oscillator.presenting import presenter

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.figure import Figure

    from oscillator.orbits.branch import Branch

__all__ = ["HARMONICS", "ContactNoise", "MassNoise", "Noise", "branch_noise", "noise", "point_noise", "response_above"]


@dataclass(frozen=True)
class ContactNoise:
    """One contact's noise measures over a return (module docstring)."""

    contact: str
    onsets: int
    rate: float
    impulse: float
    energy: float
    power: float
    impact_max: float
    impact_mean: float
    force: Spectrum

    @property
    def impulse_rate(self) -> float:
        """The contact's mean force (N): impulses per second times the mean impulse."""
        return self.rate * self.impulse


@dataclass(frozen=True)
class MassNoise:
    """One mass's noise measures over a return (module docstring)."""

    mass: int
    acceleration: Spectrum
    slips: int
    step_max: float


@dataclass(frozen=True)
class Noise:
    """The noise measures of a return (:func:`noise`): ``contacts["right"]``, ``contacts["left"]``,
    ``masses[1]``, ``masses[2]``; ``case`` the motion's start, ``span`` the return (s)."""

    case: Case
    periods: int
    span: float
    contacts: dict[str, ContactNoise]
    masses: dict[int, MassNoise]

    def plot(self) -> Figure:
        """The contact forces' and the masses' accelerations' spectra in dB against frequency,
        the harmonics of Omega marked (docs/noise.md)."""
        return presenter().plot_noise(self)

    @property
    def power(self) -> float:
        """The power both contacts dissipate (W)."""
        return sum(contact.power for contact in self.contacts.values())

    def spectra(self) -> pd.DataFrame:
        """Every spectrum as one table: ``signal`` (``force_right``, ``force_left``,
        ``acceleration_m1``, ``acceleration_m2``), its ``unit`` and ``reference`` (of the levels),
        then :meth:`~oscillator.orbits.spectra.Spectrum.table`'s columns, harmonic by harmonic."""
        named = {f"force_{name}": c.force for name, c in self.contacts.items()}
        named |= {f"acceleration_m{i}": m.acceleration for i, m in self.masses.items()}
        return spectra_table(named)

    def columns(self, cutoff: float = 0.0) -> dict[str, float]:
        """Every measure as a flat mapping: ``impact_rate_right``, ``impulse_left``, ...,
        ``force_level_right`` (dB re 1 N above ``cutoff`` Hz), ``acceleration_level_m1`` (dB re
        1e-6 m/s^2 above ``cutoff`` Hz), ``slip_step_max_m2``."""
        flat: dict[str, float] = {}
        for name, c in self.contacts.items():
            flat |= {f"impact_rate_{name}": c.rate, f"impulse_{name}": c.impulse}
            flat |= {f"impulse_rate_{name}": c.impulse_rate, f"impact_energy_{name}": c.energy}
            flat |= {f"impact_power_{name}": c.power, f"force_level_{name}": c.force.level(cutoff)}
        for i, m in self.masses.items():
            flat |= {f"acceleration_level_m{i}": m.acceleration.level(cutoff), f"slip_step_max_m{i}": m.step_max}
        return flat


def _signals(piece: IntegratedPiece, mode: Mode, c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The four signals on the piece at times ``t``, ``(len(t), 4)``: the right stop's force and
    the left contact's (compressive, 0 while open), m1's and m2's accelerations (the mode's field,
    0 for a resting mass)."""
    y = np.ascontiguousarray(piece(t)[:4].T)
    s1, s2, left, right = mode_flags(mode)
    found = np.zeros((len(t), 4))
    if right:
        found[:, 0] = c[K6] * (y[:, 0] - c[D1])
    if left:
        found[:, 1] = -left_force(y.T, c)
    field = np.empty((len(t), 2))
    _field_rows(np.asarray(t, dtype=float), y, c, (s1, s2, left, right), field)
    found[:, 2:] = field
    return found


@njit(cache=True)
def _field_rows(
    t: np.ndarray, y: np.ndarray, c: np.ndarray, mode: tuple[int, int, bool, bool], out: np.ndarray
) -> None:  # pragma: no cover - compiled
    """``out[k] = (a1, a2)``, the mode's field at ``(t[k], y[k])``."""
    s1, s2, left, right = mode
    for k in range(len(t)):
        r = rates(t[k], y[k, 0], y[k, 1], y[k, 2], y[k, 3], c, s1, s2, left, right)
        out[k, 0], out[k, 1] = r[1], r[3]


def _accelerations(t: float, y: np.ndarray, mode: Mode, c: np.ndarray) -> tuple[float, float]:
    """``(a1, a2)``: the mode's field at ``(t, y)`` (0 for a resting mass)."""
    s1, s2, left, right = mode_flags(mode)
    r = rates(t, float(y[0]), float(y[1]), float(y[2]), float(y[3]), c, s1, s2, left, right)
    return float(r[1]), float(r[3])


def _steps(segments: list[Segment], c: np.ndarray, mass: int) -> list[float]:
    """The steps of mass ``mass``'s acceleration where it sticks or starts to slip."""
    steps = []
    for before, after in itertools.pairwise(segments):
        if (before.mode.sign(mass) == 0) != (after.mode.sign(mass) == 0):
            a0 = _accelerations(before.t1, before.y1, before.mode, c)[mass - 1]
            a1 = _accelerations(after.t0, after.y0, after.mode, c)[mass - 1]
            steps.append(abs(a1 - a0))
    return steps


def _contact(name: str, coefficients: np.ndarray, given: dict[str, float], sizes: tuple[float, int]) -> ContactNoise:
    """Contact ``name``'s measures (module docstring) from its force's Fourier coefficients;
    ``given`` its response measures, ``sizes`` the return's span and forcing periods."""
    span, periods = sizes
    spectrum = Spectrum(coefficients, 1.0 / span, "N", FORCE_REFERENCE)
    onsets = round(given["onsets"] * periods)
    return ContactNoise(
        contact=name,
        onsets=onsets,
        rate=given["impact_rate"],
        impulse=given["impulse"],
        energy=given["impact_energy"],
        power=given["impact_power"],
        impact_max=given["impact_max"],
        impact_mean=given["impact_mean"],
        force=spectrum,
    )


def noise(case: Case, periods: int = 1, harmonics: int = HARMONICS) -> Noise:
    """The noise measures of the case's motion from its start over ``periods`` forcing periods
    (module docstring): of an orbit, over its return (:meth:`oscillator.Orbit.noise`)."""
    if not isinstance(case, Case):
        raise InputError(not_a_case(case), field="case")
    check_count(periods, "periods", 1, 100_000)
    check_count(harmonics, "harmonics", 0, 100_000)
    c = coefficients(case.parameters)
    span = periods * case.parameters.period
    segments, response, found = _spectra(case, periods, harmonics)
    contacts = {
        name: _contact(name, found[:, k], response.contact[name], (span, periods))
        for k, name in enumerate(("right", "left"))
    }
    masses = {}
    for i in (1, 2):
        spectrum = Spectrum(found[:, 1 + i], 1.0 / span, "m/s^2", ACCELERATION_REFERENCE)
        steps = _steps(segments, c, i)
        masses[i] = MassNoise(i, spectrum, len(steps), max(steps, default=0.0))
    return Noise(case, periods, span, contacts, masses)


def _spectra(case: Case, periods: int, harmonics: int) -> tuple[list[Segment], Response, np.ndarray]:
    """One run of ``periods`` forcing periods from the case's start: its smooth segments, its
    response measures and the four signals' Fourier coefficients to ``harmonics``, ``(harmonics +
    1, 4)`` (:func:`_signals`' columns), from the same pieces integrated again."""
    span = periods * case.parameters.period
    return _spectra_of(
        simulate(case, t_end=case.initial.t0 + span, save=SaveAt(steps=False, segments=True)), periods, harmonics
    )


def _spectra_of(result: Result, periods: int, harmonics: int) -> tuple[list[Segment], Response, np.ndarray]:
    """:func:`_spectra` of a run of ``periods`` forcing periods that kept its segments."""
    c = coefficients(result.case.parameters)
    span = periods * result.case.parameters.period
    segments = [segment for segment in result.segments if segment.t1 > segment.t0]
    pieces = [(segment, integrated(segment, c, dense=True)) for segment in segments]
    response = measured(result, periods, [piece for _, piece in pieces])
    parts: list[Piece] = [(s.t0, s.t1, functools.partial(_signals, piece, s.mode, c)) for s, piece in pieces]
    found = fourier_coefficients(parts, span, harmonics).reshape(harmonics + 1, 4)  # the four signals at once
    return segments, response, found


def response_above(result: Result, periods: int, below: int) -> Response:
    """The response measures of a run of ``periods`` forcing periods that kept its segments, with
    ``force_above`` and ``a_above`` above the return's ``below``-th harmonic
    (:func:`oscillator.orbits.response.measured_above` calls it)."""
    _, response, found = _spectra_of(result, periods, below)
    return above(response, found)


def branch_noise(branch: Branch, harmonics: int = HARMONICS, cutoff: float = 0.0) -> pd.DataFrame:
    """The noise measures at every point of a continued branch: one row per point with the
    parameter, ``stable``, ``piece`` and every column of :meth:`Noise.columns` (levels above
    ``cutoff`` Hz); against ``Omega``, the branch's noise response. Each point is measured from its
    section state over its return, as the branch holds it."""
    import pandas as pd

    return pd.DataFrame([row | found.columns(cutoff) for row, found in point_noise(branch, harmonics)])


def point_noise(branch: Branch, harmonics: int = HARMONICS) -> Iterator[tuple[dict[str, Any], Noise]]:
    """Each point of a continued branch: its row (the parameter, ``stable``, ``piece``) and its
    :class:`Noise` over its return from its section state, as the branch holds it."""
    check_count(harmonics, "harmonics", 0, 100_000)
    for row, case in branch_points(branch):
        yield row, noise(case, branch.period, harmonics)
