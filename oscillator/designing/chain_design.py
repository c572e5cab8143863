"""Design of a declared machine over an operating band (issue 52): the value of one of its
numbers that makes the worst of a measure over the band smallest, as a friction-damper designer
chooses the normal load (docs/systems.md, "Designing a friction damper").

The worst over the band (:func:`worst_over`) is found in two stages: the period-1 orbit swept up
the band (:func:`~oscillator.orbits.chain_response.frequency_sweep`, ``sweep`` values), then the
largest value refined between its two neighbours (Brent's bounded method, each orbit by Newton
from the nearest one found: a peak may sit on a kink, where the motion starts or stops sticking,
so no derivative is asked of it).  At a smooth peak the worst's derivative in the designed number
is the measure's own partial derivative (the peak's place moves, but the measure is stationary
along the band there: the envelope theorem), exact (:mod:`oscillator.orbits.chain_sensitivity`).
A sweep sees a peak narrower than its spacing only by chance: give ``sweep`` values enough.

The design (:func:`chain_design`) minimises the worst over the number's range by Brent's bounded
method (SciPy's ``minimize_scalar``), each evaluation one :func:`worst_over`; the result holds
every evaluation (the curve of the worst against the number) and the optimum's derivative, which
is near zero at an inner optimum and says which way to go at a bound.  A band whose motion jumps
between coexisting orbits is judged by the orbit the upward sweep follows.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from scipy.optimize import minimize_scalar

from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_orbits import ChainOrbit, find_chain_orbit
from oscillator.orbits.chain_response import frequency_sweep, orbit_measures
from oscillator.orbits.chain_tangents import check_names
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["ChainDesign", "Worst", "chain_design", "worst_over"]

#: How closely the peak's place along the band and the design's value are located (relative to
#: their ranges).
XTOL = 1e-6
#: The most values of the designed number judged (Brent's method takes about 15).
MAX_EVALUATIONS = 40


@dataclass(frozen=True)
class Worst:
    """The worst of ``measure`` over a band: its ``value``, where (``at``, the band parameter's
    value), the orbit there, and ``gradient``: its exact derivative in each number asked
    (``nan`` where the peak sits on a grazing, which has none)."""

    measure: str
    value: float
    at: float
    orbit: ChainOrbit
    gradient: dict[str, float]


@dataclass(frozen=True)
class ChainDesign:
    """A design: the chain at the best value of ``vary``, ``worst`` there (with its derivative in
    ``vary``), and ``history``: every value judged (``vary``'s value, ``worst``, ``at``), sorted."""

    chain: FrictionChain
    vary: str
    value: float
    worst: Worst
    history: pd.DataFrame

    def plot(self, sweeps: Mapping[float, pd.DataFrame] | None = None) -> Figure:
        """The worst against the number varied, the best starred; with ``sweeps`` (the number's
        value -> its sweep over the band), the objective along the band at each too."""
        from oscillator.presenting import presenter

        return presenter().plot_chain_design(self, sweeps)

    @property
    def summary(self) -> str:
        """The design in one sentence."""
        w = self.worst
        return (
            f"{self.vary} = {self.value:.6g}: the worst {w.measure} over the band is {w.value:.6g}, at {w.at:.6g}; "
            f"its derivative in {self.vary} there {w.gradient[self.vary]:+.3g}"
        )


class _Along:
    """Orbits along the band, each found by Newton from the nearest one found before (after a
    transient where that fails), and the measure's derivative along the band at each."""

    def __init__(self, chain: FrictionChain, param: str, measure: str, transient: int) -> None:
        self.chain, self.param, self.measure, self.transient = chain, param, measure, transient
        self.known: dict[float, np.ndarray] = {}

    def orbit(self, value: float) -> ChainOrbit:
        point = self.chain.with_values({self.param: value})
        nearest = min(self.known, key=lambda v: abs(v - value))
        try:
            orbit = find_chain_orbit(point, self.known[nearest], transient=0)
        except OscillatorError:
            orbit = find_chain_orbit(point, transient=self.transient)
        self.known[value] = orbit.state
        return orbit

    def measured(self, value: float) -> float:
        return orbit_measures(self.orbit(value))[self.measure]


def worst_over(
    chain: FrictionChain,
    measure: str,
    over: tuple[str, float, float],
    *,
    sweep: int = 21,
    names: Sequence[str] = (),
    transient: int = 100,
) -> Worst:
    """The worst (largest) ``measure`` (a column of :func:`~oscillator.orbits.chain_response.
    orbit_measures`: ``x_max:blade``) over ``over = (param, low, high)``, located to
    :data:`XTOL` of the band (module docstring), with its exact derivative in ``names``."""
    param, low, high = over
    check_names(chain, [param, *names])
    if not (2 <= sweep <= 10_000) or not low < high:
        raise InputError(f"the band needs 2 to 10000 values over low < high, got {sweep} over {low:g}..{high:g}")
    swept = frequency_sweep(chain, np.linspace(low, high, sweep), param=param, transient=transient)
    if (swept.status == "failed").all():
        raise SimulationFailed(
            f"no orbit was found anywhere on the band: {swept.message.iloc[0]}", reason=Reason.NO_ORBIT
        )
    if measure not in swept:
        known = [c for c in swept.columns if ":" in c and not c.startswith(("x:", "v:", "z:"))]
        raise InputError(f"no measure named {printable(measure)}; choose one of {', '.join(known)}", field="measure")
    values = swept[measure].to_numpy(float)
    k = int(np.nanargmax(values))
    along = _Along(chain, param, measure, transient)
    along.known = {
        float(v): swept.loc[j, list(chain.system.state)].to_numpy(float)
        for j, v in enumerate(swept[param])
        if not math.isnan(values[j])
    }
    at = float(swept[param].iloc[k])
    a, b = (float(swept[param].iloc[j]) for j in (max(k - 1, 0), min(k + 1, len(values) - 1)))
    refined = minimize_scalar(
        lambda x: -along.measured(x), bounds=(a, b), method="bounded", options={"xatol": XTOL * (high - low)}
    )
    if -float(refined.fun) > values[k]:
        at = float(refined.x)
    orbit = along.orbit(at)
    gradient = dict.fromkeys(names, math.nan)
    if names:
        try:
            found = orbit.sensitivities(list(names)).of(measure)
        except SimulationFailed as error:  # the peak sits on a grazing: no derivative there
            if error.reason is not Reason.NOT_DIFFERENTIABLE:
                raise
        else:
            gradient = {name: float(found[f"d/d{name}"]) for name in names}
    value = orbit_measures(orbit)[measure]
    return Worst(measure, value, float(at), orbit, gradient)


def chain_design(
    chain: FrictionChain,
    vary: Mapping[str, Sequence[float]],
    over: Mapping[str, Sequence[float]],
    objective: str,
    *,
    sweep: int = 21,
    xtol: float = 1e-4,
    progress: Callable[[int, int], None] | None = None,
) -> ChainDesign:
    """The value of ``vary``'s one number, in its range, that makes the worst ``objective`` over
    the band ``over`` smallest (module docstring): ``chain_design(machine, {"platform.F": (0.05,
    3.0)}, {"Omega": (0.6, 1.6)}, "x_max:blade")``.  ``xtol`` is the design's tolerance relative
    to its range; ``progress(done, total)`` is told after each value judged (``total``: what golden
    sections to ``xtol`` would take; Brent's method takes fewer, or at most :data:`MAX_EVALUATIONS`)."""
    if len(vary) != 1 or len(over) != 1:
        raise InputError(
            "a system's design varies one number over one band for now, e.g. vary={'platform.F': (0.05, 3.0)}, "
            "over={'Omega': (0.6, 1.6)}",
            field="vary" if len(vary) != 1 else "over",
        )
    (name, span), (param, band) = next(iter(vary.items())), next(iter(over.items()))
    check_names(chain, [name, param])
    low, high = (float(v) for v in span)
    if not low < high:
        raise InputError(f"{printable(name)}'s range must be low < high, got {low:g}..{high:g}", field=name)
    chain.with_values({name: low})  # each end checked as the file's values are
    chain.with_values({name: high})
    band_range = (param, float(band[0]), float(band[1]))
    seen: dict[float, Worst] = {}
    expected = min(MAX_EVALUATIONS, math.ceil(math.log(xtol) / math.log(0.618)) + 3)  # Brent's, about

    def worst(value: float) -> float:
        found = worst_over(chain.with_values({name: value}), objective, band_range, sweep=sweep, names=(name,))
        seen[value] = found
        if progress is not None:
            progress(len(seen), expected)
        return found.value

    result = minimize_scalar(
        worst, bounds=(low, high), method="bounded", options={"xatol": xtol * (high - low), "maxiter": MAX_EVALUATIONS}
    )
    best = float(result.x) if float(result.x) in seen else min(seen, key=lambda v: seen[v].value)
    history = pd.DataFrame(
        [{name: v, "worst": w.value, "at": w.at, f"d/d{name}": w.gradient[name]} for v, w in sorted(seen.items())]
    )
    return ChainDesign(chain.with_values({name: best}), name, best, seen[best], history)
