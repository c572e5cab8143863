"""The noise measures drawn (docs/noise.md): each contact force's and each mass's acceleration's
spectrum, a level in dB per harmonic against frequency on a logarithmic axis, the harmonics of
the forcing frequency marked, as an engineer reads a spectrum."""

from __future__ import annotations

import math
import textwrap
from typing import TYPE_CHECKING

import numpy as np

from oscillator.report.outputs import plain_label, wrapped_title

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from oscillator.attractors.frequency import FrequencyResponse
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.chain_noise import ChainNoise
    from oscillator.orbits.noise import Noise
    from oscillator.orbits.spectra import Spectrum

__all__ = [
    "SPECTRA_FIGURE",
    "chain_spectra_figure",
    "noise_figure",
    "noise_response_figure",
    "spectra_map",
    "spectra_response_figure",
]

#: The name of a frequency response's spectra figure in its folder's figures/.
SPECTRA_FIGURE = "frequency-spectra"

#: Harmonics of Omega named on the top axis.
NAMED = (1, 2, 3, 5, 10, 20, 50, 100)
_NAMES = {"right": "contact force, right stop (x1 = d1)", "left": "contact force, m1 on m2's stop"}


def _panel(ax: Axes, spectrum: Spectrum, what: str, periods: float, omega: float) -> None:
    """One spectrum: each harmonic's level as a stem from the panel's floor, those of Omega
    filled (a return of ``periods`` forcing periods has ``periods - 1`` between them; a span of
    a fractional number has none)."""
    table = spectrum.table().iloc[1:]
    shown = table[np.isfinite(table.level)]
    floor = float(shown.level.max()) - 80.0 if len(shown) else -100.0
    whole = round(periods) if abs(periods - round(periods)) < 1e-9 * max(periods, 1.0) else 0
    forcing = (shown.harmonic % whole == 0).to_numpy() if whole else np.zeros(len(shown), bool)
    for mask, color, label in ((forcing, "C0", "harmonics of Omega"), (~forcing, "0.6", "other harmonics of 1/span")):
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


def noise_figure(found: Noise | ChainNoise) -> Figure:
    """The spectra of the contact forces (of the contacts that struck) and of the masses'
    accelerations, one panel each, frequency (Hz) on a logarithmic axis; of the article's system
    or of a declared one."""
    from oscillator.orbits.noise import Noise

    if isinstance(found, Noise):
        spectra = [(c.force, _NAMES[name]) for name, c in found.contacts.items() if c.onsets]
        spectra += [(m.acceleration, f"acceleration of m{i}") for i, m in found.masses.items()]
        periods = "one forcing period" if found.periods == 1 else f"{found.periods} forcing periods"
        title = wrapped_title(found.case, f"spectra over {periods}")
        return _spectra_figure(spectra, found.periods, found.case.parameters.Omega, title)
    elements = {element.name: element for element in found.chain.elements}
    spectra = [
        (s, f'{elements[name].type} "{plain_label(name)}": its force on {plain_label(elements[name].on)}')
        for name, s in found.forces.items()
        if np.any(s.coefficients)
    ]
    spectra += [(s, f"acceleration of {plain_label(name)}") for name, s in found.accelerations.items()]
    periods = "one forcing period" if found.periods == 1 else f"{found.periods:g} forcing periods"
    title = textwrap.fill(f"{plain_label(found.chain.title or 'friction chain')}: spectra over {periods}", 100)
    return _spectra_figure(spectra, found.periods, found.chain.Omega, title)


