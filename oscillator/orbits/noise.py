"""Noise measures of a periodic motion of the article's system: what engineers who fight rattle
read off a motion, per contact (docs/noise.md).

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
  energy per period over ``T``: the energy audit);
* the contact force's Fourier coefficients over the return, harmonic ``k`` at ``k / nT`` Hz
  (:func:`~oscillator.orbits.spectra.fourier_coefficients`, exact on each smooth piece), and
  its level above a cut-off, in dB re 1 N, A-weighted if asked.

Each contact piece is integrated again from its start as the response measures integrate it
(:mod:`oscillator.orbits.pieces`, DOP853 at 1e-12, compiled) and its dense output is read at the
quadrature's nodes: the measures come from the motion's own pieces, not from samples.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from oscillator.errors import InputError
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, not_a_case
from oscillator.model.fields import C3, D1, K6, coefficients
from oscillator.model.parameters import check_count
from oscillator.orbits.pieces import ARTICLE_PIECE, IntegratedPiece, article_data, integrate_piece, mode_flags
from oscillator.orbits.response import TOLERANCE, left_force, measured
from oscillator.orbits.spectra import Piece, fourier_coefficients, level_db, mean_square_above
from oscillator.orbits.tangent import INTEGRALS

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = ["HARMONICS", "ContactNoise", "Noise", "noise"]

#: Harmonics of the return's frequency kept in each contact force's spectrum by default.
HARMONICS = 200


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
    coefficients: np.ndarray
    fundamental: float

    @property
    def impulse_rate(self) -> float:
        """The contact's mean force (N): impulses per second times the mean impulse."""
        return self.rate * self.impulse

    def level(self, cutoff: float = 0.0, *, weighted: bool = False) -> float:
        """The contact force's level (dB re 1 N) from its harmonics above ``cutoff`` Hz, A-weighted
        if ``weighted``; ``-inf`` without contact."""
        return level_db(mean_square_above(self.coefficients, self.fundamental, cutoff, weighted=weighted))

    def spectrum(self) -> pd.DataFrame:
        """The contact force's harmonics: ``harmonic`` ``k``, ``frequency`` (Hz), ``amplitude`` (N,
        ``2 |c_k|``, the mean ``|c_0|`` at ``k = 0``) and ``level`` (dB re 1 N of its mean square)."""
        import pandas as pd

        k = np.arange(len(self.coefficients))
        amplitude = np.abs(self.coefficients) * np.where(k == 0, 1.0, 2.0)
        square = np.abs(self.coefficients) ** 2 * np.where(k == 0, 1.0, 2.0)
        with np.errstate(divide="ignore"):
            level = 10.0 * np.log10(square)
        return pd.DataFrame({"harmonic": k, "frequency": k * self.fundamental, "amplitude": amplitude, "level": level})


@dataclass(frozen=True)
class Noise:
    """The noise measures of a return (:func:`noise`): ``contacts["right"]``, ``contacts["left"]``."""

    periods: int
    span: float
    contacts: dict[str, ContactNoise]

    @property
    def power(self) -> float:
        """The power both contacts dissipate (W)."""
        return sum(contact.power for contact in self.contacts.values())

    def columns(self, cutoff: float = 0.0) -> dict[str, float]:
        """Every measure as a flat mapping: ``impact_rate_right``, ``impulse_left``, ...,
        ``force_level_right`` (dB re 1 N above ``cutoff`` Hz)."""
        flat: dict[str, float] = {}
        for name, c in self.contacts.items():
            flat |= {f"impact_rate_{name}": c.rate, f"impulse_{name}": c.impulse}
            flat |= {f"impulse_rate_{name}": c.impulse_rate, f"impact_energy_{name}": c.energy}
            flat |= {f"impact_power_{name}": c.power, f"force_level_{name}": c.level(cutoff)}
        return flat


def _right_force(piece: IntegratedPiece, c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The right stop's force on the piece at times ``t``: ``K6 (x1 - d1)``."""
    force: np.ndarray = c[K6] * (piece(t)[0] - c[D1])
    return force


def _left_force(piece: IntegratedPiece, c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The left contact's compressive force on the piece at times ``t``."""
    return -left_force(piece(t), c)


def _left_loss(piece: IntegratedPiece, c: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The power the left contact's damper dissipates at times ``t``: ``C3 (v1 - v2)^2``."""
    y = piece(t)
    loss: np.ndarray = c[C3] * (y[1] - y[3]) ** 2
    return loss


def noise(case: Case, periods: int = 1, harmonics: int = HARMONICS) -> Noise:
    """The noise measures of the case's motion from its start over ``periods`` forcing periods
    (module docstring): of an orbit, over its return (:meth:`oscillator.Orbit.noise`)."""
    if not isinstance(case, Case):
        raise InputError(not_a_case(case), field="case")
    check_count(periods, "periods", 1, 100_000)
    check_count(harmonics, "harmonics", 0, 100_000)
    p, c = case.parameters, coefficients(case.parameters)
    span = periods * p.period
    result = simulate(case, t_end=case.initial.t0 + span, save=SaveAt(steps=False, segments=True))
    response = measured(result, periods)
    forces: dict[str, list[Piece]] = {"right": [], "left": []}
    losses: list[Piece] = []
    for segment in result.segments:
        mode = segment.mode
        if not segment.t1 > segment.t0 or not (mode.left or mode.right):
            continue
        data = article_data(mode_flags(mode), np.zeros(0, np.int64), c)
        start = np.concatenate([segment.y0, np.zeros(INTEGRALS)])
        span_ = (segment.t0, segment.t1)
        solved = integrate_piece(ARTICLE_PIECE, data, span_, start, rtol=TOLERANCE, atol=TOLERANCE, dense=True)
        if mode.right:
            forces["right"].append((*span_, functools.partial(_right_force, solved, c)))
        if mode.left:
            forces["left"].append((*span_, functools.partial(_left_force, solved, c)))
            losses.append((*span_, functools.partial(_left_loss, solved, c)))
    lost = {"right": 0.0, "left": span * float(fourier_coefficients(losses, span, 0)[0].real)}
    contacts = {}
    for name in ("right", "left"):
        series = fourier_coefficients(forces[name], span, harmonics)
        given = response.contact[name]
        onsets = round(given["onsets"] * periods)
        per = 1.0 / onsets if onsets else math.nan
        contacts[name] = ContactNoise(
            contact=name,
            onsets=onsets,
            rate=onsets / span,
            impulse=float(series[0].real) * span * per if onsets else 0.0,
            energy=lost[name] * per if onsets else 0.0,
            power=lost[name] / span,
            impact_max=given["impact_max"],
            impact_mean=given["impact_mean"],
            coefficients=series,
            fundamental=1.0 / span,
        )
    return Noise(periods, span, contacts)
