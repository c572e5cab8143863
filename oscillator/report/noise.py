"""The noise measures drawn (docs/noise.md): each contact force's and each mass's acceleration's
spectrum, a level in dB per harmonic against frequency on a logarithmic axis, the harmonics of
the forcing frequency marked, as an engineer reads a spectrum."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from oscillator.report.outputs import wrapped_title

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from oscillator.orbits.noise import Noise
    from oscillator.orbits.spectra import Spectrum

__all__ = ["noise_figure"]

#: Harmonics of Omega named on the top axis.
NAMED = (1, 2, 3, 5, 10, 20, 50, 100)
_NAMES = {"right": "contact force, right stop (x1 = d1)", "left": "contact force, m1 on m2's stop"}


def _panel(ax: Axes, spectrum: Spectrum, what: str, periods: int, omega: float) -> None:
    """One spectrum: each harmonic's level as a stem from the panel's floor, those of Omega
    filled (a return of ``periods`` forcing periods has ``periods - 1`` between them)."""
    table = spectrum.table().iloc[1:]
    shown = table[np.isfinite(table.level)]
    floor = float(shown.level.max()) - 80.0 if len(shown) else -100.0
    forcing = (shown.harmonic % periods == 0).to_numpy()
    for mask, color, label in ((forcing, "C0", "harmonics of Omega"), (~forcing, "0.6", "subharmonics of the return")):
        rows = shown[mask & (shown.level > floor).to_numpy()]
        if len(rows):
            ax.vlines(rows.frequency, floor, rows.level, lw=0.8, color=color)
            ax.plot(rows.frequency, rows.level, "o", ms=2.5, color=color, label=label)
    ax.set_xscale("log")
    ax.set_ylim(bottom=floor)
    unit = "1 N" if spectrum.unit == "N" else f"1e{math.log10(spectrum.reference):.0f} {spectrum.unit}"
    ax.set_ylabel(f"level (dB re {unit})")
    ax.set_title(what, fontsize=9, loc="left")
    ax.grid(alpha=0.3, which="both")
    top = ax.secondary_xaxis("top")
    named = [k for k in NAMED if k * omega / (2 * math.pi) <= float(table.frequency.max())]
    top.set_xticks([k * omega / (2 * math.pi) for k in named], labels=[f"{k}Ω" if k > 1 else "Ω" for k in named])
    top.tick_params(labelsize=7)


def noise_figure(found: Noise) -> Figure:
    """The spectra of the contact forces (of the contacts that struck) and of both masses'
    accelerations, one panel each, frequency (Hz) on a logarithmic axis."""
    from matplotlib.figure import Figure

    spectra = [(c.force, _NAMES[name]) for name, c in found.contacts.items() if c.onsets]
    spectra += [(m.acceleration, f"acceleration of m{i}") for i, m in found.masses.items()]
    fig = Figure(figsize=(8.5, 2.3 * len(spectra) + 0.8), layout="constrained")
    axes = fig.subplots(len(spectra), 1, sharex=True, squeeze=False)[:, 0]
    omega = found.case.parameters.Omega
    for ax, (spectrum, what) in zip(axes, spectra, strict=True):
        _panel(ax, spectrum, what, found.periods, omega)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("frequency (Hz)")
    periods = "one forcing period" if found.periods == 1 else f"{found.periods} forcing periods"
    fig.suptitle(wrapped_title(found.case, f"spectra over a return of {periods}"), fontsize=9)
    return fig
