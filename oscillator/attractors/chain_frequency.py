"""The frequency response of a declared system (issue 52): every period-1 branch over a number's
span, through its folds and unstable stretches, and what slow sweeps up and down meet.

:func:`chain_frequency_response` works as the article's
:func:`~oscillator.attractors.frequency.frequency_response` does, with a chain's pieces:

1. **sweeps**: :func:`~oscillator.orbits.chain_response.frequency_sweep` up the span and down,
   each value's orbit found from the one before (a test rig's slow sweep);
2. **seeds**: the attractors at ``seeds`` values (:func:`~oscillator.attractors.chain_attractors.find_chain_attractors`
   from the given starts, the chain's own by default), their period-1 orbits;
3. **branches**: each seed's orbit, then each sweep's, that lies on no branch traced yet, followed
   both ways to the span's ends (:func:`~oscillator.orbits.chain_branch.continue_chain_orbit`:
   exact Jacobians through every switch, folds located); the two halves joined into one branch.

An orbit lies on a branch when the branch passes its value and Newton's method, started there from
the state interpolated along the branch, returns the orbit (its free coordinates to
:data:`SAME`).  A branch ends where it leaves the span, where a mass or slider starts or stops
sticking at the section (the orbit goes on as another kind, which a later seed or sweep may
start), or where the corrector fails; each half says which.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.analysis.execution import Executor
from oscillator.attractors.chain_attractors import check_chain_states, find_chain_attractors
from oscillator.attractors.mapping import AttractorSettings
from oscillator.errors import InputError, OscillatorError
from oscillator.model.chain_fields import state_of
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import check_count
from oscillator.orbits.chain_branch import ChainBranch, continue_chain_orbit
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.chain_response import frequency_sweep
from oscillator.presenting import Presented, presenter
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["SAME", "ChainFrequencyResponse", "chain_frequency_response", "on_branch"]

#: Two orbits are one where their free coordinates agree to this, relative to ``1 + |y|``.
SAME = 1e-6
#: The most branches traced (each candidate orbit not on one yet starts another).
MAX_BRANCHES = 50


@dataclass(frozen=True)
class ChainFrequencyResponse(Presented):
    """What :func:`chain_frequency_response` found.

    Attributes
    ----------
    chain : FrictionChain
    param : str
    span : tuple of float
    branches : tuple of ChainBranch
        Each followed both ways from the orbit that started it (its points in order of the
        number along the branch, through its folds).
    sweeps : DataFrame
        The sweeps' rows (:func:`~oscillator.orbits.chain_response.frequency_sweep`), with
        ``direction`` (``up``, ``down``).
    skipped : tuple of str
        The candidate orbits no branch could be started from, and why.
    """

    chain: FrictionChain
    param: str
    span: tuple[float, float]
    branches: tuple[ChainBranch, ...] = field(repr=False)
    sweeps: pd.DataFrame = field(repr=False)
    skipped: tuple[str, ...] = ()

    def table(self) -> pd.DataFrame:
        """One row per point of every branch: ``branch`` (its number), then the branch's columns
        (the number, ``stable``, ``largest``, the measures, the state)."""
        parts = [b.points.assign(branch=k) for k, b in enumerate(self.branches)]
        if not parts:
            return pd.DataFrame({"branch": pd.Series(dtype="int64"), self.param: pd.Series(dtype="float64")})
        table = pd.concat(parts, ignore_index=True)
        return table[["branch", *(c for c in table.columns if c != "branch")]]

    def bifurcations(self) -> pd.DataFrame:
        """One row per fold or change of stability of every branch: ``branch``, ``kind``, the
        number's value."""
        parts = [b.bifurcations.assign(branch=k) for k, b in enumerate(self.branches)]
        columns = ["branch", "kind", self.param]
        if not parts:
            return pd.DataFrame(columns=columns)
        return pd.concat(parts, ignore_index=True)[columns]

    def plot(self, measure: str | None = None) -> Figure:
        """Each mass's ``x_max`` (or ``measure``) along every branch (solid where stable, dotted
        where not, folds marked) under the sweeps' orbits."""
        return presenter().plot_chain_frequency(self, measure)


def on_branch(chain: FrictionChain, param: str, branch: ChainBranch, value: float, state: np.ndarray) -> bool:
    """Whether the orbit of ``chain`` at ``value`` of ``param`` through ``state`` lies on
    ``branch`` (module docstring)."""
    points = branch.points
    lam = points[param].to_numpy(float)
    states = points[list(chain.system.state)].to_numpy(float)
    scale = 1.0 + float(np.max(np.abs(state)))
    for k in np.flatnonzero((lam[:-1] - value) * (lam[1:] - value) <= 0):
        a, b = lam[k], lam[k + 1]
        guess = states[k] if a == b else states[k] + (value - a) / (b - a) * (states[k + 1] - states[k])
        if np.max(np.abs(guess - state)) > 0.1 * scale:
            continue
        try:
            orbit = find_chain_orbit(chain.with_values({param: value}), guess, transient=0)
        except OscillatorError:
            continue
        free = [chain.system.state.index(name) for name in orbit.free]
        if np.max(np.abs(orbit.state[free] - state[free]), initial=0.0) <= SAME * scale:
            return True
    return False


