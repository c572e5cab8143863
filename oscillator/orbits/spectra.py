"""Fourier series of a periodic signal known piece by piece, and the levels engineers read off
them (docs/noise.md).

A signal ``f`` of period ``P`` that is smooth on each of its pieces (a contact force over each
smooth piece of an orbit, zero between contacts) has the coefficients

    c_k = 1/P integral_0^P f(t) exp(-2 pi i k t / P) dt,   k = 0, 1, ..., K,

computed here by Gauss-Legendre quadrature on each piece, split so that no sub-interval is longer
than the highest harmonic's period, nor than a :data:`STRETCHES`-th of ``P``: with :data:`NODES`
nodes a sub-interval integrates a polynomial of degree ``2 NODES - 1`` exactly (and the
harmonic's half turn on each side of its middle to about 1e-30), so a smooth piece's coefficients
are exact to rounding, however the signal
jumps between pieces (a sampled FFT would alias the jumps).  The
mean square is ``|c_0|^2 + 2 sum_k |c_k|^2`` (Parseval), the harmonic ``k`` at ``k / P`` Hz.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from oscillator.errors import InputError
from oscillator.model.parameters import check_count
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = [
    "HARMONICS",
    "NODES",
    "STRETCHES",
    "Piece",
    "Spectrum",
    "a_weighting",
    "check_cutoff",
    "fourier_coefficients",
    "harmonics_below",
    "level_db",
    "mean_square_above",
    "quadrature_nodes",
    "spectra_table",
]

#: A piece of a signal: ``(t0, t1, f)``, ``f`` its values at an array of times in ``[t0, t1]``
#: (or, for several signals at once, an array ``(times, signals)``).
Piece = tuple[float, float, Callable[[np.ndarray], np.ndarray]]

#: Harmonics of a return's frequency kept in a spectrum by default.
HARMONICS = 200

#: Gauss-Legendre nodes per sub-interval.
NODES = 16
#: The fewest stretches a period is split into: no stretch longer than a sixteenth of it, nor than
#: the highest harmonic's period (a few harmonics of a long piece are as exact as many).
STRETCHES = 16
#: The decibel references: of a force level, 1 N; of an acceleration level, 1e-6 m/s^2 (ISO 1683).
FORCE_REFERENCE, ACCELERATION_REFERENCE = 1.0, 1e-6


def quadrature_nodes(t0: float, t1: float, longest: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre's :data:`NODES` nodes on ``[t0, t1]`` split so that no stretch is longer
    than ``longest``, and their weights (scaled to the stretches: ``sum weights f(nodes)`` is the
    integral)."""
    nodes, weights = np.polynomial.legendre.leggauss(NODES)
    count = max(1, math.ceil((t1 - t0) / longest))
    edges = np.linspace(t0, t1, count + 1)
    half = 0.5 * np.diff(edges)
    times = ((edges[:-1] + edges[1:]) * 0.5)[:, None] + half[:, None] * nodes[None, :]
    return times.ravel(), (half[:, None] * weights[None, :]).ravel()


def fourier_coefficients(pieces: Sequence[Piece], period: float, harmonics: int) -> np.ndarray:
    """``c_0, ..., c_K`` (``K = harmonics``) of the signal of period ``period`` that is ``f(t)`` on
    each piece ``(t0, t1, f)`` (``f`` takes an array of times) and zero elsewhere (module
    docstring); the pieces lie in one period and do not overlap.  Where ``f`` gives several
    signals at once (an array ``(times, signals)``), their coefficients are the columns of an
    array ``(harmonics + 1, signals)``."""
    check_count(harmonics, "harmonics", 0, 100_000)
    if not period > 0 or not math.isfinite(period):
        raise InputError(f"period must be a positive number of seconds, got {period!r}", field="period")
    longest = period / max(harmonics, STRETCHES)
    total: np.ndarray | float = 0.0
    for t0, t1, f in pieces:
        if not t1 > t0:
            continue
        times, scale = quadrature_nodes(t0, t1, longest)
        values = np.asarray(f(times), dtype=float)
        values = values * (scale if values.ndim == 1 else scale[:, None])
        total = total + _waves(times, period, harmonics) @ values
    coefficients: np.ndarray = np.asarray(total, dtype=complex) / period
    if coefficients.ndim == 0:  # no piece: the signal is zero
        coefficients = np.zeros(harmonics + 1, dtype=complex)
    return coefficients


#: Harmonics between two whose waves :func:`_waves` computes directly (the others by products).
_BLOCK = 32


def _waves(times: np.ndarray, period: float, harmonics: int) -> np.ndarray:
    """``exp(-2 pi i k t / period)`` for ``k = 0 .. harmonics`` (rows) at ``times`` (columns):
    every :data:`_BLOCK`-th harmonic's directly, those between as its product with the powers of
    the first (a few roundings each, not ``k``: an exponential costs tens of products)."""
    first = np.exp(-2j * np.pi * times / period)
    steps = np.empty((_BLOCK, len(times)), dtype=complex)
    steps[0] = 1.0
    if _BLOCK > 1:
        steps[1:] = np.cumprod(np.broadcast_to(first, (_BLOCK - 1, len(times))), axis=0)
    anchors = np.exp(-2j * np.pi * np.outer(np.arange(0, harmonics + 1, _BLOCK), times) / period)
    waves = (anchors[:, None, :] * steps[None, :, :]).reshape(-1, len(times))
    return waves[: harmonics + 1]


