"""Bifurcation curves in a plane of two parameters: where a bifurcation located by
:func:`~oscillator.orbits.continuation.continue_orbit` happens as both parameters change.

A bifurcation of a period-N orbit is where an orbit *of one kind* ends: the kind on the side the
branch came from (its cycle of switches).  The curve is the border of the region where that kind
exists, and is traced by a predictor-corrector in the plane, scaled by the window (each parameter
divided by its range):

* the predictor steps along the curve's secant (its first step along the first parameter, both
  ways from the start);
* the corrector is a 1-D location along the normal: on the line through the predicted point
  along the parameter nearest the normal, ``continue_orbit`` runs from a point ``depth`` inside
  (where the kind surely exists, and the other kind of a hysteresis window does not) outward
  past the predicted point, and locates where the kind ends, to ``tol`` (1e-8 by default) by its
  own bisection.

Newton's method started at the border itself can land on the orbit of the other kind (the two
differ by 1e-3 at a sliding bifurcation with hysteresis), and a nonsmooth border has no
derivative for an augmented Newton system; the continuation from inside follows its own branch
and meets the border from the side it belongs to.  A step whose corrector finds no border is
halved; below ``min_step`` the curve ends there: where the bifurcation stops existing (a
codimension-two point) or meets another (a merge).  A turn of the curve back in one parameter (a
fold of the curve) is passed, and recorded.

A declared system's curve (:class:`~oscillator.model.chains.FrictionChain`, issue 52) is traced
the same way, its numbers named as the system names them (``Omega``, ``wall.at``): each line's
continuation is :func:`~oscillator.orbits.chain_branch.continue_chain_orbit`, and the border is
located between two of its points by :func:`~oscillator.orbits.chain_branch.locate_change` (a
fold, a change of stability, or a grazing: where the orbit's cycle of switches changes).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Interrupted, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import Parameters, check_count
from oscillator.orbits.branch import Bifurcation, Branch
from oscillator.orbits.chain_branch import ChainBranch, continue_chain_orbit, locate_change
from oscillator.orbits.chain_tangents import check_names
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.shooting import tightened
from oscillator.presenting import Presented, presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["CHAIN_CURVE_KINDS", "CURVE_KINDS", "DEFAULT_STEP", "Curve", "check_curve", "trace_curve"]

#: The predictor's step, as a fraction of the window (``oscillator curve --step`` has the same default).
DEFAULT_STEP = 0.05
#: The kinds a curve can be traced for (``continue_orbit``'s, ``sliding`` for either sliding kind).
CURVE_KINDS = ("sliding", *(kind.value for kind in Bifurcation if kind is not Bifurcation.TORUS))
#: The kinds a declared system's curve can be traced for.
CHAIN_CURVE_KINDS = tuple(kind.value for kind in Bifurcation if not kind.nonsmooth or kind is Bifurcation.GRAZING)


@dataclass(frozen=True)
class _Kind:
    """What is inside: an orbit with this cycle of switches (its text, as branches write it)."""

    signature: str


@dataclass(frozen=True)
class Curve(Presented):
    """A bifurcation curve in the plane of ``x`` and ``y``.

    Attributes
    ----------
    kind : str
    x, y : str
        The two parameters.
    points : DataFrame
        The curve in order, from one end to the other: ``x``'s and ``y``'s values (columns named
        after them).
    ends : tuple of str
        How each end ended (the first for the start of ``points``, the second for its end).
    folds : tuple of tuple of float
        Where the curve turned back in one of the parameters (``(x, y)``).
    inside : str
        The inside orbit's cycle of switches.
    inside_point : tuple of float, optional
        A point on the inside of the curve (where that orbit exists), near its start.
    labels : tuple of str, optional
        The axes' labels with their units (a declared system's numbers; the article's parameters
        are labelled by their names).
    """

    kind: str
    x: str
    y: str
    points: pd.DataFrame = field(repr=False)
    ends: tuple[str, str]
    folds: tuple[tuple[float, float], ...]
    inside: str
    inside_point: tuple[float, float] | None = None
    labels: tuple[str, str] | None = None

    def plot(self, atlas: Any = None) -> Figure:
        """The curve in its plane, over ``atlas``'s regimes (an :class:`~oscillator.attractors.atlas.Atlas`)
        if given (as ``oscillator curve`` draws it)."""
        return presenter().plot_global(self, atlas=atlas)


@dataclass(frozen=True)
class _Change:
    """A bifurcation on a line's branch: its kind, the number's value there (approximate until
    :meth:`_Lines.exact`), the cycle of switches before it and where it lies on the branch."""

    kind: str
    value: float
    before: str
    index: int = 0


@dataclass(frozen=True)
class _Line:
    """A line's continuation: the cycle of switches and the orbit where it started, its changes in
    order along it, and the branch (to locate a change exactly)."""

    start: str
    state: np.ndarray
    changes: tuple[_Change, ...]
    branch: Any = field(repr=False, default=None)


class _CaseLines:
    """Lines of the article's case: ``continue_orbit``, its bifurcations located to ``tol``."""

    def __init__(self, case: Case, period: int, tol: float) -> None:
        self.case, self.period, self.tol = case, period, tol

    def first(self, fixed: dict[str, float], param: str, start: float, stop: float) -> _Line:
        """The line the curve starts from: the orbit found from the case's start."""
        line = resolve_case(self.case, **fixed)
        return self._line(continue_orbit(line, param=param, start=start, stop=stop, period=self.period, step=0.1))

    def across(self, fixed: dict[str, float], param: str, start: float, stop: float, guess: np.ndarray) -> _Line:
        """A line across the curve, from ``start`` inside, its orbit found from ``guess``."""
        line = resolve_case(self.case, **fixed)
        branch = continue_orbit(
            line,
            param=param,
            start=start,
            stop=stop,
            period=self.period,
            guess=guess,
            transient=0,
            step=0.1,
            locate_tol=self.tol,
            max_points=200,
        )
        return self._line(branch)

    @staticmethod
    def _line(branch: Branch) -> _Line:
        rows = branch.bifurcations
        changes = tuple(_Change(str(r.kind), float(r[branch.param]), str(r.before)) for _, r in rows.iterrows())
        first = branch.points.iloc[0] if len(branch.points) else None
        state = np.array([] if first is None else [first.x1, first.v1, first.x2, first.v2], dtype=float)
        return _Line(_signature_at_start(branch), state, changes)

    @staticmethod
    def exact(line: _Line, change: _Change) -> float:
        return change.value  # located by the continuation


