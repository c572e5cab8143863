"""Locating a branch's bifurcations between two of its points, by bisection along the branch to
``locate_tol`` in the parameter: a change of the cycle of switches (sliding, grazing), a fold, a
multiplier leaving the unit circle; and the orbit where a branch ends."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from oscillator.orbits.branch import Bifurcation, Skipped
from oscillator.orbits.corrector import (
    Continuer,
    Located,
    OrbitPoint,
    critical_multiplier,
    kind_of_change,
    natural,
    slope,
)
from oscillator.orbits.shooting import STATE
from oscillator.orbits.signature import Signature

__all__ = ["between", "end_point", "own_kind", "record_bifurcation"]


def own_kind(cont: Continuer, a: OrbitPoint, b: OrbitPoint) -> OrbitPoint | None:
    """The orbit of ``a``'s kind at ``b``'s parameter, if there is one although the corrector
    went to ``b``, of another kind (two orbits coexist there): then the step is retried shorter
    (or, at the smallest step, this orbit is taken), so that the branch follows its own orbit
    to where it ends."""
    own = natural(cont, b.lam, a.y + slope(a, cont.sigma) * (b.lam - a.lam))
    return own if isinstance(own, OrbitPoint) and own.same_kind(a) else None


def end_point(cont: Continuer, a: OrbitPoint, b: OrbitPoint, lam_end: float) -> OrbitPoint | Skipped:
    """The orbit at ``lam = lam_end``, between ``a`` and ``b``: of ``a``'s kind where that still
    exists (Newton from ``a`` moved along the branch's slope), else Newton from the
    interpolation of ``a`` and ``b``."""
    own = natural(cont, lam_end, a.y + slope(a, cont.sigma) * (lam_end - a.lam))
    if not isinstance(own, OrbitPoint) or not own.same_kind(a):
        weight = (lam_end - a.lam) / (b.lam - a.lam)
        own = natural(cont, lam_end, a.y + weight * (b.y - a.y))
    return own if isinstance(own, Skipped) else OrbitPoint(own.y, lam_end, own.image, b.tangent, own.iterations)


def between(cont: Continuer, a: OrbitPoint, b: OrbitPoint, ds: float, locate_tol: float) -> list[Located]:
    """The bifurcations between two consecutive points, located, with the orbits on their sides."""
    if not a.same_kind(b):  # one or more changes of the event sequence, in turn
        found, current = [], a
        for _ in range(8):
            left, right = bisect_signature(cont, current, b, locate_tol)
            kind = kind_of_change(current.signature, right.signature, increasing=b.lam > a.lam)
            found += signature_change(cont, kind, left, right, current.signature, locate_tol)
            if right.same_kind(b):
                break
            current = OrbitPoint(right.y, right.lam, right.image, b.tangent, 0)
        return found
    if a.tangent[4] * b.tangent[4] < 0:
        sign = np.sign(a.tangent[4])
        left, right = bisect(cont, a, b, ds, lambda p: np.sign(p.tangent[4]) == sign, locate_tol)
        if not _at_fold(left, right):  # the slope dP/dlam jumped near a switch's change, not a fold
            return []
        return [Located(record_bifurcation(cont, Bifurcation.FOLD, left, right, a.signature, b.signature), left, right)]
    if a.unstable != b.unstable:
        count = a.unstable
        left, right = bisect(cont, a, b, ds, lambda p: p.unstable == count, locate_tol)
        # the multiplier on the unit circle, read where it crosses (between the located sides)
        mu = min((critical_multiplier(left), critical_multiplier(right)), key=lambda value: abs(abs(value) - 1))
        kind = Bifurcation.of_multiplier(mu)
        return [Located(record_bifurcation(cont, kind, left, right, a.signature, b.signature), left, right)]
    return []


#: At a fold a multiplier is 1: the turn is a fold where one is within this of 1 on either side.
FOLD_MULTIPLIER = 0.05


def _at_fold(left: OrbitPoint, right: OrbitPoint) -> bool:
    """Whether the branch turns at a fold between ``left`` and ``right``: a multiplier is near 1
    (:data:`FOLD_MULTIPLIER`).  Beside a point where the cycle of switches changes, the central
    difference ``dP/dlam`` can straddle it and turn the tangent without a fold."""
    values = np.concatenate([left.multipliers, right.multipliers])
    return bool(np.min(np.abs(values - 1.0)) <= FOLD_MULTIPLIER)


def signature_change(
    cont: Continuer, kind: Bifurcation, left: OrbitPoint, right: OrbitPoint, before: Signature, locate_tol: float
) -> list[Located]:
    """One row where the two sides meet; two where they do not (a gap: no period-N orbit lies
    between the end of ``left``'s kind and the start of ``right``'s)."""
    if abs(right.lam - left.lam) <= 3 * locate_tol:
        return [Located(record_bifurcation(cont, kind, left, right, before, right.signature), left, right)]
    return [
        Located(record_bifurcation(cont, kind, left, None, before, None), left, None),
        Located(record_bifurcation(cont, kind, right, None, None, right.signature), None, right),
    ]


def bisect_signature(cont: Continuer, a: OrbitPoint, b: OrbitPoint, locate_tol: float) -> tuple[OrbitPoint, OrbitPoint]:
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
    slope_a, slope_b = slope(a, cont.sigma), slope(b, cont.sigma)
    left, beyond = a, b.lam  # the last orbit like a; a parameter where none like a was found
    while abs(beyond - left.lam) > locate_tol:
        mid = 0.5 * (left.lam + beyond)
        p = natural(cont, mid, left.y + slope_a * (mid - left.lam))
        if isinstance(p, OrbitPoint) and p.same_kind(a):
            left = p
        else:
            beyond = mid
    right, short = b, left.lam  # the first orbit of another kind; where none was found
    if beyond != b.lam:  # most often the other kind exists right there
        p = natural(cont, beyond, b.y + slope_b * (beyond - b.lam))
        if isinstance(p, OrbitPoint) and not p.same_kind(a):
            right = p
    while abs(right.lam - short) > locate_tol:
        mid = 0.5 * (short + right.lam)
        p = natural(cont, mid, right.y + slope_b * (mid - right.lam))
        if isinstance(p, OrbitPoint) and not p.same_kind(a):
            right = p
        else:
            short = mid
    return left, right


def bisect(
    cont: Continuer, a: OrbitPoint, b: OrbitPoint, ds: float, like_a: Callable[[OrbitPoint], bool], locate_tol: float
) -> tuple[OrbitPoint, OrbitPoint]:
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


def record_bifurcation(
    cont: Continuer,
    kind: Bifurcation,
    at: OrbitPoint,
    other: OrbitPoint | None,
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
