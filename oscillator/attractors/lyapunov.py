"""The Lyapunov spectrum of the flow, from its variational equations through every switch.

Over each forcing period the engine integrates the variational equations of the mode it is in,
and at every switch the supervisor applies the switch's saltation matrix (Müller 1995, "Calculation
of Lyapunov exponents for dynamic systems with discontinuities"; for Filippov systems with
sliding, Dieci and Lopez 2011): the derivative of the stroboscopic map over one period,
``M_k`` (:func:`oscillator.orbits.shooting.period_map`).  The spectrum is the growth rate of
``M_k ... M_1`` along an orthonormal frame, re-orthonormalised every period by a QR factorisation
(the discrete QR method; Benettin et al. 1980, Dieci, Russell and Van Vleck 1997):

    M_k Q_(k-1) = Q_k R_k,      lambda_i = lim (1 / (K T)) sum_k log |R_k[i, i]|.

The frame is first aligned over ``frame`` periods without averaging, so that on a periodic
orbit each period's ``log |R[i, i]|`` is already ``log |mu_i|`` (a multiplier of the orbit) and the
average does not carry the frame's first turn.  A mass that sticks annihilates velocity
disturbances (its saltation matrix has a zero row), so an exponent can be ``-inf``: the flow
contracts a direction to nothing in finite time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.analysis.execution import check_progress
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import check_count
from oscillator.orbits.settings import check_guess
from oscillator.orbits.shooting import period_map, settled
from oscillator.presenting import Presented, presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["LyapunovSpectrum", "lyapunov", "separation_exponent"]

#: The most forcing periods averaged over, and the longest transient.
MAX_PERIODS = 10_000_000
#: The frame's alignment (periods) before the averaging starts.
FRAME = 20
#: Below this, a component of the nearby state is zero (the model refuses subnormal values).
TINY = 1e-80


@dataclass(frozen=True)
class LyapunovSpectrum(Presented):
    """The Lyapunov exponents of a motion.

    Attributes
    ----------
    case : Case or FrictionChain
        The case, with the overrides; or the friction chain.
    exponents : ndarray
        The exponents (1/s), one per state coordinate (four for the article's system), largest
        first; ``-inf`` for a direction the flow annihilates.
    periods : int
        Forcing periods averaged over (after the transient and the frame's alignment).
    start : ndarray
        The state (``x1, v1, x2, v2``; a chain's ``system.state``) where the averaging began, at
        ``t0 + (transient + frame) T``.
    convergence : DataFrame
        The running averages after each period: ``period``, ``t`` (s of averaging) and
        ``lambda1`` ... ``lambda<n>``, the frame's columns in the order of the exponents.
    """

    case: Case | FrictionChain
    exponents: np.ndarray
    periods: int
    start: np.ndarray
    convergence: pd.DataFrame = field(repr=False)

    @property
    def largest(self) -> float:
        """The largest exponent (1/s): positive for a chaotic motion, zero for a quasi-periodic one,
        negative for a motion that settles on a periodic orbit."""
        return float(self.exponents[0])

    @property
    def dimension(self) -> float:
        """The Kaplan-Yorke dimension of the stroboscopic map's attractor, ``k + sum_(i<=k) lambda_i
        / |lambda_(k+1)|`` with ``k`` the most exponents whose sum is nonnegative (0 when the
        largest is negative)."""
        sums = np.cumsum(self.exponents)
        k = int(np.sum(sums >= 0))
        if k == 0:
            return 0.0
        if k == len(self.exponents) or not np.isfinite(self.exponents[k]):
            return float(k)
        return float(k + sums[k - 1] / abs(self.exponents[k]))

    def plot(self) -> Figure:
        """The running averages of the exponents against the averaging time (as ``oscillator
        lyapunov`` draws them)."""
        return presenter().plot_global(self)


def _start(case: Case, guess: Sequence[float] | np.ndarray | None, transient: int) -> tuple[float, np.ndarray]:
    """The state after ``transient`` periods from ``guess`` (or the case's start) at ``t0``."""
    y = case.initial.y if guess is None else check_guess(guess)
    return case.initial.t0 + transient * case.parameters.period, settled(case, y, transient)


def _qr_step(monodromy: np.ndarray, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The frame carried one period and re-orthonormalised, and ``log |R[i, i]|``."""
    q, r = np.linalg.qr(monodromy @ frame)
    with np.errstate(divide="ignore"):
        return q, np.log(np.abs(np.diag(r)))


def lyapunov(
    case: Case | FrictionChain | str,
    *,
    periods: int = 500,
    transient: int = 100,
    guess: Sequence[float] | np.ndarray | None = None,
    progress: Callable[[int, int], None] | None = None,
    **overrides: float,
) -> LyapunovSpectrum:
    """The Lyapunov spectrum of the motion from the case's start (or ``guess``).

    Parameters
    ----------
    case : Case, FrictionChain or str
        A case, a shipped case's name, or a declared system (its spectrum over its own state:
        :func:`oscillator.attractors.chain_attractors.chain_lyapunov`).
    periods : int
        Forcing periods averaged over (1 to 10^7).
    transient : int
        Forcing periods simulated first, so that the motion is on its attractor (0 to 10^7).
    guess : sequence of 4 floats, optional
        ``(x1, v1, x2, v2)`` at the case's ``t0`` to start from instead of the case's start.
    progress : callable, optional
        ``progress(done, total)`` after every averaged period.
    **overrides
        Any parameter, initial value or solver option, as for :func:`oscillator.simulate`.

    Examples
    --------
    >>> from oscillator.attractors.lyapunov import lyapunov
    >>> spectrum = lyapunov("instance-1", Omega=1.85, periods=50)
    >>> spectrum.largest < 0   # a stable periodic orbit
    True
    """
    periods = check_count(periods, "periods", 1, MAX_PERIODS)
    transient = check_count(transient, "transient", 0, MAX_PERIODS)
    check_progress(progress)
    if isinstance(case, FrictionChain):
        from oscillator.attractors.chain_attractors import chain_lyapunov

        chain = case.with_values(overrides) if overrides else case
        return chain_lyapunov(chain, periods=periods, transient=transient, guess=guess, progress=progress)
    case = resolve_case(case, **overrides)
    for k in (0, transient + periods - 1):  # the period resolved beside the first and the last section times
        section_times(case, k, k + 1)
    t, y = _start(case, guess, transient)

    def maps() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        nonlocal t, y
        while True:
            image = period_map(case, t, y, 1, derivative=True)
            assert image.monodromy is not None
            t, y = image.t1, image.end
            yield image.monodromy, y

    return qr_average(case, maps(), case.parameters.period, periods, progress)


def qr_average(
    system: Case | FrictionChain,
    maps: Iterator[tuple[np.ndarray, np.ndarray]],
    period: float,
    periods: int,
    progress: Callable[[int, int], None] | None = None,
) -> LyapunovSpectrum:
    """The spectrum of the period maps' derivatives ``maps`` yields (each with the state after
    it), one forcing period of ``period`` seconds each: the frame aligned over :data:`FRAME`
    maps, then the QR average over ``periods`` more (module docstring)."""
    start_state, frame = np.empty(0), np.empty((0, 0))
    sums, rows = np.zeros(0), []
    for k in range(-FRAME, periods):
        monodromy, y = next(maps)
        if k == -FRAME:
            frame, sums = np.eye(len(monodromy)), np.zeros(len(monodromy))
        frame, logs = _qr_step(monodromy, frame)
        if k < 0:
            start_state = y
            continue
        sums += logs
        rows.append((k + 1, (k + 1) * period, *(sums / ((k + 1) * period))))
        if progress is not None:
            progress(k + 1, periods)
    exponents = sums / (periods * period)
    order = np.argsort(-exponents, kind="stable")  # the frame's columns, largest final exponent first
    table = np.array(rows)
    convergence = pd.DataFrame(
        np.column_stack([table[:, :2], table[:, 2:][:, order]]),
        columns=["period", "t", *(f"lambda{k}" for k in range(1, len(order) + 1))],
    )
    convergence["period"] = convergence["period"].astype(int)
    return LyapunovSpectrum(system, exponents[order], periods, start_state, convergence)


def separation_exponent(
    case: Case | str,
    *,
    periods: int = 500,
    transient: int = 100,
    distance: float = 1e-8,
    **overrides: float,
) -> float:
    """The largest exponent from two nearby trajectories (Benettin's method): a copy ``distance``
    away is run beside the motion, their separation measured and the copy set back to
    ``distance`` along it after each period; the mean of ``log(separation / distance)`` per
    second.  Independent of the variational equations and the saltation matrices: the check of
    :func:`lyapunov` on a chaotic motion."""
    periods = check_count(periods, "periods", 1, MAX_PERIODS)
    transient = check_count(transient, "transient", 0, MAX_PERIODS)
    case = resolve_case(case, **overrides)
    t, y = _start(case, None, transient)
    direction = np.ones(4) / 2.0
    near = y + distance * direction
    total = 0.0
    for _ in range(periods):
        here = period_map(case, t, y, 1, derivative=False)
        there = period_map(case, t, near, 1, derivative=False)
        gap = there.end - here.end
        separation = float(np.linalg.norm(gap))
        total += np.log(separation / distance)
        t, y = here.t1, here.end
        near = y + gap * (distance / separation)
        near[np.abs(near) < TINY] = 0.0  # a component that died away (a stuck mass's velocity) is zero
    return float(total / (periods * case.parameters.period))
