"""Continuation of a periodic orbit in a parameter, and the bifurcations along the branch.

Pseudo-arclength continuation (Keller 1977; Allgower & Georg 2003, Ch. 2) of the zeros of
``F(y, lam) = P(y; lam) - y`` in ``u = (y, lam / sigma)`` with ``sigma = |stop - start|``:
a tangent predictor ``u + ds t`` and a Newton corrector on ``F = 0`` and ``t . (u - u_pred) = 0``.
``dF/dy = M - I`` is the monodromy matrix (:mod:`oscillator.orbits.shooting`); ``dF/dlam`` is a
central difference of the map.  The branch follows unstable parts and turns at folds.

Between two points, the branch has a bifurcation where

* the orbit's event signature changes (:func:`~oscillator.orbits.shooting.cyclic_signature`): a
  rest interval appears or disappears (``sliding_onset`` / ``sliding_vanish``, named as the
  parameter increases) or a pair of other switches does (``grazing``): the map is continuous
  but not differentiable there, and its multipliers may jump;
* ``lam`` turns back (``fold``), or a multiplier leaves the unit circle at -1
  (``period_doubling``) or as a complex pair (``torus``), with the signature unchanged.

Each is located by bisection along the branch, to ``locate_tol`` in the parameter.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Interrupted, OscillatorError, Reason, SimulationFailed
from oscillator.io.cases import Case, resolve_case
from oscillator.io.files import as_folder
from oscillator.model.parameters import Parameters, real_argument
from oscillator.orbits.shooting import (
    MAX_TRANSIENT,
    STATE,
    PeriodMap,
    Signature,
    check_count,
    check_guess,
    check_orbit_settings,
    cyclic_signature,
    fixed_point_system,
    moving_multipliers,
    multipliers_of,
    newton,
    orbit_case,
    period_map,
    pinned_rows,
    start_of,
    verdict_of,
)
from oscillator.presenting import presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["BIFURCATION_KINDS", "Bifurcation", "Branch", "ContinuationSettings", "check_settings", "continue_orbit"]


class Bifurcation(enum.StrEnum):
    """The kinds of bifurcation a branch locates, named as the parameter increases (the values
    are the ``kind`` column's text)."""

    SLIDING_ONSET = "sliding_onset"
    """A rest interval appears (a mass's cycle of switches gains a sliding onset)."""
    SLIDING_VANISH = "sliding_vanish"
    """A rest interval vanishes, or a mass at rest all period can no longer be held where it stuck."""
    GRAZING = "grazing"
    """The cycle of switches changes with as many rests: a pair of switches appears or vanishes
    where the orbit touches a boundary."""
    FOLD = "fold"
    """The branch turns back in the parameter: a multiplier crosses the unit circle at +1."""
    PERIOD_DOUBLING = "period_doubling"
    """A real multiplier crosses the unit circle at -1."""
    TORUS = "torus"
    """A complex pair of multipliers crosses the unit circle (Neimark-Sacker)."""

    @property
    def nonsmooth(self) -> bool:
        """Located where the cycle of switches changes (the map is not smooth there), not where a
        multiplier crosses the unit circle; the branch may jump across it."""
        return self in (Bifurcation.SLIDING_ONSET, Bifurcation.SLIDING_VANISH, Bifurcation.GRAZING)

    @classmethod
    def of_rests(cls, appears: bool) -> Bifurcation:
        """A rest interval appearing or vanishing as the parameter increases."""
        return cls.SLIDING_ONSET if appears else cls.SLIDING_VANISH

    @classmethod
    def of_multiplier(cls, mu: complex) -> Bifurcation:
        """The smooth bifurcation of a multiplier ``mu`` on the unit circle."""
        if abs(mu.imag) > 1e-6 * abs(mu):
            return cls.TORUS
        return cls.PERIOD_DOUBLING if mu.real < 0 else cls.FOLD


#: The kinds' text, as the ``kind`` column holds them.
BIFURCATION_KINDS = tuple(kind.value for kind in Bifurcation)
#: The default largest step, the smallest allowed and the most points (``continue_orbit``).
DEFAULT_STEP = 1 / 40
MIN_STEP = 1e-6
MAX_POINTS = 100_000


@dataclass(frozen=True)
class _Point:
    """One corrected point of the branch (its multipliers and signature computed once: the
    bisections ask for them again and again)."""

    y: np.ndarray
    lam: float
    image: PeriodMap
    tangent: np.ndarray  # in (y, lam / sigma)
    iterations: int
    #: ``sigma dP/dlam`` here, where it was computed (the corrector's next steps reuse it).
    column: np.ndarray | None = None

    @cached_property
    def multipliers(self) -> np.ndarray:
        assert self.image.monodromy is not None
        return multipliers_of(self.image.monodromy)

    @cached_property
    def signature(self) -> Signature:
        return cyclic_signature(self.image)

    @cached_property
    def rest_positions(self) -> tuple[tuple[int, float], ...]:
        """``(mass, x_i)`` of each mass at rest all period: where it stuck."""
        return tuple((mass, float(self.y[2 * mass - 2])) for mass in self.image.resting)

    def same_kind(self, other: _Point) -> bool:
        """The same cycle of switches, and every mass at rest all period resting at the same place
        (a family of such orbits is followed at that place; where static friction cannot hold
        the mass there any more, the orbit ends even if the signature does not change)."""
        if self.signature != other.signature or self.image.resting != other.image.resting:
            return False
        return all(
            abs(x - y) <= 1e-9 * max(1.0, abs(x))
            for (_, x), (_, y) in zip(self.rest_positions, other.rest_positions, strict=True)
        )

    @cached_property
    def unstable(self) -> int:
        """Multipliers outside the unit circle (a mass at rest all period adds none: its 1 is neutral)."""
        assert self.image.monodromy is not None
        return int(np.sum(np.abs(moving_multipliers(self.image.monodromy, self.image.resting)) > 1.0))

    @cached_property
    def stable(self) -> bool:
        assert self.image.monodromy is not None
        return verdict_of(self.image.monodromy, self.image.resting)


@dataclass(frozen=True)
class Skipped:
    """A point the corrector could not compute, and why (in place of a :class:`_Point`)."""

    lam: float
    reason: Reason
    message: str


def _skipped(lam: float, error: OscillatorError) -> Skipped:
    reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
    return Skipped(lam, reason, str(error))


@dataclass(frozen=True)
class _Located:
    """A located bifurcation: its row, and the orbits on either side (None across a gap)."""

    row: dict[str, Any]
    left: _Point | None
    right: _Point | None


@dataclass(frozen=True)
class Branch:
    """A continued branch of periodic orbits.

    Attributes
    ----------
    param : str
        The continued parameter.
    points : DataFrame
        One row per point, in the order of the branch (including the orbits on either side of each
        located bifurcation): the parameter under its own name, ``x1, v1, x2, v2`` at the section,
        ``mu1..mu4`` (the multipliers, complex, largest modulus first: a real one near -1
        is a period doubling, a complex pair leaving the unit circle a torus), ``stable``, ``signature`` (the
        event kinds over one period as a cycle:
        :func:`~oscillator.orbits.shooting.cyclic_signature`), ``piece`` (the branch's
        continuous pieces, numbered from 0: a new one begins after a jump or a gap) and
        ``iterations`` (the corrector's Newton steps; 0 for an orbit found at a bifurcation's
        side).
    bifurcations : DataFrame
        The parameter under its own name, ``kind`` (:data:`BIFURCATION_KINDS`), the state at the
        bifurcation (on the side the branch came from), ``jump`` (how far the orbit on the other
        side is, at the section: zero for a continuous bifurcation, finite where a rest interval
        appears with a finite length), ``before`` and ``after`` (the signatures on either side,
        along the branch).  Where no period-N orbit lies between the end of one kind and the
        start of the next (a gap), each end is a row of its own, with ``jump`` NaN and an empty
        ``after`` (the gap's first end) or ``before`` (its last), and the state of the orbit
        that ends there.
    section : float
        The section's time.
    period : int
        Forcing periods per return.
    complete : bool
        Whether the branch reached ``stop`` (else ``message`` says why it ended).
    message : str
    reason : Reason or None
        Why it ended early, for a program (:class:`~oscillator.errors.Reason`); None when complete.
    """

    param: str
    points: pd.DataFrame
    bifurcations: pd.DataFrame
    section: float
    period: int
    complete: bool = True
    message: str = ""
    reason: Reason | None = None
    case: Case | None = field(default=None, repr=False, compare=False)

    @property
    def coordinate(self) -> str:
        """The coordinate drawn by default: ``x2`` (as Fig. 14), unless it does not change along
        the branch (m2 parked): then the first of ``x1, v2, v1`` that does."""
        for name in ("x2", "x1", "v2", "v1"):
            values = self.points[name].to_numpy(float)
            if len(values) and np.ptp(values) > 1e-9 * max(1.0, float(np.max(np.abs(values)))):
                return name
        return "x2"

    def plot(self, coordinate: str | None = None, *, sweep_points: pd.DataFrame | None = None) -> Figure:
        """The branch as ``oscillator continue`` draws it (``figures/branch.png``): ``coordinate``
        at the section (default :attr:`coordinate`) against the parameter, stable solid,
        unstable dashed, bifurcations marked; over ``sweep_points`` (columns the parameter and
        ``coordinate``), if given."""
        return presenter().plot_branch(self, _coordinate(coordinate or self.coordinate), sweep_points)

    def plot_multipliers(self) -> Figure:
        """The multipliers' moduli against the parameter (``figures/multipliers.png``)."""
        return presenter().plot_multipliers(self)

    def save(self, folder: str | Path, *, coordinate: str | None = None) -> Path:
        """Write the branch as ``oscillator continue`` does (tables, ``case.toml``, ``run.json``,
        figures, report) into ``folder``, a new one; :func:`oscillator.read_run` reads it back."""
        return presenter().save_branch(self, as_folder(folder), coordinate=_coordinate(coordinate or self.coordinate))

    def _repr_html_(self) -> str:
        return presenter().branch_html(self)


def _coordinate(name: str) -> str:
    if name not in STATE:
        raise InputError(f"coordinate must be one of {', '.join(STATE)}, got {name!r}", field="coordinate")
    return name


class _Continuer:
    """The branch's state as it is traced: the case, the scaling and the corrector."""

    def __init__(self, case: Case, param: str, t0: float, period: int, sigma: float, tol: float) -> None:
        self.case, self.param, self.t0, self.period = case, param, t0, period
        self.sigma, self.tol = sigma, tol
        self.scale = max(1.0, abs(case.parameters.d), abs(case.parameters.d1))

    def at(self, lam: float) -> Case:
        return resolve_case(self.case, **{self.param: lam})

    def first(self, guess: np.ndarray, lam: float, direction: float) -> _Point:
        """The orbit at ``lam`` from ``guess``, with its tangent pointing ``direction`` in ``lam``."""
        y, image, _ = newton(self.at(lam), self.t0, guess, self.period, tol=self.tol, max_iterations=20)
        jacobian = self.jacobian(y, lam, image)
        return _Point(y, lam, image, self.tangent(jacobian, None, direction), 0, jacobian[:, 4])

    def residual(self, y: np.ndarray, lam: float) -> tuple[np.ndarray, PeriodMap]:
        """``P(y) - y`` (zero in the displacement of a mass at rest all period) and the map."""
        image = period_map(self.at(lam), self.t0, y, self.period)
        return fixed_point_system(image)[1], image

    def jacobian(self, y: np.ndarray, lam: float, image: PeriodMap, column: np.ndarray | None = None) -> np.ndarray:
        """``[M - I, sigma dP/dlam]`` (4 x 5); a mass at rest all period keeps its displacement:
        its row is ``[e_(x_i), 0]`` (:func:`~oscillator.orbits.shooting.fixed_point_system`).

        ``dP/dlam`` is a central difference (two runs without the derivative), unless ``column``
        is given (the corrector's steps between two points reuse the last point's: a chord
        method in ``lam``, exact in ``y``)."""
        if column is None:
            h = 1e-6 * max(1.0, abs(lam))
            plus = period_map(self.at(lam + h), self.t0, y, self.period, derivative=False).end
            minus = period_map(self.at(lam - h), self.t0, y, self.period, derivative=False).end
            column = self.sigma * (plus - minus) / (2 * h)
        column = column.copy()
        column[pinned_rows(image.settled)] = 0.0
        return np.column_stack([fixed_point_system(image)[0], column])

    def tangent(self, jacobian: np.ndarray, previous: np.ndarray | None, direction: float) -> np.ndarray:
        """The unit null vector of ``jacobian``, oriented along ``previous`` (or ``direction`` in lam)."""
        t: np.ndarray = np.linalg.svd(jacobian)[2][-1]
        reference = previous @ t if previous is not None else direction * t[4]
        return -t if reference < 0 else t

    def correct(
        self,
        guess: np.ndarray,
        tangent: np.ndarray,
        anchor: np.ndarray,
        max_iterations: int = 8,
        column: np.ndarray | None = None,
    ) -> _Point | Skipped:
        """Newton on ``F = 0`` and ``tangent . (u - anchor) = 0`` from ``guess``; why not, if it fails.

        Each step takes ``M`` where it stands (the run that gives ``F`` carries it) and
        ``dP/dlam`` from ``column`` when given (the last point's); the point found gets its own,
        computed there, and its tangent from it."""
        u = guess.copy()
        for iteration in range(max_iterations + 1):
            y, lam = u[:4], u[4] * self.sigma
            try:
                residual, image = self.residual(y, lam)
                converged = np.max(np.abs(residual)) <= self.tol * self.scale
                constraint = float(tangent @ (u - anchor))
                jacobian = self.jacobian(y, lam, image, None if converged else column)
            except OscillatorError as error:
                return _skipped(lam, error)
            if converged and abs(constraint) <= 1e-9:
                return _Point(y.copy(), lam, image, self.tangent(jacobian, tangent, 1.0), iteration, jacobian[:, 4])
            if iteration == max_iterations:
                break
            try:
                step = np.linalg.solve(np.vstack([jacobian, tangent]), -np.append(residual, constraint))
            except np.linalg.LinAlgError:
                return Skipped(lam, Reason.SINGULAR, "the corrector's system is singular")
            u = u + step
            if not np.isfinite(u).all():
                return Skipped(lam, Reason.SINGULAR, "the corrector's step is not finite")
        return Skipped(
            float(u[4] * self.sigma), Reason.NO_CONVERGENCE, f"the corrector did not converge in {max_iterations} steps"
        )

    def along(self, a: _Point, s: float) -> _Point | Skipped:
        """The point at arclength ``s`` from ``a`` along its tangent (corrected)."""
        u_a = np.append(a.y, a.lam / self.sigma)
        anchor = u_a + s * a.tangent
        return self.correct(anchor, a.tangent, anchor, column=a.column)


def _kind_of_change(before: Signature, after: Signature, increasing: bool) -> Bifurcation:
    """The kind of a change of the orbit's cycle of switches, named as the parameter increases;
    with the cycle unchanged, a mass at rest all period could no longer be held where it stuck."""
    if before == after:
        return Bifurcation.of_rests(appears=not increasing)
    if before.rests == after.rests:
        return Bifurcation.GRAZING
    return Bifurcation.of_rests(appears=(after.rests > before.rests) == increasing)


def _critical(point: _Point) -> complex:
    values = point.multipliers
    return complex(values[np.argmin(np.abs(np.abs(values) - 1.0))])


def _check_range(
    case: Case | str, param: str, start: object, stop: object, overrides: dict[str, Any], locate_tol: float
) -> tuple[float, float]:
    """``start`` and ``stop`` as valid values of ``param``, far enough apart to continue."""
    Parameters.check_name(param)
    if param in overrides:
        raise InputError(f"{param} is the continued parameter; give its range with start and stop", field=param)
    values = real_argument(start, "start"), real_argument(stop, "stop")
    for name, value in zip(("start", "stop"), values, strict=True):
        try:
            resolve_case(case, **{**overrides, param: value})
        except InputError as error:
            raise InputError(f"{name} = {value!r} is not a valid {param}: {error}", field=name) from None
    width = abs(values[1] - values[0])
    if width < 10 * locate_tol or width < 1e-12 * max(abs(values[0]), abs(values[1])):
        least = max(10 * locate_tol, 1e-12 * abs(values[0]))
        raise InputError(
            f"`stop` must be at least {least:.3g} away from `start` (10 times the location "
            f"tolerance), got {values[1]!r} and {values[0]!r}",
            field="stop",
        )
    return values


def continue_orbit(
    case: Case | str,
    *,
    param: str,
    start: float,
    stop: float,
    period: int = 1,
    section: float | None = None,
    guess: Sequence[float] | np.ndarray | None = None,
    transient: int | None = None,
    step: float | None = None,
    max_points: int = 400,
    tol: float = 1e-9,
    locate_tol: float = 1e-9,
    progress: Callable[[float], None] | None = None,
    **overrides: float,
) -> Branch:
    """Continue the period-``period`` orbit in ``param`` from ``start`` to ``stop``: a :class:`Branch`.

    Parameters
    ----------
    case : Case or str
    param : str
        Any parameter of :class:`~oscillator.Parameters` (``"Q2"``, ``"Omega"``, ...).
    start, stop : float
        The parameter's range; the branch starts at the orbit found at ``start`` (as
        :func:`~oscillator.find_orbit` finds it) and ends when it passes ``stop`` (or comes back
        past ``start`` after folds).  Both must be valid values of ``param`` with the case's
        other parameters, and at least ``10 locate_tol`` apart.
    period, section, guess, transient, tol
        As for :func:`~oscillator.find_orbit`.
    step : float, optional
        The largest step along the branch, in units of ``|stop - start|``, in ``[1e-6, 1]``
        (default 1/40).
    max_points : int
        The most points computed (2 to 100000).
    locate_tol : float
        Bifurcations are located to this in the parameter (``> 0``).
    progress : callable, optional
        Called with the fraction of ``[start, stop]`` covered after each point.
    **overrides
        Any other parameter, initial value or solver option.

    Returns
    -------
    Branch
        ``complete`` is False when the branch ended before ``stop`` (the corrector failed,
        ``max_points`` was reached, or the branch came back past ``start``), and ``message``
        says where and why; the points so far are kept.

    Raises
    ------
    InputError
        Bad input.
    SimulationFailed
        No orbit at ``start`` (Newton failed there, or the simulation did).
    Interrupted
        Ctrl-C: a ``KeyboardInterrupt`` whose ``result`` is the branch so far (``complete``
        False, ``message`` saying where it was interrupted).

    Examples
    --------
    >>> from oscillator import continue_orbit
    >>> branch = continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5)
    >>> branch.bifurcations[["Q2", "kind"]].round(6).values.tolist()
    [[71.157742, 'sliding_vanish']]
    """
    settings = check_settings(
        case,
        param=param,
        start=start,
        stop=stop,
        period=period,
        section=section,
        guess=guess,
        transient=transient,
        step=step,
        max_points=max_points,
        tol=tol,
        locate_tol=locate_tol,
        progress=progress,
        **overrides,
    )
    start, stop = settings.start, settings.stop
    base = orbit_case(case, {**overrides, param: start})
    section_, y_start = start_of(base, section, guess, transient)
    cont = _Continuer(base, param, section_, settings.period, abs(stop - start), settings.tol)
    direction = 1.0 if stop > start else -1.0

    trace = _Trace(cont.first(y_start, start, direction), cont.scale, param)
    try:
        complete, message = _trace_branch(cont, trace, settings, progress)
    except KeyboardInterrupt:
        last = trace.points[-1].lam
        trace.reason = Reason.INTERRUPTED
        partial = trace.branch(base, section_, settings.period, False, f"interrupted at {param} = {last:.10g}")
        raise Interrupted(partial) from None
    return trace.branch(base, section_, settings.period, complete, message)


@dataclass(frozen=True)
class ContinuationSettings:
    """:func:`continue_orbit`'s numeric settings, checked (:func:`check_settings`)."""

    start: float
    stop: float
    period: int
    tol: float
    locate_tol: float
    max_points: int
    step: float  #: the largest step, as a fraction of ``|stop - start|``


def check_settings(
    case: Case | str,
    *,
    param: str,
    start: object,
    stop: object,
    period: object = 1,
    section: object = None,
    guess: object = None,
    transient: object = None,
    step: object = None,
    max_points: object = 400,
    tol: object = 1e-9,
    locate_tol: object = 1e-9,
    progress: object = None,
    **overrides: object,
) -> ContinuationSettings:
    """Check :func:`continue_orbit`'s arguments without computing anything (the command line
    does so before it creates its folder).

    Raises
    ------
    InputError
        The first argument that is refused, named.
    """
    period_, tol_, _ = check_orbit_settings(period, tol, 1)
    locate_tol_ = real_argument(locate_tol, "locate_tol", positive=True)
    start_, stop_ = _check_range(case, param, start, stop, overrides, locate_tol_)
    max_points_ = check_count(max_points, "max_points", 2, MAX_POINTS)
    step_ = DEFAULT_STEP if step is None else real_argument(step, "step", positive=True)
    if not MIN_STEP <= step_ <= 1:
        raise InputError(
            f"step must be from {MIN_STEP:g} to 1 (a fraction of |stop - start|), got {shown(step)}", field="step"
        )
    if progress is not None and not callable(progress):
        raise InputError(f"progress must be a function of the fraction done, got {shown(progress)}", field="progress")
    if guess is not None:
        check_guess(guess)
    if transient is not None:
        check_count(transient, "transient", 0, MAX_TRANSIENT)
    if section is not None:
        real_argument(section, "section")
    return ContinuationSettings(start_, stop_, period_, tol_, locate_tol_, max_points_, step_)


def _trace_branch(
    cont: _Continuer, trace: _Trace, settings: ContinuationSettings, progress: Callable[[float], None] | None
) -> tuple[bool, str]:
    """Step along the branch from its first point to ``stop``; ``(complete, why it ended)``."""
    param, sigma, points = cont.param, cont.sigma, trace.points
    start, stop, ds_max = settings.start, settings.stop, settings.step
    max_points, locate_tol = settings.max_points, settings.locate_tol
    direction = 1.0 if stop > start else -1.0
    ds, ds_min = ds_max / 4, ds_max / 2**12
    lo, hi = min(start, stop), max(start, stop)
    while len(points) < max_points:
        a = points[-1]
        b = cont.along(a, ds)
        fits = isinstance(b, _Point) and b.iterations <= 5
        own = _own_kind(cont, a, b) if isinstance(b, _Point) and fits and not b.same_kind(a) else None
        if own is not None and ds <= ds_min:  # the corrector keeps jumping: take a's kind there
            b = _Point(
                own.y,
                own.lam,
                own.image,
                cont.tangent(cont.jacobian(own.y, own.lam, own.image), a.tangent, 1.0),
                own.iterations,
            )
        elif not isinstance(b, _Point) or not fits or own is not None:
            if ds <= ds_min:
                why = f": {b.message} ({b.reason})" if isinstance(b, Skipped) else " (it kept jumping to another orbit)"
                trace.reason = b.reason if isinstance(b, Skipped) else Reason.NO_CONVERGENCE
                return False, f"the corrector failed at {param} = {a.lam:.10g} with the smallest step{why}"
            ds /= 2
            continue
        if not lo - 1e-12 * sigma <= b.lam <= hi + 1e-12 * sigma:
            end = _end_point(cont, a, b, stop if (b.lam - stop) * direction > 0 else start)
            if isinstance(end, Skipped):
                trace.reason = end.reason
                return False, f"no orbit found at {param} = {stop:.10g}, the end of the range: {end.message}"
            trace.add(_between(cont, a, end, ds, locate_tol), end)
            if end.lam == stop:
                return True, ""
            trace.reason = Reason.NO_ORBIT
            return False, f"the branch came back to {param} = {start:.10g} after a fold"
        trace.add(_between(cont, a, b, ds, locate_tol), b)
        if progress is not None:
            progress(min(1.0, abs(b.lam - start) / sigma))
        if b.iterations <= 2:
            ds = min(ds * 1.5, ds_max)
    trace.reason = Reason.MAX_POINTS
    return False, (
        f"max_points = {max_points} reached at {param} = {points[-1].lam:.10g}, "
        f"{abs(points[-1].lam - start) / sigma:.0%} of the range"
    )


def _own_kind(cont: _Continuer, a: _Point, b: _Point) -> _Point | None:
    """The orbit of ``a``'s kind at ``b``'s parameter, if there is one although the corrector
    went to ``b``, of another kind (two orbits coexist there): then the step is retried shorter
    (or, at the smallest step, this orbit is taken), so that the branch follows its own orbit
    to where it ends."""
    own = _natural(cont, b.lam, a.y + _slope(a, cont.sigma) * (b.lam - a.lam))
    return own if isinstance(own, _Point) and own.same_kind(a) else None


class _Trace:
    """The branch as it is traced: its points, where each continuous piece begins, its bifurcations."""

    def __init__(self, first: _Point, scale: float, param: str) -> None:
        self.param = param
        self.points, self.piece_starts = [first], [0]
        self.rows: list[dict[str, Any]] = []
        self.scale = scale
        #: Why the branch ended early (set where it does).
        self.reason: Reason | None = None

    def add(self, located: list[_Located], b: _Point) -> None:
        """The bifurcations between the last point and ``b``, the orbits on their sides (so the
        branch reaches each bifurcation), then ``b``; a new piece begins after a jump or a gap."""
        for found in located:
            self.rows.append(found.row)
            jump = found.row["jump"]
            self._append(found.left, b)
            if found.right is not None and (math.isnan(jump) or jump > 1e-6 * self.scale):
                self.piece_starts.append(len(self.points))  # the orbit beyond the jump starts a piece
            self._append(found.right, b)
        self.points.append(b)

    def _append(self, side: _Point | None, b: _Point) -> None:
        last = self.points[-1]
        if side is not None and side is not b and not (side.lam == last.lam and np.array_equal(side.y, last.y)):
            self.points.append(side)

    def points_frame(self, param: str) -> pd.DataFrame:
        pieces = np.zeros(len(self.points), dtype=int)
        for start in self.piece_starts[1:]:
            pieces[start:] += 1
        rows = []
        for p, piece in zip(self.points, pieces, strict=True):
            rows.append(
                {
                    param: p.lam,
                    **dict(zip(STATE, p.y, strict=True)),
                    **{f"mu{k + 1}": complex(p.multipliers[k]) for k in range(4)},
                    "stable": p.stable,
                    "signature": str(p.signature),
                    "piece": int(piece),
                    "iterations": p.iterations,
                }
            )
        return pd.DataFrame(rows)

    def bifurcations_frame(self, param: str) -> pd.DataFrame:
        numbers = dict.fromkeys([param, *STATE, "jump"], float)
        frame = pd.DataFrame(self.rows, columns=[param, "kind", *STATE, "jump", "before", "after"])
        return frame.astype({**numbers, "kind": object, "before": object, "after": object})

    def branch(self, case: Case, section: float, period: int, complete: bool, message: str) -> Branch:
        """The :class:`Branch` traced so far (``case``: the case at its start)."""
        param = self.param
        reason = None if complete else self.reason
        return Branch(
            param,
            self.points_frame(param),
            self.bifurcations_frame(param),
            section,
            period,
            complete,
            message,
            reason,
            case,
        )


def _end_point(cont: _Continuer, a: _Point, b: _Point, lam_end: float) -> _Point | Skipped:
    """The orbit at ``lam = lam_end``, between ``a`` and ``b``: of ``a``'s kind where that still
    exists (Newton from ``a`` moved along the branch's slope), else Newton from the
    interpolation of ``a`` and ``b``."""
    own = _natural(cont, lam_end, a.y + _slope(a, cont.sigma) * (lam_end - a.lam))
    if not isinstance(own, _Point) or not own.same_kind(a):
        weight = (lam_end - a.lam) / (b.lam - a.lam)
        own = _natural(cont, lam_end, a.y + weight * (b.y - a.y))
    return own if isinstance(own, Skipped) else _Point(own.y, lam_end, own.image, b.tangent, own.iterations)


def _between(cont: _Continuer, a: _Point, b: _Point, ds: float, locate_tol: float) -> list[_Located]:
    """The bifurcations between two consecutive points, located, with the orbits on their sides."""
    if not a.same_kind(b):  # one or more changes of the event sequence, in turn
        found, current = [], a
        for _ in range(8):
            left, right = _bisect_signature(cont, current, b, locate_tol)
            kind = _kind_of_change(current.signature, right.signature, increasing=b.lam > a.lam)
            found += _signature_change(cont, kind, left, right, current.signature, locate_tol)
            if right.same_kind(b):
                break
            current = _Point(right.y, right.lam, right.image, b.tangent, 0)
        return found
    if a.tangent[4] * b.tangent[4] < 0:
        sign = np.sign(a.tangent[4])
        left, right = _bisect(cont, a, b, ds, lambda p: np.sign(p.tangent[4]) == sign, locate_tol)
        return [_Located(_record(cont, Bifurcation.FOLD, left, right, a.signature, b.signature), left, right)]
    if a.unstable != b.unstable:
        count = a.unstable
        left, right = _bisect(cont, a, b, ds, lambda p: p.unstable == count, locate_tol)
        # the multiplier on the unit circle, read where it crosses (between the located sides)
        mu = min((_critical(left), _critical(right)), key=lambda value: abs(abs(value) - 1))
        kind = Bifurcation.of_multiplier(mu)
        return [_Located(_record(cont, kind, left, right, a.signature, b.signature), left, right)]
    return []


def _signature_change(
    cont: _Continuer, kind: Bifurcation, left: _Point, right: _Point, before: Signature, locate_tol: float
) -> list[_Located]:
    """One row where the two sides meet; two where they do not (a gap: no period-N orbit lies
    between the end of ``left``'s kind and the start of ``right``'s)."""
    if abs(right.lam - left.lam) <= 3 * locate_tol:
        return [_Located(_record(cont, kind, left, right, before, right.signature), left, right)]
    return [
        _Located(_record(cont, kind, left, None, before, None), left, None),
        _Located(_record(cont, kind, right, None, None, right.signature), None, right),
    ]


def _natural(cont: _Continuer, lam: float, guess: np.ndarray) -> _Point | Skipped:
    """The orbit at ``lam`` by Newton from ``guess`` (no arclength condition); why not, if it fails."""
    try:
        y, image, _ = newton(cont.at(lam), cont.t0, guess, cont.period, tol=cont.tol, max_iterations=8)
    except OscillatorError as error:
        return _skipped(lam, error)
    return _Point(y, lam, image, np.zeros(5), 0)


def _slope(p: _Point, sigma: float) -> np.ndarray:
    """``dy/dlam`` along the branch at ``p`` (zero where unknown or at a fold)."""
    return p.tangent[:4] / (p.tangent[4] * sigma) if p.tangent[4] != 0 else np.zeros(4)


def _bisect_signature(cont: _Continuer, a: _Point, b: _Point, locate_tol: float) -> tuple[_Point, _Point]:
    """The last orbit of ``a``'s signature and the first of another, between ``a`` and ``b``.

    The map is not differentiable where the signature changes, and with static > kinetic
    friction not even continuous: a rest interval can appear with a finite length.  So each side
    is followed from its own side, by bisection in the parameter with Newton at fixed parameter
    started from the nearest orbit of its kind (moved along the branch's slope):

    * the end of ``a``'s kind, from ``a``;
    * the start of the other kind, from ``b``.

    They meet where the orbit changes continuously.  Where the two kinds overlap (hysteresis), the
    first bisection finds where ``a``'s kind ends and the other is found at once beyond it; where
    neither exists in between, the two ends are apart: a gap in the branch, where the motion is
    not a period-N orbit (or one this branch does not pass).
    """
    slope_a, slope_b = _slope(a, cont.sigma), _slope(b, cont.sigma)
    left, beyond = a, b.lam  # the last orbit like a; a parameter where none like a was found
    while abs(beyond - left.lam) > locate_tol:
        mid = 0.5 * (left.lam + beyond)
        p = _natural(cont, mid, left.y + slope_a * (mid - left.lam))
        if isinstance(p, _Point) and p.same_kind(a):
            left = p
        else:
            beyond = mid
    right, short = b, left.lam  # the first orbit of another kind; where none was found
    if beyond != b.lam:  # most often the other kind exists right there
        p = _natural(cont, beyond, b.y + slope_b * (beyond - b.lam))
        if isinstance(p, _Point) and not p.same_kind(a):
            right = p
    while abs(right.lam - short) > locate_tol:
        mid = 0.5 * (short + right.lam)
        p = _natural(cont, mid, right.y + slope_b * (mid - right.lam))
        if isinstance(p, _Point) and not p.same_kind(a):
            right = p
        else:
            short = mid
    return left, right


def _bisect(
    cont: _Continuer, a: _Point, b: _Point, ds: float, like_a: Callable[[_Point], bool], locate_tol: float
) -> tuple[_Point, _Point]:
    """Bisect the arclength between ``a`` and ``b`` until the two sides are within ``locate_tol``
    in the parameter; the last point like ``a`` and the first like ``b``."""
    lo_s, hi_s, left, right = 0.0, ds, a, b
    for _ in range(80):
        if abs(right.lam - left.lam) <= locate_tol and hi_s - lo_s <= 1e-3 * ds:
            break
        s = 0.5 * (lo_s + hi_s)
        p = cont.along(a, s)
        if isinstance(p, Skipped):  # on the switching boundary itself: nudge
            p = cont.along(a, s * (1 + 1e-7))
            if isinstance(p, Skipped):
                break
        if like_a(p):
            lo_s, left = s, p
        else:
            hi_s, right = s, p
    return left, right


def _record(
    cont: _Continuer,
    kind: Bifurcation,
    at: _Point,
    other: _Point | None,
    before: Signature | None,
    after: Signature | None,
) -> dict[str, object]:
    """A bifurcation row: the parameter (between ``at`` and ``other``, or at ``at`` where no
    orbit lies on the other side), the state at ``at`` and ``jump``, the distance (max norm)
    between the two sides' states at the section (NaN without an ``other``; 0 at a fold,
    period doubling or torus, where the branch is smooth)."""
    lam = at.lam if other is None else 0.5 * (at.lam + other.lam)
    if other is None:
        jump = math.nan
    elif not kind.nonsmooth:
        jump = 0.0
    else:
        jump = float(np.max(np.abs(other.y - at.y)))
    return {
        cont.param: lam,
        "kind": kind.value,
        **dict(zip(STATE, at.y, strict=True)),
        "jump": jump,
        "before": "" if before is None else str(before),
        "after": "" if after is None else str(after),
    }
