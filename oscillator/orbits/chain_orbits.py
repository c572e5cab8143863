"""Periodic orbits of a friction chain (issue 52, its first step): the fixed points of the
stroboscopic map by Newton's method, and their Floquet multipliers.

The period map ``P`` takes the chain's state ``y`` (its
:attr:`~oscillator.model.chains.FrictionChain.system`'s ``state``: each mass's ``x, v``, each
slider's ``z``) at the section ``s`` to the state at ``s + N T``: one run of
:func:`~oscillator.hybrid.chain_run.simulate_chain` from ``y``, every switch by the chains' rules.
Its derivative ``M = dP/dy`` is exact: the tangent equations along each
smooth piece and the saltation rule at every switch (:mod:`oscillator.orbits.chain_tangents`;
the tests compare it with central differences of the map).  Newton's
method solves ``P(y) = y`` in the coordinates that can move at the section: a mass stuck on its
belt or floor there keeps its velocity (the belt's speed is its domain, as the article's resting
mass keeps ``v = 0``), and one stuck the whole period keeps its place too (a nearby place is an
orbit as well: the multiplier 1, neutral), as does the stretch ``z`` of a slider that holds the
whole period or has ``F = 0``.  A Newton step longer than twice the larger of the state and
the residual is shortened to that (far from an orbit the map's derivative says little, and a
long step can take the motion where every run is long).  The multipliers are the eigenvalues of ``M`` over the
coordinates that move.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.chain_run import ChainResult, simulate_chain
from oscillator.model.chain_fields import state_of
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SolverOptions
from oscillator.orbits.chain_tangents import RTOL, tangent_pass

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.chain_noise import ChainNoise
    from oscillator.orbits.chain_sensitivity import ChainSensitivities

__all__ = ["ORBIT_OPTIONS", "ChainOrbit", "chain_period_map", "find_chain_orbit", "held_coordinates"]

#: CVODE's tolerances for a chain's period map.
ORBIT_OPTIONS = SolverOptions(rtol=1e-12, atol=1e-12)


@dataclass(frozen=True)
class ChainOrbit:
    """A periodic orbit of a friction chain's stroboscopic map.

    Attributes
    ----------
    chain : FrictionChain
        The chain.
    section : float
        The section's time: the orbit passes ``state`` at ``section + k N T``.
    state : ndarray
        The state at ``section`` (the chain's system's ``state`` names).
    period : int
        ``N``: forcing periods per return.
    free : tuple of str
        The coordinates that move at the section, those Newton solved for and the multipliers
        are of.
    residual : float
        ``|P(state) - state|`` over :attr:`free` (max norm).
    iterations : int
        Newton steps taken.
    neutral : tuple of str
        The coordinates in which the orbit is neutral, held by Newton at the guess's values: the
        place of a mass stuck on its belt or floor the whole period (``x:<mass>``), the stretch of
        a slider that holds the whole period or has ``F = 0`` (``z:<slider>``): a nearby value is
        an orbit too (multiplier 1).
    run : ChainResult
        One return of the orbit: its events and trajectory.
    """

    chain: FrictionChain
    section: float
    state: np.ndarray
    period: int
    free: tuple[str, ...]
    residual: float
    iterations: int
    neutral: tuple[str, ...]
    run: ChainResult

    @functools.cached_property
    def monodromy(self) -> np.ndarray:
        """``dP/dy`` over :attr:`free`, exact through every switch (the tangent pass along
        :attr:`run`, computed when first asked)."""
        names = list(self.chain.system.state)
        return _derivative(self.run, [names.index(name) for name in self.free])

    @functools.cached_property
    def multipliers(self) -> np.ndarray:
        """The monodromy's eigenvalues, largest modulus first."""
        found = np.linalg.eigvals(self.monodromy) if len(self.free) else np.empty(0, complex)
        return found[np.argsort(-np.abs(found), kind="stable")]

    @property
    def stable(self) -> bool:
        """No disturbance grows: every multiplier inside the unit circle."""
        return bool(np.all(np.abs(self.multipliers) < 1.0))

    @property
    def events(self) -> pd.DataFrame:
        """The events over one return of the orbit."""
        return self.run.events

    def sensitivities(self, params: str | Sequence[str]) -> ChainSensitivities:
        """The exact derivatives of the orbit in the chain's numbers ``params`` (``platform.F``,
        ``blade.k``, ``Omega``): of its state, its switch times and its measures
        (:func:`oscillator.orbits.chain_sensitivity.chain_sensitivities`)."""
        from oscillator.orbits.chain_sensitivity import chain_sensitivities

        return chain_sensitivities(self, params)

    def noise(self, harmonics: int = 200) -> ChainNoise:
        """The spectra of each stop's and contact's force and each mass's acceleration over one
        return, with the orbit's noise measures
        (:func:`oscillator.orbits.chain_noise.chain_noise`, docs/noise.md)."""
        from oscillator.orbits.chain_noise import chain_noise

        return chain_noise(self, harmonics)

    @property
    def verdict(self) -> str:
        """The stability in words, with the coordinates in which the orbit is neutral."""
        words = ["stable" if self.stable else "unstable"]
        words += [f"neutral in {name}: a nearby value is an orbit too (multiplier 1)" for name in self.neutral]
        return "; ".join(words)