class _ChainLines:
    """Lines of a declared system: :func:`continue_chain_orbit`, a change located between two of
    its points by :func:`locate_change`."""

    def __init__(self, chain: FrictionChain, tol: float) -> None:
        self.chain, self.tol = chain, tol

    def first(self, fixed: dict[str, float], param: str, start: float, stop: float) -> _Line:
        line = self.chain.with_values(fixed)
        return self._line(continue_chain_orbit(line, param=param, start=start, stop=stop, step=0.2, measures=False))

    def across(self, fixed: dict[str, float], param: str, start: float, stop: float, guess: np.ndarray) -> _Line:
        line = self.chain.with_values(fixed)
        branch = continue_chain_orbit(
            line,
            param=param,
            start=start,
            stop=stop,
            guess=guess,
            transient=0,
            step=0.2,
            max_points=200,
            measures=False,
        )
        return self._line(branch)

    @staticmethod
    def _line(branch: ChainBranch) -> _Line:
        """Its folds and changes of stability, and its grazings (the cycle of switches changes
        between two points), in order along it."""
        points, param = branch.points, branch.param
        signatures = points.signature.astype(str).tolist()
        changes = [
            _Change(str(r.kind), float(r[param]), signatures[int(r.point)], int(r.point))
            for _, r in branch.bifurcations.iterrows()
        ]
        for k in range(len(signatures) - 1):
            if signatures[k] != signatures[k + 1]:
                value = 0.5 * float(points[param].iloc[k] + points[param].iloc[k + 1])
                changes.append(_Change(Bifurcation.GRAZING.value, value, signatures[k], k))
        state = points[list(branch.chain.system.state)].iloc[0].to_numpy(float)
        return _Line(signatures[0], state, tuple(sorted(changes, key=lambda c: c.index)), branch)

    def exact(self, line: _Line, change: _Change) -> float:
        value, _ = locate_change(line.branch, change.index, Bifurcation(change.kind), self.tol)
        return value


_Lines = _CaseLines | _ChainLines