def _both_ways(
    chain: FrictionChain, param: str, span: tuple[float, float], start: tuple[float, np.ndarray], step: float
) -> ChainBranch:
    """The branch through the orbit ``start = (value, state)``, followed to both ends of ``span``
    and joined (the lower half reversed)."""
    value, state = start
    low, high = span
    halves = []
    for stop in (low, high):
        if stop == value:
            continue
        halves.append(
            (
                stop,
                continue_chain_orbit(
                    chain, param=param, start=value, stop=stop, guess=state, transient=0, step=step, within=span
                ),
            )
        )
    return _joined(chain, param, halves)


def _joined(chain: FrictionChain, param: str, halves: list[tuple[float, ChainBranch]]) -> ChainBranch:
    """One branch of its halves: the one towards the span's low end reversed, then the other
    without its first point (the same orbit); the ends' reasons named by side."""
    points, changes, ended = [], [], []
    for k, (stop, half) in enumerate(halves):
        rows = half.points.iloc[::-1] if k == 0 and len(halves) == 2 else half.points.iloc[1 if k else 0 :]
        points.append(rows)
        changes.append(half.bifurcations)
        ended.append(f"towards {stop:g}: {half.ended}")
    table = pd.concat(points, ignore_index=True)
    found = pd.concat(changes, ignore_index=True).sort_values(param, kind="stable").drop(columns="point")
    width = halves[0][1].width
    return ChainBranch(chain, param, table, found.reset_index(drop=True), "; ".join(ended), width)


def _candidates(
    chain: FrictionChain, param: str, seeds: np.ndarray, starts: np.ndarray, settings: AttractorSettings
) -> list[tuple[float, np.ndarray]]:
    """The period-1 attractors' orbits at the seed values, ``(value, state)``."""
    found = []
    for value in seeds.tolist():
        here = find_chain_attractors(chain.with_values({param: value}), starts, settings=settings, executor=Executor())
        found += [(value, a.orbit.state) for a in here.attractors if a.period == 1 and a.orbit is not None]
    return found


def chain_frequency_response(
    chain: FrictionChain,
    param: str,
    span: tuple[float, float],
    *,
    seeds: int = 5,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    sweep: int = 41,
    transient: int = 100,
    step: float = 0.05,
    progress: Callable[[int, int], None] | None = None,
) -> ChainFrequencyResponse:
    """Every period-1 branch of ``chain`` over ``span`` of ``param`` (a name of its
    :meth:`~oscillator.model.chains.FrictionChain.parameter_names`) that the attractors at
    ``seeds`` values (from ``states``, rows of its ``system.state``; its own start by default) and
    the sweeps up and down over ``sweep`` values reach, each followed both ways to the span's ends
    (module docstring); ``step`` the continuation's largest step as a fraction of the span.
    ``progress(done, total)`` after each sweep value and after the seeds.
    ``oscillator.frequency_response(chain, param, span)`` calls it."""
    chain = chain.checked()
    low, high = (float(v) for v in span)
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise InputError(f"span must be two finite numbers, the lower first, got {printable(str(span))}", field="span")
    chain.with_values({param: low}).with_values({param: high})  # both ends checked, the field named
    seeds, sweep = check_count(seeds, "seeds", 1, 1000), check_count(sweep, "sweep", 2, 100_000)
    starts = check_chain_states(chain, state_of(chain) if states is None else states)
    settings = AttractorSettings(transient=max(transient, 1), record=8, lyapunov_periods=0)  # periodic ones only
    values = np.linspace(low, high, sweep)
    done, total = 0, 2 * sweep + seeds

    def tick(k: int, _: int) -> None:
        if progress is not None:
            progress(done + k, total)

    up = frequency_sweep(chain, values, param=param, transient=transient, progress=tick).assign(direction="up")
    done += sweep
    down = frequency_sweep(chain, values[::-1], param=param, transient=transient, progress=tick)
    done += sweep
    sweeps = pd.concat([up, down.assign(direction="down")], ignore_index=True)
    found = _candidates(chain, param, np.linspace(low, high, seeds), starts, settings)
    tick(seeds, total)
    met = sweeps[sweeps.status != "failed"]
    found += [(float(v), y) for v, y in zip(met[param], met[list(chain.system.state)].to_numpy(float), strict=True)]
    branches: list[ChainBranch] = []
    skipped: list[str] = []
    for value, state in found:
        if any(on_branch(chain, param, b, value, state) for b in branches):
            continue
        if len(branches) == MAX_BRANCHES:
            skipped.append(f"{param} = {value:.6g}: more than {MAX_BRANCHES} branches")
            continue
        try:
            branches.append(_both_ways(chain, param, (low, high), (value, state), step))
        except OscillatorError as error:
            skipped.append(f"{param} = {value:.6g}: {error}")
    return ChainFrequencyResponse(chain, param, (low, high), tuple(branches), sweeps, tuple(skipped))
