"""A friction chain's periodic orbit followed in one of its numbers through folds: pseudo-arclength
continuation (issue 52), ``oscillator.continue_orbit(chain, param="Omega", start=0.8, stop=1.6)``.

The unknowns are the orbit's free coordinates at the section and the number ``lam`` (scaled by the
span's width); the equations ``P(y, lam) - y = 0`` (:mod:`oscillator.orbits.chain_orbits`) and the
arclength condition ``t . (u - u_pred) = 0``.  Their Jacobian ``[M - I, dP/dlam]`` is exact: the
monodromy and the map's derivative in the number, through every switch
(:mod:`oscillator.orbits.chain_tangents`).  From each point the tangent (the Jacobian's null vector,
oriented as the last) predicts the next, Newton corrects it; the step grows after an easy
correction and halves after a hard or failed one.  A fold is where the tangent's ``lam``
component changes sign, located on the parabola through the three points about it; a change of
stability says which multiplier left the unit circle (:meth:`~oscillator.orbits.branch.
Bifurcation.of_multiplier`: through -1 a period doubling, as a complex pair a torus).
The branch ends where it leaves the span, where the coordinates that move at the section change
(a mass starts or stops sticking there: the branch continues as another kind of orbit; the steps
shorten to :data:`MIN_STEP` first, so that the branch ends at the change), or where the corrector
fails at the smallest step; the reason is kept.  Where the orbit's cycle of switches changes
between two points (a stop or a contact starts or stops closing: a grazing, where the branch may
turn as sharply as at a fold), the step across is shortened to :data:`CROSS_STEP`, so that the
branch passes the grazing within that much of the span.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.model.chains import FrictionChain
from oscillator.orbits.branch import Bifurcation
from oscillator.orbits.chain_orbits import ChainOrbit, chain_period_map, find_chain_orbit, held_coordinates
from oscillator.orbits.chain_response import orbit_measures
from oscillator.orbits.chain_tangents import check_names, tangent_pass

__all__ = ["ChainBranch", "continue_chain_orbit", "cycle_text", "locate_change"]

#: The corrector's tolerance on ``|P(y) - y|`` (relative to the state's scale, at least 1).
TOL = 1e-10
#: The smallest step, as a fraction of the span's width.
MIN_STEP = 1e-5
#: The longest step across a point where the orbit's cycle of switches changes (a grazing: the
#: branch turns sharply there, and a long step would cut the corner).
CROSS_STEP = 1e-4


@dataclass(frozen=True)
class ChainBranch:
    """A followed branch: ``points`` (one row a point in the order followed: the number, ``stable``,
    ``largest`` (the largest multiplier's modulus), the measures and the state), ``folds`` and
    ``bifurcations`` (``kind``, the number's value, the point before), and why it ended."""

    chain: FrictionChain
    param: str
    points: pd.DataFrame
    bifurcations: pd.DataFrame
    ended: str
    width: float = 1.0
    """The span's width, the number's scale in the arclength."""

    @property
    def folds(self) -> pd.DataFrame:
        """The folds (turning points in the number)."""
        return self.bifurcations[self.bifurcations.kind == Bifurcation.FOLD]


@dataclass(frozen=True)
class _Point:
    y: np.ndarray
    lam: float
    tangent: np.ndarray
    orbit: ChainOrbit
    iterations: int


class _Follower:
    """The branch's equations at a value of the number (the chain, its free coordinates, the scale)."""

    def __init__(self, chain: FrictionChain, param: str, span: tuple[float, float], free: list[int]) -> None:
        self.chain, self.param, self.free = chain, param, free
        self.low, self.high = span
        self.width = span[1] - span[0]

    def system(self, y: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray, ChainOrbit]:
        """``P(y) - y`` over the free coordinates, ``[M - I, width dP/dlam]`` and the orbit's run."""
        chain = self.chain.with_values({self.param: lam})
        image = chain_period_map(chain, chain.t0, y)
        held, neutral = held_coordinates(chain, image)
        if sorted(set(range(len(y))) - held) != self.free:
            raise _Changed(lam)
        along = tangent_pass(image, [self.param])
        free = self.free
        ends = np.asarray(image.y_end[: len(y)], dtype=float)
        residual = (ends - y)[free]
        jacobian = np.column_stack(
            [along.monodromy[np.ix_(free, free)] - np.eye(len(free)), self.width * along.derivatives[free, 0]]
        )
        names = chain.system.state
        orbit = ChainOrbit(
            chain,
            chain.t0,
            y,
            1,
            tuple(names[k] for k in free),
            float(np.abs(residual).max(initial=0.0)),
            0,
            neutral,
            image,
        )
        orbit.__dict__["monodromy"] = along.monodromy[np.ix_(free, free)]  # known already: the cached value
        return residual, jacobian, orbit

    def tangent(self, jacobian: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
        t: np.ndarray = np.linalg.svd(jacobian)[2][-1]
        reference = previous @ t if previous is not None else t[-1]
        return -t if reference < 0 else t

    def correct(self, guess: _Point, step: float) -> _Point | None:
        """Newton from the prediction ``guess + step t`` with the arclength condition; None if it fails."""
        anchor = np.append(guess.y[self.free], guess.lam / self.width) + step * guess.tangent
        u, y = anchor.copy(), guess.y.copy()
        for iteration in range(8):
            y[self.free], lam = u[:-1], u[-1] * self.width
            try:
                residual, jacobian, orbit = self.system(y, lam)
            except _Changed:
                raise
            except OscillatorError:
                return None
            scale = max(1.0, float(np.abs(y).max()))
            constraint = float(guess.tangent @ (u - anchor))
            if np.abs(residual).max(initial=0.0) <= TOL * scale and abs(constraint) <= 1e-9:
                return _Point(y.copy(), lam, self.tangent(jacobian, guess.tangent), orbit, iteration)
            try:
                u = u + np.linalg.solve(np.vstack([jacobian, guess.tangent]), -np.append(residual, constraint))
            except np.linalg.LinAlgError:
                return None
            if not np.isfinite(u).all():
                return None
        return None


class _Changed(OscillatorError):
    """The coordinates that move at the section changed at ``lam``."""

    def __init__(self, lam: float) -> None:
        super().__init__(f"the coordinates that move at the section change at {lam:.8g}")
        self.lam = lam


def continue_chain_orbit(
    chain: FrictionChain,
    *,
    param: str,
    start: float,
    stop: float,
    guess: np.ndarray | None = None,
    step: float = 0.1,
    max_points: int = 500,
    transient: int = 100,
    within: tuple[float, float] | None = None,
    measures: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> ChainBranch:
    """The period-1 orbit of ``chain`` followed in ``param`` from ``start`` towards ``stop`` (its
    orbit at ``start`` found from ``guess``, or after ``transient`` forcing periods) until it
    leaves the span between them, or ``within`` (a wider span holding both: a branch that turns
    at a fold goes on inside it; module docstring); ``step`` the first and largest arclength step
    as a fraction of the span's width; ``measures=False`` leaves the orbits' response measures out
    of the points (a bifurcation curve's lines need none).  ``oscillator.continue_orbit(chain,
    param=..., start=..., stop=...)`` calls it."""
    (param,) = check_names(chain, [param])
    low, high = sorted((float(start), float(stop)))
    if not low < high:
        raise InputError(f"start and stop must differ, got {start!r} and {stop!r}", field="stop")
    if within is not None:
        if not within[0] <= low < high <= within[1]:
            raise InputError(f"within {within} must hold {start!r} and {stop!r}", field="within")
        low, high = float(within[0]), float(within[1])
    if not 0 < step <= 0.5 or isinstance(max_points, bool) or not 2 <= max_points <= 100_000:
        raise InputError("step must be in (0, 0.5] and max_points 2 to 100000", field="step")
    first = find_chain_orbit(chain.with_values({param: float(start)}), guess, transient=transient)
    names = list(chain.system.state)
    follower = _Follower(chain, param, (low, high), [names.index(n) for n in first.free])
    _, jacobian, orbit = follower.system(first.state, float(start))
    heading = np.zeros(len(follower.free) + 1)
    heading[-1] = 1.0 if stop > start else -1.0
    point = _Point(first.state, float(start), follower.tangent(jacobian, heading), orbit, first.iterations)
    points, ended = _follow(follower, point, step, max_points, progress)
    table = _table(points, param, names, measures)
    return ChainBranch(chain, param, table, _changes(points, param), ended, high - low)


def _follow(
    follower: _Follower, point: _Point, step: float, max_points: int, progress: Callable[[int, int], None] | None
) -> tuple[list[_Point], str]:
    """The points from ``point`` on, and why the branch ended."""
    points, h = [point], step
    while len(points) < max_points:
        changed: _Changed | None = None
        try:
            found = follower.correct(point, h)
        except _Changed as change:  # shorter steps approach where it changes
            found, changed = None, change
        crossed = found is not None and _cycle(found.orbit) != _cycle(point.orbit) and h > CROSS_STEP
        if found is None or (found.iterations > 4 and h > MIN_STEP) or crossed:
            h /= 2
            if h < MIN_STEP:
                return points, _why(point.lam, changed)
            continue
        points.append(found)
        point, h = found, min(step, h * 1.5) if found.iterations <= 3 else h
        if progress is not None:
            progress(len(points), max_points)
        if not follower.low <= found.lam <= follower.high:
            return points, "the end of the span"
    return points, f"max_points = {max_points} reached"


def _cycle(orbit: ChainOrbit) -> tuple[tuple[str, str, int], ...]:
    """The orbit's switches inside its return, counted by element and kind (not at its ends: the
    run's start sets its modes there): where it changes between two points, a switch appeared or
    went between them (a grazing)."""
    span = orbit.period * orbit.chain.period
    t = orbit.events.t - orbit.section
    inside = orbit.events[(t > 1e-9 * span) & (t < span * (1.0 - 1e-9))]
    counts = inside.groupby(["element", "kind"]).size()
    return tuple((str(element), str(kind), int(n)) for (element, kind), n in counts.items())


def cycle_text(cycle: tuple[tuple[str, str, int], ...]) -> str:
    """An orbit's cycle of switches as text (the ``signature`` column): each element's switches by
    kind and count, ``wall closes x1, wall opens x1``; ``no switches`` for none."""
    return ", ".join(f"{element} {kind} x{n}" for element, kind, n in cycle) or "no switches"


def _why(last: float, changed: _Changed | None) -> str:
    """Why the branch ended at its last point ``last``, the steps shortened to the smallest."""
    if changed is None:
        return f"the corrector failed at the smallest step near {last:.8g}"
    low, high = sorted((last, changed.lam))
    return (
        f"the coordinates that move at the section change between {low:.8g} and {high:.8g} (a mass or slider "
        "starts or stops sticking there: the orbit goes on as another kind)"
    )


def _table(points: list[_Point], param: str, names: list[str], measures: bool) -> pd.DataFrame:
    rows = []
    for p in points:
        moduli = np.abs(p.orbit.multipliers)
        row = {
            param: p.lam,
            "stable": bool(np.all(moduli < 1.0)),
            "largest": float(moduli.max(initial=0.0)),
            "signature": cycle_text(_cycle(p.orbit)),
        }
        found = orbit_measures(p.orbit) if measures else {}
        rows.append(row | found | dict(zip(names, p.y.tolist(), strict=True)))
    return pd.DataFrame(rows)


def _changes(points: list[_Point], param: str) -> pd.DataFrame:
    """Folds (the tangent's ``lam`` component changes sign: the parabola's vertex through the three
    points about it) and changes of stability (the multiplier that crossed the unit circle)."""
    rows: list[dict[str, object]] = []
    for k in range(1, len(points)):
        a, b = points[k - 1], points[k]
        if a.tangent[-1] * b.tangent[-1] < 0 and 0 < k < len(points) - 1:
            lam = _vertex([points[j].lam for j in (k - 1, k, k + 1)])
            rows.append({"kind": Bifurcation.FOLD, param: lam, "point": k - 1})
        stable_a, stable_b = (bool(np.all(np.abs(p.orbit.multipliers) < 1.0)) for p in (a, b))
        if stable_a != stable_b:
            kind = Bifurcation.of_multiplier(complex((b if not stable_b else a).orbit.multipliers[0]))
            if kind is not Bifurcation.FOLD:  # a fold is found by the branch's turn
                rows.append({"kind": kind, param: 0.5 * (a.lam + b.lam), "point": k - 1})
    return pd.DataFrame(rows, columns=["kind", param, "point"])


def _vertex(values: list[float]) -> float:
    """The extreme of the parabola through three equally weighted values at arclengths -1, 0, 1."""
    left, middle, right = values
    curvature = left - 2 * middle + right
    if curvature == 0:
        return middle
    return middle - (right - left) ** 2 / (8 * curvature)


def locate_change(branch: ChainBranch, k: int, kind: Bifurcation, tol: float = 1e-9) -> tuple[float, np.ndarray]:
    """Where ``kind`` happens between the branch's points ``k`` and ``k + 1``, to ``tol`` in the
    number: the number's value there and the orbit's state at the point of the side of ``k``.

    Each trial point is the branch's corrector from point ``k`` at an arclength ``s`` along its
    tangent (exact Newton, :data:`TOL`).  A fold is where the tangent's number component vanishes,
    a change of stability where the largest multiplier's modulus crosses 1 (both smooth in ``s``:
    Brent's method); a grazing is where the cycle of switches changes (not smooth: bisection).
    A corrector that fails between the two raises :class:`~oscillator.errors.SimulationFailed`.
    """
    chain, param, names = branch.chain, branch.param, list(branch.chain.system.state)
    rows = branch.points.iloc[[k, k + 1]]
    (ya, yb), (lam_a, lam_b) = rows[names].to_numpy(float), rows[param].to_numpy(float)
    at_a = chain.with_values({param: float(lam_a)})
    held, _ = held_coordinates(at_a, chain_period_map(at_a, at_a.t0, ya))
    follower = _Follower(chain, param, (0.0, branch.width), sorted(set(range(len(names))) - held))
    _, jacobian, orbit = follower.system(ya, float(lam_a))
    free = follower.free
    chord = np.append(yb[free] - ya[free], (lam_b - lam_a) / branch.width)
    start = _Point(ya, float(lam_a), follower.tangent(jacobian, chord), orbit, 0)
    reach = float(start.tangent @ chord)

    def at(s: float) -> _Point:
        found = start if s == 0 else follower.correct(start, s)
        if found is None:
            message = f"the corrector failed at {param} near {start.lam:.10g} locating a {kind}"
            raise SimulationFailed(message, reason=Reason.NO_CONVERGENCE)
        return found

    if kind is Bifurcation.GRAZING:
        low, high, cycle = 0.0, reach, _cycle(orbit)
        while (high - low) * branch.width > tol:
            middle = 0.5 * (low + high)
            low, high = (middle, high) if _cycle(at(middle).orbit) == cycle else (low, middle)
        found = at(low)
        return found.lam, found.y
    if kind is Bifurcation.FOLD:
        sign = np.sign(start.tangent[-1])

        def measure(s: float) -> float:
            return float(sign * at(s).tangent[-1])
    else:

        def measure(s: float) -> float:
            return float(np.abs(at(s).orbit.multipliers).max(initial=0.0)) - 1.0

    try:  # the number moves at most ``width`` per unit of arclength
        s = brentq(measure, 0.0, reach, xtol=tol / branch.width, rtol=4 * np.finfo(float).eps)
    except ValueError:  # no change of sign between the two points
        message = f"no {kind} between {param} = {lam_a:.10g} and {lam_b:.10g}"
        raise SimulationFailed(message, reason=Reason.NO_CONVERGENCE) from None
    found = at(float(s))
    return found.lam, found.y