class _Tracer:
    """The curve's plane, the inside kind and the corrector."""

    def __init__(
        self,
        lines: _Lines,
        x: str,
        y: str,
        window: tuple[tuple[float, float], tuple[float, float]],
        kind: _Kind,
        side: float,
    ) -> None:
        self.lines, self.x, self.y, self.window, self.kind, self.side = lines, x, y, window, kind, side
        self.spans = np.array([window[0][1] - window[0][0], window[1][1] - window[1][0]])

    def flipped(self) -> _Tracer:
        """The same, walking the other way (the inside on the other side of the tangent)."""
        return _Tracer(self.lines, self.x, self.y, self.window, self.kind, -self.side)

    def inward(self, tangent: np.ndarray) -> np.ndarray:
        """The unit normal (scaled) pointing into the region of the kind: the same side of the
        tangent all along the curve."""
        normal: np.ndarray = self.side * np.array([-tangent[1], tangent[0]])
        return normal

    def in_window(self, point: np.ndarray) -> bool:
        (xlo, xhi), (ylo, yhi) = self.window
        return bool(xlo <= point[0] <= xhi and ylo <= point[1] <= yhi)

    def locate(
        self, predicted: np.ndarray, inward: np.ndarray, depth: float, guess: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The border on the line through ``predicted`` along the parameter nearest ``inward``:
        a continuation from ``depth`` (scaled) inside to ``depth`` outside; the border's point
        and the orbit where the continuation started (inside: the next step's guess), or None."""
        axis = 1 if abs(inward[1]) >= abs(inward[0]) else 0
        names = (self.x, self.y)
        sign = math.copysign(1.0, inward[axis])
        inside_at = predicted[axis] + sign * depth * self.spans[axis]
        outside_at = predicted[axis] - sign * depth * self.spans[axis]
        fixed = {names[1 - axis]: float(predicted[1 - axis])}
        try:
            line = self.lines.across(fixed, names[axis], float(inside_at), float(outside_at), guess)
            if line.start != self.kind.signature:
                return None  # the start is not of the kind: the step went too far
            change = next((c for c in line.changes if c.before == self.kind.signature), None)
            if change is None:
                return None
            point = predicted.copy()
            point[axis] = self.lines.exact(line, change)
        except OscillatorError:
            return None
        return point, line.state


def _signature_at_start(branch: Branch) -> str:
    return str(branch.points.signature.iloc[0]) if len(branch.points) else ""


def _start(
    lines: _Lines, kind: str, x: str, y: str, at: tuple[float, float], period: int, span: float
) -> tuple[_Kind, float, float, np.ndarray]:
    """The bifurcation of ``kind`` nearest ``at`` on the line of ``y`` at ``x = at[0]``, located by
    a continuation over ``y`` within ``span`` of it, from both sides: the inside kind (the side
    the branch came from), its ``y``, which way is inside in ``y`` (+1 or -1) and the orbit
    where that branch started (inside)."""
    best: tuple[float, float, _Line, _Change] | None = None
    for start, stop in ((at[1] + span, at[1] - span), (at[1] - span, at[1] + span)):
        try:
            line = lines.first({x: at[0]}, y, start, stop)
        except OscillatorError:
            continue
        for change in line.changes:
            wanted = change.kind.startswith(kind) if kind == "sliding" else change.kind == kind
            distance = abs(change.value - at[1])
            if wanted and change.before == line.start and (best is None or distance < best[0]):
                best = (distance, math.copysign(1.0, start - at[1]), line, change)
    where = None
    if best is not None:
        try:
            where = lines.exact(best[2], best[3])
        except OscillatorError:
            where = None
    if best is None or where is None:
        raise InputError(
            f"no {kind} bifurcation of the period-{period} orbit within {span:g} of {y} = {at[1]:.10g} at {x} = "
            f"{at[0]:.10g}; give --at nearer to one (oscillator continue locates them)",
            field="at",
        )
    _, inside, line, change = best
    return _Kind(change.before), where, inside, line.state


def trace_curve(
    case: Case | FrictionChain | str,
    *,
    kind: str,
    x: str,
    y: str,
    at: tuple[float, float],
    window: tuple[tuple[float, float], tuple[float, float]],
    period: int = 1,
    step: float = DEFAULT_STEP,
    min_step: float = 1e-4,
    tol: float = 1e-8,
    max_points: int = 400,
    progress: Callable[[int], None] | None = None,
    **overrides: float,
) -> Curve:
    """The curve in the plane of ``x`` and ``y`` on which the ``kind`` bifurcation near ``at``
    happens, traced both ways until it leaves ``window`` or ends.

    Parameters
    ----------
    case : Case, str or FrictionChain
        The article's case, or a declared system (its period-1 orbits).
    kind : str
        One of :data:`CURVE_KINDS` (``sliding``: either sliding kind); a declared system's, one
        of :data:`CHAIN_CURVE_KINDS`.
    x, y : str
        The two parameters (a declared system's numbers by its names: ``Omega``, ``wall.at``).
    at : (float, float)
        A point near the curve: ``(x, y)``, e.g. a bifurcation ``continue_orbit`` located in ``y``.
    window : ((float, float), (float, float))
        The plane's window: ``x``'s and ``y``'s ranges.
    period : int
    step, min_step : float
        The predictor's step, and the smallest before the curve is said to end, as fractions of
        the window (scaled).
    tol : float
        Each point is located to this in both parameters.
    max_points : int
    progress : callable, optional
        ``progress(points)`` after each point.

    Raises
    ------
    Interrupted
        On Ctrl-C, with the curve traced so far as its ``result`` (an unfinished end says
        ``"interrupted"``).
    **overrides
        Parameters and solver options (the article's case only).
    """
    subject = check_curve(case, kind=kind, x=x, y=y, at=at, window=window, period=period, step=step, **overrides)
    check_count(max_points, "max_points", 1, 100_000)
    if not (0 < min_step <= step) or not tol > 0:
        raise InputError("min_step must be in (0, step] and tol > 0", field="min_step")
    declared = isinstance(subject, FrictionChain)
    lines: _Lines = _ChainLines(subject, tol) if declared else _CaseLines(subject, period, tol)  # type: ignore[arg-type]
    span = 0.1 * (window[1][1] - window[1][0])
    try:
        inside_kind, y0, inside, orbit = _start(lines, kind, x, y, at, period, span)
        # the first tangent is +x; inside is +y or -y of it: that side stays the inside all along
        tracer = _Tracer(lines, x, y, window, inside_kind, side=inside)
        first = np.array([at[0], y0])
        tangent = _first_tangent(tracer, first, orbit)
    except KeyboardInterrupt:  # before the curve's first point: nothing to carry (not a branch's Interrupted)
        raise KeyboardInterrupt from None
    back: list[np.ndarray] = []
    ahead: list[np.ndarray] = []
    folds: list[tuple[float, float]] = []
    ends = ["interrupted", "interrupted"]

    def curve() -> Curve:
        ordered = [*back[::-1], first, *ahead]
        table = pd.DataFrame([(p[0], p[1]) for p in ordered], columns=[x, y])
        inside_point = first + 1e-3 * tracer.inward(tangent) * tracer.spans  # just inside, at the start
        side = (float(inside_point[0]), float(inside_point[1]))
        labels = _labels(subject, x, y)
        return Curve(kind, x, y, table, (ends[0], ends[1]), tuple(folds), inside_kind.signature, side, labels)

    try:
        for k, (direction, points) in enumerate(((-1.0, back), (1.0, ahead))):
            ends[k] = _walk(
                tracer, first, orbit, direction * tangent, step, min_step, max_points, points, folds, progress
            )
    except KeyboardInterrupt:
        raise Interrupted(curve()) from None
    return curve()


def _labels(subject: Case | FrictionChain, x: str, y: str) -> tuple[str, str] | None:
    """A declared system's axes' labels with their units (the article's: None, labelled by name)."""
    if not isinstance(subject, FrictionChain):
        return None
    units = (FrictionChain.unit(name) for name in (x, y))
    a, b = (f"{name} ({unit})" if unit else name for name, unit in zip((x, y), units, strict=True))
    return a, b


def _first_tangent(tracer: _Tracer, first: np.ndarray, orbit: np.ndarray) -> np.ndarray:
    """The curve's direction at its start (scaled, with a positive first component): the chord to
    the border located a little further along the first parameter; along that parameter if none
    is found there (the curve is then steep, and the walk's halving finds its way)."""
    found = tracer.locate(first + np.array([1e-3, 0.0]) * tracer.spans, np.array([0.0, tracer.side]), 0.02, orbit)
    if found is None:
        return np.array([1.0, 0.0])
    chord: np.ndarray = (found[0] - first) / tracer.spans
    unit: np.ndarray = chord / np.linalg.norm(chord)
    return unit


def _walk(
    tracer: _Tracer,
    first: np.ndarray,
    orbit: np.ndarray,
    tangent: np.ndarray,
    step: float,
    min_step: float,
    max_points: int,
    points: list[np.ndarray],
    folds: list[tuple[float, float]],
    progress: Callable[[int], None] | None,
) -> str:
    """The curve from ``first`` along ``tangent`` (scaled), until it leaves the window or ends:
    its points and folds appended to ``points`` and ``folds`` as they are found (so that an
    interrupt keeps them), and how it ended."""
    here, h = first, step
    if tangent[0] < 0:  # walking the other way: the inside is on the other side of the tangent
        tracer = tracer.flipped()
    while len(points) < max_points:
        predicted = here + h * tangent * tracer.spans
        found = tracer.locate(predicted, tracer.inward(tangent), max(2 * h, 0.02), orbit)
        if found is None:
            h *= 0.5
            if h < min_step:
                end = (
                    f"ended at {tracer.x} = {here[0]:.10g}, {tracer.y} = {here[1]:.10g}: the border of its kind "
                    f"was not found beyond, within {min_step:g} of the window (a codimension-two point, or a merge)"
                )
                return end
            continue
        point, orbit = found
        if not tracer.in_window(point):
            return f"left the window at {tracer.x} = {point[0]:.10g}, {tracer.y} = {point[1]:.10g}"
        chord = (point - here) / tracer.spans
        new_tangent = chord / np.linalg.norm(chord)
        if any(tangent[k] * new_tangent[k] < 0 and abs(tangent[k]) > 1e-3 for k in (0, 1)):
            folds.append((float(here[0]), float(here[1])))
        points.append(point)
        here, tangent = point, new_tangent
        h = min(step, 2.0 * h)
        if progress is not None:
            progress(len(points))
    return f"stopped after {max_points} points"


def check_curve(
    case: Case | FrictionChain | str,
    *,
    kind: str,
    x: str,
    y: str,
    at: tuple[float, float],
    window: tuple[tuple[float, float], tuple[float, float]],
    period: int = 1,
    step: float = DEFAULT_STEP,
    **overrides: float,
) -> Case | FrictionChain:
    """:func:`trace_curve`'s arguments checked before any work, each refusal an
    :class:`~oscillator.errors.InputError` naming its argument; the case (or system) to trace in."""
    kinds = CHAIN_CURVE_KINDS if isinstance(case, FrictionChain) else CURVE_KINDS
    if kind not in kinds:
        raise InputError(f"kind must be one of {', '.join(kinds)}, got {shown(kind)}", field="kind")
    if isinstance(case, FrictionChain):
        check_names(case, [x, y])
    else:
        for name, value in (("x", x), ("y", y)):
            Parameters.check_name(value, name)
    if x == y:
        raise InputError(f"x and y are both {x}; give two different parameters", field="y")
    (xlo, xhi), (ylo, yhi) = window
    for name, param, (low, high) in (("x", x, (xlo, xhi)), ("y", y, (ylo, yhi))):
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise InputError(
                f"{name} range of {param} must be two finite numbers low < high, got {low!r} {high!r}", field=name
            )
    if not (xlo <= at[0] <= xhi and ylo <= at[1] <= yhi):
        raise InputError(
            f"at {x} = {at[0]!r}, {y} = {at[1]!r} is outside the window ({x} {xlo:g} to {xhi:g}, {y} {ylo:g} to "
            f"{yhi:g}); give a point inside it",
            field="at",
        )
    if not (isinstance(step, (int, float)) and 0 < step <= 0.5):
        raise InputError(f"step must be a fraction of the window in (0, 0.5], got {shown(step)}", field="step")
    check_count(period, "period", 1, 1000)
    if isinstance(case, FrictionChain):
        return _checked_chain(case, x, y, window, period, overrides)
    resolved = resolve_case(case, **overrides)
    for point in ((xlo, ylo), (xhi, yhi)):
        resolve_case(resolved, **{x: point[0], y: point[1]})
    return tightened(resolved, overrides)


def _checked_chain(
    chain: FrictionChain,
    x: str,
    y: str,
    window: tuple[tuple[float, float], tuple[float, float]],
    period: int,
    overrides: dict[str, float],
) -> FrictionChain:
    """A declared system's curve: period 1, no overrides (its numbers are changed by
    ``with_values``), the window's corners valid values."""
    if period != 1:
        raise InputError(f"a declared system's curves follow its period-1 orbits, got period {period}", field="period")
    if overrides:
        raise InputError(
            f"{', '.join(map(shown, overrides))}: a declared system's numbers are set with chain.with_values (or "
            "--set), not as keywords",
            field=next(iter(overrides)),
        )
    for point in ((window[0][0], window[1][0]), (window[0][1], window[1][1])):
        chain.with_values({x: point[0], y: point[1]})
    return chain