def chain_period_map(
    chain: FrictionChain, section: float, state: np.ndarray, periods: int = 1, options: SolverOptions = ORBIT_OPTIONS
) -> ChainResult:
    """The run of ``chain`` from ``state`` at ``section`` over ``periods`` forcing periods:
    ``P(state)`` is its ``y_end`` (the chain's state first)."""
    moved = dataclasses.replace(chain, t0=float(section), t_end=None)
    return simulate_chain(moved, float(section) + periods * chain.period, options=options, start_state=state)


def _ends(result: ChainResult) -> np.ndarray:
    return np.asarray(result.y_end[: result.chain.system.size], dtype=float)


def held_coordinates(chain: FrictionChain, result: ChainResult) -> tuple[set[int], tuple[str, ...]]:
    """The state's indices held at the section, and the names neutral in them: the velocity of a
    mass stuck there; the place of one stuck all period (any nearby place is an orbit too); the
    ``z`` of a slider that holds all period (any nearby stretch too) or never can (``F = 0``: its
    ``z`` follows the motion and acts on nothing)."""
    system = chain.system
    held: set[int] = set()
    neutral = []
    for element in chain.elements:
        if element.type not in ("friction", "jenkins"):
            continue
        mode = result.mode_of(element.name)
        if element.type == "jenkins":
            if (mode == 0).all() or element.values["F"] == 0:
                held.add(system.state.index(f"z:{element.name}"))
                neutral.append(f"z:{element.name}")
            continue
        k = system.masses.index(element.on)
        if mode[0] == 0:
            held.add(2 * k + 1)
            if (mode == 0).all():
                held.add(2 * k)
                neutral.append(system.position(element.on))
    return held, tuple(neutral)


#: The tangent equations' tolerance for a Newton step's Jacobian (the orbit's multipliers take
#: :data:`~oscillator.orbits.chain_tangents.RTOL`).
NEWTON_RTOL = 1e-7


def _derivative(image: ChainResult, free: list[int], rtol: float = RTOL) -> np.ndarray:
    """``dP/dy`` over ``free``: the tangent pass along the map's run (exact)."""
    return tangent_pass(image, rtol=rtol).monodromy[np.ix_(free, free)]


def _guess(chain: FrictionChain, section: float, transient: int, options: SolverOptions) -> np.ndarray:
    """The state at the first section time ``transient`` periods or more after the chain's start
    (its start itself for none at the start): where a run at ``simulate``'s tolerances (or
    ``options``' where looser) leaves the motion, as the article's system's transient does; Newton
    refines it at ``options``'."""
    returns = max(0, math.ceil((chain.t0 + transient * chain.period - section) / chain.period - 1e-12))
    end = section + returns * chain.period
    if end <= chain.t0:
        return state_of(chain)
    default = SolverOptions()
    looser = dataclasses.replace(options, rtol=max(options.rtol, default.rtol), atol=max(options.atol, default.atol))
    return _ends(simulate_chain(chain, end, options=looser))


def find_chain_orbit(
    chain: FrictionChain,
    guess: np.ndarray | None = None,
    *,
    period: int = 1,
    section: float | None = None,
    transient: int = 100,
    tol: float = 1e-10,
    max_iterations: int = 25,
    options: SolverOptions = ORBIT_OPTIONS,
) -> ChainOrbit:
    """The periodic orbit of ``chain`` through ``guess`` at ``section`` (by default: where the
    chain's motion is after ``transient`` forcing periods), returning after ``period`` forcing
    periods, by Newton's method on the period map (module docstring); its multipliers.
    ``oscillator.find_orbit(chain)`` calls it.

    Raises
    ------
    InputError
        A guess of another size than the chain's state, or not finite; a period not a whole number
        from 1 to 1000.
    SimulationFailed
        Newton's method did not converge (``reason`` ``no_convergence``), or a run failed.
    """
    chain, periods = chain.checked(), period
    if isinstance(periods, bool) or not isinstance(periods, int) or not 1 <= periods <= 1000:
        raise InputError(f"period must be a whole number from 1 to 1000, got {periods!r}", field="period")
    section = chain.t0 if section is None else float(section)
    names = chain.system.state
    y = _guess(chain, section, transient, options) if guess is None else np.asarray(guess, dtype=float).ravel()
    if len(y) != len(names) or not np.isfinite(y).all():
        raise InputError(f"guess must be {len(names)} finite numbers ({', '.join(names)})", field="guess")
    history: list[float] = []
    for iteration in range(max_iterations + 1):
        image = chain_period_map(chain, section, y, periods, options)
        held, neutral = held_coordinates(chain, image)
        free = [k for k in range(len(y)) if k not in held]
        residual = (_ends(image) - y)[free]
        history.append(float(np.max(np.abs(residual), initial=0.0)))
        if history[-1] <= tol * max(1.0, float(np.max(np.abs(y)))):
            return ChainOrbit(
                chain, section, y, periods, tuple(names[k] for k in free), history[-1], iteration, neutral, image
            )
        if iteration == max_iterations:
            break
        matrix = _derivative(image, free, NEWTON_RTOL) - np.eye(len(free))
        try:
            step = np.linalg.solve(matrix, -residual)
        except np.linalg.LinAlgError:
            break
        reach = 2.0 * max(1.0, float(np.max(np.abs(y))), float(np.max(np.abs(residual))))
        y = y.copy()
        y[free] += step * min(1.0, reach / max(float(np.max(np.abs(step))), 1e-300))
    raise SimulationFailed(
        f"Newton's method did not converge in {max_iterations} steps (residuals "
        f"{', '.join(f'{r:.2e}' for r in history)}); give a better guess, a longer transient or more iterations",
        reason=Reason.NO_CONVERGENCE,
        field="guess",
    )