def a_weighting(frequency: np.ndarray) -> np.ndarray:
    """The A-weighting gain (dB) at ``frequency`` (Hz), IEC 61672-1: 0 dB at 1 kHz, about -19 dB
    at 100 Hz, -50 dB at 20 Hz; ``-inf`` at 0 Hz."""
    f2 = np.asarray(frequency, dtype=float) ** 2
    with np.errstate(divide="ignore"):
        ra = (12194.0**2 * f2**2) / ((f2 + 20.6**2) * np.sqrt((f2 + 107.7**2) * (f2 + 737.9**2)) * (f2 + 12194.0**2))
        gain: np.ndarray = 20.0 * np.log10(ra) + 2.0
    return gain


def check_cutoff(cutoff: object, field: str = "cutoff") -> float:
    """``cutoff``, a frequency in Hz of 0 or more, or the error that names ``field``."""
    if not isinstance(cutoff, int | float) or isinstance(cutoff, bool) or not (math.isfinite(cutoff) and cutoff >= 0):
        raise InputError(f"{field} must be a frequency in Hz, 0 or more, got {shown(cutoff)}", field=field)
    return float(cutoff)


def harmonics_below(cutoff: float, span: float) -> int:
    """How many harmonics of a return of ``span`` seconds lie above 0 Hz and at or below ``cutoff``
    Hz: harmonic ``k`` is at ``k / span`` Hz."""
    return math.floor(cutoff * span * (1 + 1e-12))


def mean_square_above(
    coefficients: np.ndarray, fundamental: float, cutoff: float = 0.0, *, weighted: bool = False
) -> float:
    """The mean square of the harmonics above ``cutoff`` Hz (``2 |c_k|^2`` each, the harmonic ``k``
    at ``k fundamental`` Hz; the mean ``c_0`` never counts), A-weighted if ``weighted``."""
    k = np.arange(1, len(coefficients))
    frequency = k * fundamental
    power = 2.0 * np.abs(coefficients[1:]) ** 2
    if weighted:
        power = power * 10.0 ** (a_weighting(frequency) / 10.0)
    return float(power[frequency > cutoff].sum())


def level_db(mean_square: float, reference: float = FORCE_REFERENCE) -> float:
    """``10 log10(mean_square / reference^2)`` (dB re ``reference``); ``-inf`` for nothing."""
    return 10.0 * math.log10(mean_square / reference**2) if mean_square > 0 else -math.inf


@dataclass(frozen=True)
class Spectrum:
    """A periodic signal's Fourier coefficients ``c_0, ..., c_K`` (:func:`fourier_coefficients`),
    harmonic ``k`` at ``k fundamental`` Hz, in ``unit``, its levels in dB re ``reference``."""

    coefficients: np.ndarray
    fundamental: float
    unit: str
    reference: float

    @property
    def mean(self) -> float:
        """The signal's mean, ``c_0``."""
        return float(self.coefficients[0].real)

    def level(self, cutoff: float = 0.0, *, weighted: bool = False) -> float:
        """The level (dB re :attr:`reference`) of the harmonics above ``cutoff`` Hz, the mean left
        out, A-weighted if ``weighted``; ``-inf`` for a constant signal."""
        square = mean_square_above(self.coefficients, self.fundamental, cutoff, weighted=weighted)
        return level_db(square, self.reference)

    def table(self) -> pd.DataFrame:
        """One row per harmonic: ``harmonic`` ``k``, ``frequency`` (Hz), ``amplitude`` (``2 |c_k|``;
        the mean ``|c_0|`` at ``k = 0``) and ``level`` (dB re :attr:`reference` of its mean square)."""
        import pandas as pd

        k = np.arange(len(self.coefficients))
        twice = np.where(k == 0, 1.0, 2.0)
        with np.errstate(divide="ignore"):
            level = 10.0 * np.log10(twice * np.abs(self.coefficients) ** 2 / self.reference**2)
        amplitude = twice * np.abs(self.coefficients)
        return pd.DataFrame({"harmonic": k, "frequency": k * self.fundamental, "amplitude": amplitude, "level": level})


def spectra_table(named: Mapping[str, Spectrum]) -> pd.DataFrame:
    """Several spectra as one table: ``signal`` (the mapping's key), its ``unit`` and the
    ``reference`` of its levels, then :meth:`Spectrum.table`'s columns, harmonic by harmonic."""
    import pandas as pd

    tables = [spectrum.table() for spectrum in named.values()]
    sizes = [len(table) for table in tables]
    columns: dict[str, Any] = {
        "signal": np.repeat(list(named), sizes),
        "unit": np.repeat([spectrum.unit for spectrum in named.values()], sizes),
        "reference": np.repeat([spectrum.reference for spectrum in named.values()], sizes),
    }
    for name in ("harmonic", "frequency", "amplitude", "level"):
        columns[name] = np.concatenate([table[name].to_numpy() for table in tables]) if tables else []
    return pd.DataFrame(columns)
