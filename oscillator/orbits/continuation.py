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

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd

from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.parameters import Parameters
from oscillator.orbits.shooting import (
    STATE,
    PeriodMap,
    check_count,
    cyclic_signature,
    multipliers_of,
    newton,
    orbit_case,
    period_map,
    start_of,
)

__all__ = ["BIFURCATION_KINDS", "Branch", "continue_orbit"]

BIFURCATION_KINDS = ("sliding_onset", "sliding_vanish", "grazing", "fold", "period_doubling", "torus")


@dataclass(frozen=True)
class _Point:
    """One corrected point of the branch (its multipliers and signature computed once: the
    bisections ask for them again and again)."""

    y: np.ndarray
    lam: float
    image: PeriodMap
    tangent: np.ndarray  # in (y, lam / sigma)
    iterations: int

    @cached_property
    def multipliers(self) -> np.ndarray:
        assert self.image.monodromy is not None
        return multipliers_of(self.image.monodromy)

    @cached_property
    def signature(self) -> str:
        return cyclic_signature(self.image)

    @cached_property
    def unstable(self) -> int:
        return int(np.sum(np.abs(self.multipliers) > 1.0))


@dataclass(frozen=True)
class _Located:
    """A located bifurcation: its row, and the orbits on either side (None across a gap)."""

    row: dict
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
        located bifurcation): the parameter under its own name, ``x1, v1, x2, v2`` at ``t0``,
        ``mu1..mu4`` (the multipliers' moduli, largest first), ``stable``, ``signature`` (the
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
    t0 : float
        The section's time.
    period : int
        Forcing periods per return.
    complete : bool
        Whether the branch reached ``stop`` (else ``message`` says why it ended).
    message : str
    """

    param: str
    points: pd.DataFrame
    bifurcations: pd.DataFrame
    t0: float
    period: int
    complete: bool = True
    message: str = ""


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
        return _Point(y, lam, image, self.tangent(self.jacobian(y, lam, image), None, direction), 0)

    def residual(self, y: np.ndarray, lam: float) -> tuple[np.ndarray, PeriodMap]:
        image = period_map(self.at(lam), self.t0, y, self.period)
        return image.end - y, image

    def jacobian(self, y: np.ndarray, lam: float, image: PeriodMap) -> np.ndarray:
        """``[M - I, sigma dP/dlam]`` (4 x 5)."""
        assert image.monodromy is not None
        h = 1e-6 * max(1.0, abs(lam))
        plus = period_map(self.at(lam + h), self.t0, y, self.period, derivative=False).end
        minus = period_map(self.at(lam - h), self.t0, y, self.period, derivative=False).end
        column = self.sigma * (plus - minus) / (2 * h)
        return np.column_stack([image.monodromy - np.eye(4), column])

    def tangent(self, jacobian: np.ndarray, previous: np.ndarray | None, direction: float) -> np.ndarray:
        """The unit null vector of ``jacobian``, oriented along ``previous`` (or ``direction`` in lam)."""
        t = np.linalg.svd(jacobian)[2][-1]
        reference = previous @ t if previous is not None else direction * t[4]
        return -t if reference < 0 else t

    def correct(
        self, guess: np.ndarray, tangent: np.ndarray, anchor: np.ndarray, max_iterations: int = 8
    ) -> _Point | None:
        """Newton on ``F = 0`` and ``tangent . (u - anchor) = 0`` from ``guess``; None if it fails."""
        u = guess.copy()
        for iteration in range(max_iterations + 1):
            y, lam = u[:4], u[4] * self.sigma
            try:
                residual, image = self.residual(y, lam)
                jacobian = self.jacobian(y, lam, image)
            except OscillatorError:
                return None
            constraint = float(tangent @ (u - anchor))
            if np.max(np.abs(residual)) <= self.tol * self.scale and abs(constraint) <= 1e-9:
                return _Point(y.copy(), lam, image, self.tangent(jacobian, tangent, 1.0), iteration)
            if iteration == max_iterations:
                return None
            system = np.vstack([jacobian, tangent])
            try:
                step = np.linalg.solve(system, -np.append(residual, constraint))
            except np.linalg.LinAlgError:
                return None
            u = u + step
            if not np.isfinite(u).all():
                return None
        return None

    def along(self, a: _Point, s: float) -> _Point | None:
        """The point at arclength ``s`` from ``a`` along its tangent (corrected)."""
        u_a = np.append(a.y, a.lam / self.sigma)
        anchor = u_a + s * a.tangent
        return self.correct(anchor, a.tangent, anchor)


def _kind_of_change(before: str, after: str, increasing: bool) -> str:
    rests_before, rests_after = before.count("sliding_onset"), after.count("sliding_onset")
    if rests_before == rests_after:
        return "grazing"
    appears = (rests_after > rests_before) == increasing
    return "sliding_onset" if appears else "sliding_vanish"


def _critical(point: _Point) -> complex:
    values = point.multipliers
    return complex(values[np.argmin(np.abs(np.abs(values) - 1.0))])


def _check_range(param: str, start: float, stop: float, overrides: dict) -> tuple[float, float]:
    if param not in Parameters.names():
        raise InputError(f"param must be one of the parameters {', '.join(Parameters.names())}, got {param!r}",
                         field="param")  # fmt: skip
    if param in overrides:
        raise InputError(f"{param} is the continued parameter; give its range with start and stop", field=param)
    start, stop = float(start), float(stop)
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise InputError(f"start and stop must be two different finite numbers, got {start!r}, {stop!r}",
                         field="start")  # fmt: skip
    return start, stop


def continue_orbit(
    case: Case | str,
    *,
    param: str,
    start: float,
    stop: float,
    period: int = 1,
    t0: float | None = None,
    guess: tuple[float, float, float, float] | np.ndarray | None = None,
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
        past ``start`` after folds).
    period, t0, guess, transient, tol
        As for :func:`~oscillator.find_orbit`.
    step : float, optional
        The largest step along the branch, in units of ``|stop - start|`` (default 1/40).
    max_points : int
        The most points computed.
    locate_tol : float
        Bifurcations are located to this in the parameter.
    progress : callable, optional
        Called with the fraction of ``[start, stop]`` covered after each point.
    **overrides
        Any other parameter, initial value or solver option.

    Examples
    --------
    >>> from oscillator import continue_orbit
    >>> branch = continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5)
    >>> branch.bifurcations[["Q2", "kind"]].round(6).values.tolist()
    [[71.157742, 'sliding_vanish']]
    """
    start, stop = _check_range(param, start, stop, overrides)
    max_points = check_count(max_points, "max_points", 2)
    period = check_count(period, "period", 1)
    base = orbit_case(case, {**overrides, param: start})
    t0_, y_start = start_of(base, t0, guess, transient)
    sigma = abs(stop - start)
    ds_max = (1 / 40) if step is None else float(step)
    if not (0 < ds_max <= 1):
        raise InputError(f"step must be in (0, 1] (a fraction of |stop - start|), got {step!r}", field="step")
    cont = _Continuer(base, param, t0_, period, sigma, tol)
    direction = 1.0 if stop > start else -1.0

    trace = _Trace(cont.first(y_start, start, direction), cont.scale)
    points = trace.points
    ds, ds_min = ds_max / 4, ds_max / 2**12
    complete, message = False, ""
    lo, hi = min(start, stop), max(start, stop)
    while len(points) < max_points:
        a = points[-1]
        b = cont.along(a, ds)
        if b is None or b.iterations > 5:
            if ds <= ds_min:
                message = f"the corrector failed at {param} = {a.lam:.10g} with the smallest step"
                break
            ds /= 2
            continue
        if not lo - 1e-12 * sigma <= b.lam <= hi + 1e-12 * sigma:
            end = _end_point(cont, a, b, stop if (b.lam - stop) * direction > 0 else start)
            if end is not None:
                trace.add(_between(cont, a, end, ds, locate_tol), end)
            complete = end is not None and end.lam == stop
            message = "" if complete else f"the branch came back to {param} = {start:g} after a fold"
            break
        trace.add(_between(cont, a, b, ds, locate_tol), b)
        if progress is not None:
            progress(min(1.0, abs(b.lam - start) / sigma))
        if b.iterations <= 2:
            ds = min(ds * 1.5, ds_max)
    else:
        message = f"max_points = {max_points} reached at {param} = {points[-1].lam:.10g}"
    return Branch(param, trace.points_frame(param), trace.bifurcations_frame(param), t0_, period, complete, message)


class _Trace:
    """The branch as it is traced: its points, where each continuous piece begins, its bifurcations."""

    def __init__(self, first: _Point, scale: float) -> None:
        self.points, self.piece_starts = [first], [0]
        self.rows: list[dict] = []
        self.scale = scale

    def add(self, located: list[_Located], b: _Point) -> None:
        """The bifurcations between the last point and ``b``, the orbits on their sides (so the
        branch reaches each bifurcation), then ``b``; a new piece begins after a jump or a gap."""
        for found in located:
            self.rows.append(found.row)
            jump = found.row["jump"]
            if found.right is not None and (math.isnan(jump) or jump > 1e-6 * self.scale):
                self.piece_starts.append(len(self.points))
            for side in (found.left, found.right):
                last = self.points[-1]
                if side is not None and side is not b and not (side.lam == last.lam and np.array_equal(side.y, last.y)):
                    self.points.append(side)
        self.points.append(b)

    def points_frame(self, param: str) -> pd.DataFrame:
        pieces = np.zeros(len(self.points), dtype=int)
        for start in self.piece_starts[1:]:
            pieces[start:] += 1
        rows = []
        for p, piece in zip(self.points, pieces, strict=True):
            moduli = np.abs(p.multipliers)
            rows.append({param: p.lam, **dict(zip(STATE, p.y, strict=True)),
                         **{f"mu{k + 1}": float(moduli[k]) for k in range(4)}, "stable": bool(np.all(moduli < 1.0)),
                         "signature": p.signature, "piece": int(piece), "iterations": p.iterations})  # fmt: skip
        return pd.DataFrame(rows)

    def bifurcations_frame(self, param: str) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=[param, "kind", *STATE, "jump", "before", "after"])


