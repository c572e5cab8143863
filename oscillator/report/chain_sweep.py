"""A declared system's sweep drawn (issue 52, ``oscillator sweep FILE``): each mass's Poincaré
points over the swept number (a bifurcation diagram: one dot per recorded period, so a period-n
motion shows n dots, an aperiodic one a smear), and the switches per period, each way of a
both-ways sweep in its own colour."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.model.chains import FrictionChain
from oscillator.report.outputs import number_label, plain_label

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["chain_sweep_figure"]

#: Each way's colour and marker.
_WAYS = {"up": ("tab:blue", "o"), "down": ("tab:orange", "x")}


def chain_sweep_figure(tables: Mapping[str, pd.DataFrame], chain: FrictionChain, param: str) -> Figure:
    """Each mass's place at the section ``t0 + n T`` against ``param``, and the switches and
    closings per period."""
    from matplotlib.figure import Figure

    masses = [mass.name for mass in chain.masses]
    poincare, summary = tables["poincare"], tables["summary"]
    ok = summary[summary.status == "ok"]
    ways = list(dict.fromkeys(ok.direction.astype(str)))
    fig = Figure(figsize=(8, 2.3 * (len(masses) + 1) + 0.6), layout="constrained")
    axes = fig.subplots(len(masses) + 1, 1, sharex=True, squeeze=False)[:, 0]
    directions = summary.set_index("index").direction.astype(str)
    way_of = poincare["index"].map(directions)
    for ax, mass in zip(axes, masses, strict=False):
        for way in ways:
            rows = poincare[way_of == way]
            color, marker = _WAYS.get(way, ("black", "."))
            ax.plot(rows[param], rows[f"x:{mass}"], marker, ms=3, color=color, ls="none", label=f"going {way}")
        ax.set_ylabel(plain_label(f"x:{mass} at t0 + nT (m)"))
        ax.grid(alpha=0.3)
    last = axes[-1]
    for way in ways:
        rows = ok[ok.direction == way].sort_values(param)
        color, marker = _WAYS.get(way, ("black", "."))
        last.plot(
            rows[param], rows.switches_per_period, "-" + marker, color=color, ms=4, label=f"switches, going {way}"
        )
        last.plot(rows[param], rows.closings_per_period, ":", color=color, label=f"closings, going {way}")
    failed = summary[summary.status != "ok"]
    if len(failed):
        last.plot(failed[param], np.zeros(len(failed)), "v", color="tab:red", label="failed")
    last.set_ylabel("per period")
    last.grid(alpha=0.3)
    last.set_xlabel(number_label(chain, param))
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="best")
    title = f"{chain.title or 'friction chain'}: sweep over {param}"
    fig.suptitle(plain_label(title), fontsize=10)
    return fig