def _spectra_figure(spectra: list[tuple[Spectrum, str]], periods: float, omega: float, title: str) -> Figure:
    """One panel per ``(spectrum, what)``, stacked, ``title`` above."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.5, 2.3 * len(spectra) + 0.8), layout="constrained")
    axes = fig.subplots(len(spectra), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (spectrum, what) in zip(axes, spectra, strict=True):
        _panel(ax, spectrum, what, periods, omega)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("frequency (Hz)")
    fig.suptitle(title, fontsize=9)
    return fig


def noise_response_figure(found: FrequencyResponse, table: pd.DataFrame, column: str) -> Figure:
    """``column`` of a frequency response's noise measures (:meth:`FrequencyResponse.noise`)
    against the parameter: each branch in its colour, runs of equal stability solid (stable) or
    dashed, as the response measures are drawn."""
    from matplotlib.figure import Figure

    from oscillator.errors import InputError
    from oscillator.report.frequency import stability_runs
    from oscillator.report.outputs import color_of, quantity_label
    from oscillator.text import shown

    measures = [c for c in table.columns if c not in ("branch", found.param, "stable", "piece")]
    if column not in measures:
        raise InputError(f"column must be one of {', '.join(measures)}, got {shown(column)}", field="column")
    fig = Figure(figsize=(8.0, 3.8), layout="constrained")
    ax = fig.subplots()
    for k, rows in table.groupby("branch", sort=True):
        for _, piece in rows.groupby("piece", sort=False):
            for span, solid in stability_runs(piece):
                ax.plot(span[found.param], span[column], color=color_of(int(k)), ls="-" if solid else "--", lw=1.4)
    ax.set_xlabel(quantity_label(found.param))
    ax.set_ylabel(column.replace("_", " ") + _UNITS.get(column.rsplit("_", 1)[0], ""))
    ax.grid(alpha=0.3)
    ax.set_title(wrapped_title(found.case, f"{column} over {found.param}: stable solid, unstable dashed"), fontsize=9)
    return fig


def spectra_response_figure(found: FrequencyResponse, spectra: pd.DataFrame) -> Figure:
    """Every stable point's spectra (:meth:`FrequencyResponse.noise_tables`) against the
    parameter (:func:`spectra_map`)."""
    from oscillator.report.outputs import quantity_label

    names = {"force_right": "contact force, right stop", "force_left": "contact force, m1 on m2's stop"}
    names |= {"acceleration_m1": "acceleration of m1", "acceleration_m2": "acceleration of m2"}
    title = wrapped_title(found.case, f"the stable orbits' spectra over {found.param}")
    return spectra_map(spectra, (found.param, quantity_label(found.param)), names, title)


def chain_spectra_figure(spectra: pd.DataFrame, chain: FrictionChain, param: str) -> Figure:
    """Every stable orbit's spectra of a system's frequency sweeps (both ways,
    :func:`~oscillator.orbits.chain_noise.sweep_noise`) against the parameter (:func:`spectra_map`)."""
    elements = {element.name: element for element in chain.elements}
    names = {
        f"force:{name}": f'{e.type} "{plain_label(name)}": its force on {plain_label(e.on)}'
        for name, e in elements.items()
    }
    names |= {f"acceleration:{mass.name}": f"acceleration of {plain_label(mass.name)}" for mass in chain.masses}
    what = f"{plain_label(chain.title or 'friction chain')}: the stable orbits' spectra over {plain_label(param)}"
    unit = chain.unit(param)
    label = f"{plain_label(param)} ({unit})" if unit else plain_label(param)
    return spectra_map(spectra, (param, label), names, textwrap.fill(what, 100))


def spectra_map(spectra: pd.DataFrame, axis: tuple[str, str], names: dict[str, str], title: str) -> Figure:
    """Spectra against a parameter (``axis``: its column and its label): one panel per signal
    that is not zero throughout, each harmonic of each stable point a dot at the point's parameter
    and the harmonic's frequency (logarithmic), coloured by its level, the panel's top 60 dB (a
    Campbell diagram of the response)."""
    from matplotlib.figure import Figure

    param, label = axis
    stable = spectra[spectra.stable.astype(bool) & (spectra.harmonic > 0) & np.isfinite(spectra.level)]
    shown = [(signal, rows) for signal, rows in stable.groupby("signal", sort=False) if len(rows)]
    fig = Figure(figsize=(8.5, 2.4 * max(len(shown), 1) + 0.8), layout="constrained")
    axes = fig.subplots(max(len(shown), 1), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (signal, rows) in zip(axes, shown, strict=False):
        top = float(rows.level.max())
        style = {"s": 3, "marker": "s", "cmap": "viridis", "vmin": top - 60.0, "vmax": top, "rasterized": True}
        dots = ax.scatter(rows[param], rows.frequency, c=rows.level, **style)
        ax.set_yscale("log")
        ax.set_ylabel("frequency (Hz)")
        ax.set_title(names.get(str(signal), plain_label(str(signal))), fontsize=9, loc="left")
        unit = "1 N" if str(signal).startswith("force") else "1e-6 m/s^2"
        fig.colorbar(dots, ax=ax, label=f"dB re {unit}", pad=0.01)
    if not shown:
        axes[0].text(0.5, 0.5, "no stable point", transform=axes[0].transAxes, ha="center")
    axes[-1].set_xlabel(label)
    fig.suptitle(title, fontsize=9)
    return fig


#: The noise columns' units, by the column's name without its contact or mass.
_UNITS = {
    "impact_rate": " (1/s)",
    "impulse": " (N s)",
    "impulse_rate": " (N)",
    "impact_energy": " (J)",
    "impact_power": " (W)",
    "force_level": " (dB re 1 N)",
    "acceleration_level": " (dB re 1e-6 m/s^2)",
    "slip_step_max": " (m/s^2)",
}