def _end_point(cont: _Continuer, a: _Point, b: _Point, lam_end: float) -> _Point | None:
    """The orbit at ``lam = lam_end``, between ``a`` and ``b`` (Newton from their interpolation)."""
    weight = (lam_end - a.lam) / (b.lam - a.lam)
    end = _natural(cont, lam_end, a.y + weight * (b.y - a.y))
    return None if end is None else _Point(end.y, lam_end, end.image, b.tangent, end.iterations)


def _between(cont: _Continuer, a: _Point, b: _Point, ds: float, locate_tol: float) -> list[_Located]:
    """The bifurcations between two consecutive points, located, with the orbits on their sides."""
    if a.signature != b.signature:  # one or more changes of the event sequence, in turn
        found, current = [], a
        for _ in range(8):
            left, right = _bisect_signature(cont, current, b, locate_tol)
            kind = _kind_of_change(current.signature, right.signature, increasing=b.lam > a.lam)
            found += _signature_change(cont, kind, left, right, current.signature, locate_tol)
            if right.signature == b.signature:
                break
            current = _Point(right.y, right.lam, right.image, b.tangent, 0)
        return found
    if a.tangent[4] * b.tangent[4] < 0:
        sign = np.sign(a.tangent[4])
        left, right = _bisect(cont, a, b, ds, lambda p: np.sign(p.tangent[4]) == sign, locate_tol)
        return [_Located(_record(cont, "fold", left, right, a.signature, b.signature), left, right)]
    if a.unstable != b.unstable:
        count = a.unstable
        left, right = _bisect(cont, a, b, ds, lambda p: p.unstable == count, locate_tol)
        # the multiplier on the unit circle, read where it crosses (between the located sides)
        mu = min((_critical(left), _critical(right)), key=lambda value: abs(abs(value) - 1))
        if abs(mu.imag) > 1e-6 * abs(mu):
            kind = "torus"
        elif mu.real < 0:
            kind = "period_doubling"
        else:
            kind = "fold"
        return [_Located(_record(cont, kind, left, right, a.signature, b.signature), left, right)]
    return []


