"""The spectra of a declared system's periodic motion (docs/noise.md, "Declared systems"): each
stop's and contact's force and each mass's acceleration, as :mod:`oscillator.orbits.noise` gives
them for the article's system.

Over one return of ``n`` forcing periods (``nT`` seconds) of a friction chain's orbit (or over a
run's span, taken as the period), per stop and contact ``e``: ``F_e``, the force it puts on its
``on`` mass while closed (:func:`~oscillator.model.chain_fields.element_force`; 0 while open),
levels in dB re 1 N; per mass ``m``: ``a_m``, its acceleration, the chain's field in the mode the
motion is in (0 while it sticks to a floor or to a belt at its constant speed), levels in dB re
1e-6 m/s^2 (ISO 1683).  Harmonic ``k`` is at ``k / nT`` Hz.

The run holds a row at every solver step and event (CVODE at the orbit's 1e-12); within each step
the state is the quintic through both rows' states, rates and second rates (Hermite, exact to the
step's sixth power: :func:`~oscillator.orbits.chain_peaks.quintic`), and each signal is the
field's or the element's at that state in the step's mode, read at the quadrature's nodes
(:func:`~oscillator.orbits.spectra.fourier_coefficients`): exact on each step however the signals
jump at a switch (a damped contact's closing, a mass that sticks), where an FFT of samples would
alias the jumps.  The stops' and contacts' impacts, impulses and powers and the friction elements'
stick-slip steps are the orbit's measures (:func:`~oscillator.orbits.chain_response.orbit_measures`),
kept beside the spectra in :attr:`ChainNoise.measures`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from oscillator.errors import InputError
from oscillator.hybrid.chain_run import ChainResult
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import check_count
from oscillator.orbits.chain_peaks import Sides, sides, within
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

    from oscillator.orbits.chain_orbits import ChainOrbit

__all__ = ["NOISE_MEASURES", "ChainNoise", "chain_noise", "smooth_stretches", "sweep_noise"]

#: The kinds of the orbit's measures kept as its noise measures (per stop and contact, then per
#: friction element: :func:`~oscillator.orbits.chain_response.orbit_measures`).
NOISE_MEASURES = (
    "impact_rate",
    "impact_velocity",
    "impulse",
    "impulse_rate",
    "impact_energy",
    "impact_power",
    "force_max",
    "slip_steps",
    "slip_step_max",
)


@dataclass(frozen=True)
class ChainNoise:
    """The spectra of a friction chain's motion over a span (:func:`chain_noise`).

    Attributes
    ----------
    chain : FrictionChain
        The chain.
    periods : float
        Forcing periods in the span (a whole number for an orbit's return).
    span : float
        The span (s): the spectra's period, harmonic ``k`` at ``k / span`` Hz.
    forces : dict of str to Spectrum
        Each stop's and contact's force on its ``on`` mass, by the element's name.
    accelerations : dict of str to Spectrum
        Each mass's acceleration, by the mass's name.
    measures : dict of str to float
        The orbit's noise measures (:data:`NOISE_MEASURES`, ``impact_power:wall``, ...); empty
        for a run that is not an orbit's.
    """

    chain: FrictionChain
    periods: float
    span: float
    forces: dict[str, Spectrum]
    accelerations: dict[str, Spectrum]
    measures: dict[str, float]

    def spectra(self) -> pd.DataFrame:
        """Every spectrum as one table (:func:`~oscillator.orbits.spectra.spectra_table`): the
        signals ``force:<element>`` and ``acceleration:<mass>``, harmonic by harmonic."""
        named = {f"force:{name}": spectrum for name, spectrum in self.forces.items()}
        named |= {f"acceleration:{name}": spectrum for name, spectrum in self.accelerations.items()}
        return spectra_table(named)

    def columns(self, cutoff: float = 0.0) -> dict[str, float]:
        """The levels as a flat mapping: ``force_level:<element>`` (dB re 1 N) and
        ``acceleration_level:<mass>`` (dB re 1e-6 m/s^2), each of the harmonics above ``cutoff``
        Hz, the mean left out."""
        flat = {f"force_level:{name}": spectrum.level(cutoff) for name, spectrum in self.forces.items()}
        return flat | {f"acceleration_level:{name}": s.level(cutoff) for name, s in self.accelerations.items()}

    def plot(self) -> Figure:
        """The stops' and contacts' forces' (of those that closed) and the masses' accelerations'
        spectra in dB against frequency, the harmonics of Omega marked (docs/noise.md)."""
        return presenter().plot_noise(self)


def _signals(run: ChainResult, at: Sides, steps: tuple[int, int], closed: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The signals at ``times`` inside the steps ``first`` to ``last`` (``steps``, in one mode):
    each stop's and contact's force (``closed``: which are closed in the mode), then each mass's
    acceleration; ``(len(times), signals)``."""
    rates, forces = within(run, at, steps, times)
    return np.column_stack([forces * closed[None, :], rates[:, 1 : 2 * len(run.chain.masses) : 2]])


def smooth_stretches(t: np.ndarray, modes: np.ndarray) -> list[tuple[int, int]]:
    """The run's smooth pieces: the first and last step of each stretch of steps in one mode
    (steps of no length, at an event, left out)."""
    steps = np.flatnonzero(np.diff(t) > 0.0)
    if not len(steps):
        return []
    changed = np.flatnonzero((np.diff(steps) > 1) | (modes[steps[1:]] != modes[steps[:-1]]).any(axis=1))
    starts, ends = np.concatenate([[0], changed + 1]), np.concatenate([changed, [len(steps) - 1]])
    return [(int(steps[a]), int(steps[b])) for a, b in zip(starts.tolist(), ends.tolist(), strict=True)]


def chain_noise(motion: ChainOrbit | ChainResult, harmonics: int = HARMONICS) -> ChainNoise:
    """The spectra of a friction chain's orbit over its return, or of a run over its span taken as
    the period (module docstring), ``harmonics`` of the span's frequency kept (0 to 100000)."""
    from oscillator.orbits.chain_orbits import ChainOrbit
    from oscillator.orbits.chain_response import orbit_measures

    if not isinstance(motion, ChainOrbit | ChainResult):
        raise InputError(
            f"motion must be a friction chain's orbit (find_chain_orbit) or run (simulate_chain), "
            f"got {type(motion).__name__}",
            field="motion",
        )
    check_count(harmonics, "harmonics", 0, 100_000)
    run = motion.run if isinstance(motion, ChainOrbit) else motion
    chain, t = run.chain, run.times
    span = float(t[-1] - t[0])
    if not span > 0:
        raise InputError("the run must span some time: its spectra's period is its span", field="motion")
    at = sides(run)
    modes = run.modes()
    pieces: list[Piece] = []
    for first, last in smooth_stretches(t, modes):
        closed = modes[first, at.contacts] != 0.0
        pieces.append(
            (float(t[first]), float(t[last + 1]), functools.partial(_signals, run, at, (first, last), closed))
        )
    coefficients = fourier_coefficients(pieces, span, harmonics).reshape(harmonics + 1, -1)
    contacts = [chain.elements[row].name for row in at.contacts]
    forces = {name: Spectrum(coefficients[:, c], 1.0 / span, "N", FORCE_REFERENCE) for c, name in enumerate(contacts)}
    accelerations = {
        mass.name: Spectrum(coefficients[:, len(contacts) + i], 1.0 / span, "m/s^2", ACCELERATION_REFERENCE)
        for i, mass in enumerate(chain.masses)
    }
    measures = {}
    if isinstance(motion, ChainOrbit):
        measures = {k: v for k, v in orbit_measures(motion).items() if k.partition(":")[0] in NOISE_MEASURES}
    return ChainNoise(chain, span / chain.period, span, forces, accelerations, measures)


def sweep_noise(
    sweeps: pd.DataFrame,
    chain: FrictionChain,
    param: str,
    harmonics: int = HARMONICS,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The levels and spectra of every orbit a frequency sweep found
    (:func:`~oscillator.orbits.chain_response.frequency_sweep`'s rows, with ``direction``): each
    orbit found again from its state at its value (Newton, no transient) and measured over its
    return.  One row per orbit of ``direction``, the parameter, ``stable`` and
    :meth:`ChainNoise.columns`; and its :meth:`ChainNoise.spectra` rows with those first.
    ``progress(done, total)`` is told after each orbit; a failed row is left out."""
    import pandas as pd

    from oscillator.orbits.chain_orbits import find_chain_orbit

    found = sweeps[sweeps.status != "failed"]
    rows, spectra = [], []
    for done, values in enumerate(found.to_dict("records"), start=1):
        state = np.array([values[name] for name in chain.system.state], dtype=float)
        point = chain.with_values({param: float(values[param])})
        heard = chain_noise(find_chain_orbit(point, state, transient=0), harmonics)
        where = {"direction": values["direction"], param: float(values[param]), "stable": bool(values["stable"])}
        rows.append(where | heard.columns())
        spectra.append(heard.spectra().assign(**where))
        if progress is not None:
            progress(done, len(found))
    first = ["direction", param, "stable"]
    table = pd.DataFrame(rows) if rows else pd.DataFrame({name: [] for name in first})
    joined = pd.concat(spectra, ignore_index=True) if spectra else pd.DataFrame({name: [] for name in first})
    return table, joined[[*first, *[c for c in joined.columns if c not in first]]]