def _signature_change(
    cont: _Continuer, kind: str, left: _Point, right: _Point, before: str, locate_tol: float
) -> list[_Located]:
    """One row where the two sides meet; two where they do not (a gap: no period-N orbit lies
    between the end of ``left``'s kind and the start of ``right``'s)."""
    if abs(right.lam - left.lam) <= 3 * locate_tol:
        return [_Located(_record(cont, kind, left, right, before, right.signature), left, right)]
    return [
        _Located(_record(cont, kind, left, None, before, ""), left, None),
        _Located(_record(cont, kind, right, None, "", right.signature), None, right),
    ]


def _natural(cont: _Continuer, lam: float, guess: np.ndarray) -> _Point | None:
    """The orbit at ``lam`` by Newton from ``guess`` (no arclength condition); None if it fails."""
    try:
        y, image, _ = newton(cont.at(lam), cont.t0, guess, cont.period, tol=cont.tol, max_iterations=8)
    except OscillatorError:
        return None
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
        if p is not None and p.signature == a.signature:
            left = p
        else:
            beyond = mid
    right, short = b, left.lam  # the first orbit of another kind; where none was found
    if beyond != b.lam:  # most often the other kind exists right there
        p = _natural(cont, beyond, b.y + slope_b * (beyond - b.lam))
        if p is not None and p.signature != a.signature:
            right = p
    while abs(right.lam - short) > locate_tol:
        mid = 0.5 * (short + right.lam)
        p = _natural(cont, mid, right.y + slope_b * (mid - right.lam))
        if p is not None and p.signature != a.signature:
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
        if p is None:  # on the switching boundary itself: nudge
            p = cont.along(a, s * (1 + 1e-7))
            if p is None:
                break
        if like_a(p):
            lo_s, left = s, p
        else:
            hi_s, right = s, p
    return left, right


def _record(cont: _Continuer, kind: str, at: _Point, other: _Point | None, before: str, after: str) -> dict:
    """A bifurcation row: the parameter (between ``at`` and ``other``, or at ``at`` where no
    orbit lies on the other side), the state at ``at`` and ``jump``, the distance (max norm)
    between the two sides' states at the section (NaN without an ``other``; 0 at a fold,
    period doubling or torus, where the branch is smooth)."""
    lam = at.lam if other is None else 0.5 * (at.lam + other.lam)
    if other is None:
        jump = math.nan
    elif kind in ("fold", "period_doubling", "torus"):
        jump = 0.0
    else:
        jump = float(np.max(np.abs(other.y - at.y)))
    return {cont.param: lam, "kind": kind, **dict(zip(STATE, at.y, strict=True)), "jump": jump,
            "before": before, "after": after}  # fmt: skip
