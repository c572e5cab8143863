"""Exact parameter sensitivities of a periodic orbit, through every switch (docs/sensitivities.md).

The stroboscopic map ``P(y, c)`` is one run over ``n`` forcing periods.  Its derivative in the
parameters ``c`` at fixed ``y`` is carried along the run's smooth pieces by the tangent equations
(:mod:`oscillator.orbits.tangent`), ``sigma' = J sigma + df/dc``, from ``sigma = 0``, and through
each switch by the saltation rule with one more column: the switch time ``t_s`` is set by a
boundary ``h(t, y, c) = 0`` and moves with the parameters,

    tau = dt_s/dc = -(n . sigma- + dh/dc) / (n . f- + h_t),      sigma+ = sigma- + (f- - f+) tau,

then the velocity of a mass that comes to rest is pinned (:func:`~oscillator.model.saltation.
rest_projection`).  ``dh/dc`` is ``e_d`` on the left stop (``h = x1 - x2 + d``), ``-e_d1`` on the
right stop (``h = x1 - d1``), zero on ``v_i = 0`` and ``dA_i/dc - s d(mu_s g + p_i)/dc`` on a flow
barrier.  At the end, ``t1 = t0 + n 2 pi / Omega`` moves with ``Omega``:
``dP/dc = sigma(t1) + f(t1) dt1/dc``.

A periodic orbit ``y* = P(y*, c)`` moves by ``dy*/dc = (I - M)^-1 dP/dc`` (``M = dP/dy``, the
monodromy), with the displacement of a mass at rest all period kept where it stuck (its row of
``I - M`` is zero: a continuum of orbits).  A second pass from ``sigma = dy*/dc`` gives the
derivative of everything along the orbit: its section points, its switch times and its response
measures (:mod:`oscillator.orbits.response_derivatives`), and a second-order pass the derivatives of the
multipliers (:mod:`oscillator.orbits.monodromy_derivative`).

Where the orbit grazes a boundary (``n . f- + h_t = 0``), meets rest with its force on the static
threshold, or passes a boundary without crossing it, the map is not differentiable; the distances
to each such point are measured (:attr:`Sensitivities.margins`) and the derivative is refused
below :data:`MARGIN`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.record import Segment
from oscillator.model.fields import coefficients, state_derivative
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.saltation import Boundary, boundary_of, elementary_switches, rest_projection
from oscillator.model.system import ARTICLE
from oscillator.orbits.pieces import ARTICLE_MAP, ARTICLE_PIECE, article_data, integrate_piece, mode_flags
from oscillator.orbits.tangent import INTEGRALS, force_gradient, threshold_gradient
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.shooting import Orbit

__all__ = [
    "MARGIN",
    "Crossing",
    "Pass",
    "Piece",
    "Sensitivities",
    "Switch",
    "check_params",
    "columns_of",
    "crossings",
    "map_gradient",
    "selector_of",
    "sensitivities",
    "tangent_pass",
]

#: The smallest relative distance to a point where the map is not differentiable (a grazing, a
#: rest on its threshold) at which derivatives are still given.
MARGIN = 1e-6
#: The re-integration's tolerances (as the response measures').
_TOLERANCE = 1e-12
_STATE = ARTICLE.state
_POSITION = {name: k for k, name in enumerate(Parameters.names())}


def check_params(params: object) -> tuple[str, ...]:
    """``params`` as a tuple of parameter names (one name or a sequence), each checked."""
    names = (params,) if isinstance(params, str) else tuple(params) if isinstance(params, Sequence) else None
    if not names:
        raise InputError(
            f"params must name one or more parameters ({', '.join(Parameters.names())}), got {params!r}",
            field="params",
        )
    return tuple(dict.fromkeys(Parameters.check_name(name, "params") for name in names))  # each once


@dataclass(frozen=True)
class Switch:
    """One switch of the pass: its time, the modes either side, ``tau = dt_s/dc`` (k), the state
    and ``sigma`` either side, and the boundary that set its time: its normal ``n``, and the speed
    ``n . f- + h_t`` at which the flow crossed it (zero at a grazing)."""

    t: float
    before: Mode
    after: Mode
    tau: np.ndarray
    y: np.ndarray
    sigma_before: np.ndarray
    sigma_after: np.ndarray
    normal: np.ndarray
    speed: float


@dataclass(frozen=True)
class Piece:
    """One smooth piece of the pass: its mode, ends, ``sigma`` at each end (after the switch that
    began it, before the one that ends it), the end times' derivatives ``tau``, the response
    integrals and their derivatives, and its interior extrema ``(which, t, y, sigma)``."""

    mode: Mode
    t0: float
    t1: float
    y0: np.ndarray
    y1: np.ndarray
    sigma0: np.ndarray
    sigma1: np.ndarray
    tau0: np.ndarray
    tau1: np.ndarray
    integrals: np.ndarray
    derivatives: np.ndarray
    extrema: list[tuple[str, float, np.ndarray, np.ndarray]]
    samples: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Pass:
    """A tangent pass over a run's segments: the pieces and switches in order, ``sigma`` at the
    end and ``dt1/dc``, and at each of ``marks`` the state and its total derivative."""

    pieces: list[Piece]
    switches: list[Switch]
    end: np.ndarray
    marks: list[np.ndarray]


def columns_of(params: tuple[str, ...]) -> np.ndarray:
    """The parameters' positions in the parameter vector, for the compiled kernels."""
    return np.array([_POSITION[name] for name in params], dtype=np.int64)


def selector_of(params: tuple[str, ...]) -> np.ndarray:
    """``dc/dparams`` (25 x k): column ``j`` is the unit vector of parameter ``j``."""
    selector = np.zeros((len(Parameters.names()), len(params)))
    for j, name in enumerate(params):
        selector[_POSITION[name], j] = 1.0
    return selector


def _pack(y: np.ndarray, sigma: np.ndarray, k: int) -> np.ndarray:
    return np.concatenate([y, np.zeros(INTEGRALS), sigma.ravel(), np.zeros(INTEGRALS * k)])


def _boundary_gradient(name: str, t: float, y: np.ndarray, c: np.ndarray, mode: Mode, after: Mode) -> np.ndarray:
    """``dh/dc`` (25) of the boundary ``name`` (:func:`~oscillator.model.saltation.elementary_switches`)."""
    gradient = np.zeros(len(c))
    if name == "left":
        gradient[_POSITION["d"]] = 1.0
    elif name == "right":
        gradient[_POSITION["d1"]] = -1.0
    elif name.startswith("barrier"):
        mass = int(name[-1])
        forces = np.empty((2, len(c)))
        x1, v1, x2, v2 = (float(v) for v in y)
        force_gradient(t, x1, v1, x2, v2, mode.left, mode.right, c, forces)
        static = np.empty(len(c))
        threshold_gradient(c, mass, True, static)
        gradient = forces[mass - 1] - after.sign(mass) * static
    return gradient


@dataclass(frozen=True)
class Crossing:
    """One boundary crossed at a switch (:func:`~oscillator.model.saltation.elementary_switches`):
    the modes either side, the boundary, the fields either side, the speed ``n . f- + h_t``,
    ``tau`` (k) and ``sigma`` (4 x k) just before it."""

    before: Mode
    after: Mode
    name: str
    boundary: Boundary
    f_minus: np.ndarray
    f_plus: np.ndarray
    speed: float
    tau: np.ndarray
    sigma: np.ndarray

    @property
    def sigma_after(self) -> np.ndarray:
        """``sigma`` just after the crossing, ``sigma + (f- - f+) tau``."""
        moved: np.ndarray = self.sigma + np.outer(self.f_minus - self.f_plus, self.tau)
        return moved


def crossings(
    t: float,
    y_before: np.ndarray,
    y_after: np.ndarray,
    sigma: np.ndarray,
    p: Parameters,
    before: Mode,
    after: Mode,
    selector: np.ndarray,
) -> list[Crossing]:
    """The boundaries the switch ``before -> after`` at ``t`` crosses, each with ``tau`` and the
    ``sigma`` it meets (module docstring), one after the other.

    Raises the refusal (:class:`~oscillator.errors.SimulationFailed`) at a grazing."""
    c = coefficients(p)
    found = []
    carried = sigma.copy()
    for mode, new, name in elementary_switches(before, after):
        boundary = boundary_of(name, t, y_before, p, mode, new)
        f_minus = np.array(state_derivative(t, y_before, p, mode))
        f_plus = np.array(state_derivative(t, y_after, p, new))
        speed = float(boundary.normal @ f_minus + boundary.rate)
        if speed == 0.0:
            raise _not_differentiable(f"the flow is tangent to the {boundary.name} at t = {t:.10g} s (a grazing)", 0.0)
        gradient = _boundary_gradient(name, t, y_before, c, mode, new) @ selector
        tau = -(boundary.normal @ carried + gradient) / speed
        found.append(Crossing(mode, new, name, boundary, f_minus, f_plus, speed, tau, carried))
        carried = found[-1].sigma_after
    return found


def _piece(
    segment: Segment, sigma: np.ndarray, tau0: np.ndarray, c: np.ndarray, columns: np.ndarray, marks: Sequence[float]
) -> tuple[Piece, dict[float, np.ndarray]]:
    """One segment integrated again with the tangent system from ``sigma`` at its start."""
    k = len(columns)
    mode = segment.mode
    data = article_data(mode_flags(mode), columns, c)
    start = _pack(segment.y0, sigma, k)
    span = (segment.t0, segment.t1)
    solved = integrate_piece(ARTICLE_PIECE, data, span, start, rtol=_TOLERANCE, atol=_TOLERANCE, dense=True)
    end = solved.end
    body = 4 + INTEGRALS
    extrema = [
        (("v1", "v2", "left")[which], float(t), y[:4].copy(), y[body : body + 4 * k].reshape(4, k))
        for which, t, y in zip(solved.which, solved.times, solved.states, strict=True)
    ]
    moving = segment.t1 > segment.t0
    inside = {t: solved(t) for t in marks if segment.t0 <= t < segment.t1} if moving else {}
    grid = np.linspace(segment.t0, segment.t1, 33)
    samples = solved(grid)[:4].T if moving else segment.y0[None, :]
    piece = Piece(
        mode,
        segment.t0,
        segment.t1,
        segment.y0.copy(),
        end[:4].copy(),
        sigma.copy(),
        end[body : body + 4 * k].reshape(4, k).copy(),
        tau0,
        np.zeros(k),
        end[4:body].copy(),
        end[body + 4 * k :].reshape(INTEGRALS, k).copy(),
        extrema,
        samples,
    )
    return piece, {t: np.concatenate([v[:4], v[body : body + 4 * k]]) for t, v in inside.items()}


def tangent_pass(
    segments: Sequence[Segment],
    p: Parameters,
    params: tuple[str, ...],
    sigma0: np.ndarray,
    t_end: float,
    dt_end: np.ndarray,
    marks: Sequence[float] = (),
) -> Pass:
    """The tangent system along ``segments`` (a run from ``segments[0].t0`` to ``t_end``, whose end
    time moves by ``dt_end``), from ``sigma0`` (4 x k) at the start; see the module docstring."""
    selector = selector_of(params)
    c = coefficients(p)
    columns = columns_of(params)
    k = len(params)
    sigma = rest_projection(segments[0].mode) @ np.asarray(sigma0, dtype=float).reshape(4, k)
    tau = np.zeros(k)
    pieces: list[Piece] = []
    switches: list[Switch] = []
    found: dict[float, np.ndarray] = {}
    for index, segment in enumerate(segments):
        piece, inside = _piece(segment, sigma, tau, c, columns, marks)
        found |= inside
        if index + 1 < len(segments):
            following = segments[index + 1]
            t = following.t0
            crossed = crossings(t, piece.y1, following.y0, piece.sigma1, p, segment.mode, following.mode, selector)
            first, after = crossed[0], following.mode
            carried = rest_projection(after) @ crossed[-1].sigma_after
            switch = Switch(
                t,
                segment.mode,
                after,
                first.tau,
                piece.y1.copy(),
                piece.sigma1.copy(),
                carried,
                first.boundary.normal,
                first.speed,
            )
            switches.append(switch)
            sigma, tau = switch.sigma_after, switch.tau
        else:
            switch = None
        pieces.append(_with_end(piece, tau if switch is not None else dt_end))
    last = pieces[-1]
    f_end = np.array(state_derivative(t_end, last.y1, p, last.mode))
    end = last.sigma1 + np.outer(f_end, dt_end)
    marked = []
    for t in marks:
        v = found.get(t)
        if v is None:
            raise ValueError(f"no piece holds the time {t!r}")
        marked.append(v)
    return Pass(pieces, switches, end, marked)


def map_gradient(
    segments: Sequence[Segment], p: Parameters, params: tuple[str, ...], t_end: float, dt_end: np.ndarray
) -> np.ndarray:
    """``dP/dc`` (4 x k) at fixed start: the end of :func:`tangent_pass` from ``sigma = 0``, with
    nothing else of the pass integrated or kept (the continuation's corrector takes its column in
    the parameter from it).

    Raises the refusal (:class:`~oscillator.errors.SimulationFailed`) at a grazing."""
    selector, c, columns, k = selector_of(params), coefficients(p), columns_of(params), len(params)
    sigma = np.zeros((4, k))
    for index, segment in enumerate(segments):
        data = article_data(mode_flags(segment.mode), columns, c)
        start = np.concatenate([segment.y0, sigma.ravel()])
        span = (segment.t0, segment.t1)
        end = integrate_piece(ARTICLE_MAP, data, span, start, rtol=_TOLERANCE, atol=_TOLERANCE).end
        y1, sigma1 = end[:4], end[4:].reshape(4, k)
        if index + 1 < len(segments):
            following = segments[index + 1]
            crossed = crossings(following.t0, y1, following.y0, sigma1, p, segment.mode, following.mode, selector)
            sigma = rest_projection(following.mode) @ crossed[-1].sigma_after
    f_end = np.array(state_derivative(t_end, y1, p, segments[-1].mode))
    gradient: np.ndarray = sigma1 + np.outer(f_end, dt_end)
    return gradient


def _with_end(piece: Piece, tau1: np.ndarray) -> Piece:
    from dataclasses import replace

    return replace(piece, tau1=np.asarray(tau1, dtype=float))


def _not_differentiable(why: str, distance: float) -> SimulationFailed:
    return SimulationFailed(
        f"the orbit is not differentiable in its parameters here: {why}, at a relative distance {distance:.3g} "
        f"(below {MARGIN:g}); this is a bifurcation point (grazing, sliding or a rest on its threshold), where "
        "the measures have one derivative on each side: move the parameter off it",
        reason=Reason.NOT_DIFFERENTIABLE,
        field="params",
    )


@dataclass(frozen=True)
class Sensitivities:
    """The derivatives of a periodic orbit in its parameters (:func:`sensitivities`).

    Attributes
    ----------
    orbit : Orbit
        The orbit differentiated.
    params : tuple of str
        The parameters, in the columns' order.
    map : DataFrame
        ``dP/dc`` at the orbit's state, at fixed state (rows ``x1, v1, x2, v2``).
    state : DataFrame
        ``dy*/dc``: how the orbit's section point moves (rows ``x1, v1, x2, v2``).
    points : DataFrame
        Each section point of a period-``n`` orbit (``point`` 0 to ``n - 1``, at ``section + k T``)
        and its derivative (one column per parameter, rows ``point, variable``).
    switches : DataFrame
        Every switch over one return: ``t``, the domains of m1 and m2 either side (and the
        contacts), the ``speed`` at which the flow crossed the boundary that set its time
        (``n . f- + h_t``), and ``dt/d<param>`` for each parameter.
    measures : DataFrame
        Every response measure (index: :data:`oscillator.orbits.response.COLUMNS`): ``value`` and
        ``d/d<param>`` for each parameter.
    margins : DataFrame
        The distance from each point where the map is not differentiable (``what``, ``t``,
        ``distance``, relative to the terms it compares), nearest first.
    multipliers : DataFrame
        The Floquet multipliers (largest modulus first, as :attr:`Orbit.multipliers`): ``value``
        (complex), ``modulus``, ``simple`` (False for a multiplier within
        :data:`~oscillator.orbits.monodromy_derivative.SIMPLE` of another: a repeated one, such as
        the zero multipliers of an orbit whose masses rest), ``d/d<param>`` (complex) and
        ``d|mu|/d<param>``; ``nan`` where the multiplier is not simple.  Computed when first asked (a second-order pass,
        :mod:`oscillator.orbits.monodromy_derivative`).
    """

    orbit: Orbit
    params: tuple[str, ...]
    map: pd.DataFrame
    state: pd.DataFrame
    points: pd.DataFrame
    switches: pd.DataFrame
    measures: pd.DataFrame
    margins: pd.DataFrame
    #: What :attr:`multipliers` needs: the run's segments, ``dy*/dc`` and ``dt1/dc``.
    _along: tuple[Sequence[Segment], np.ndarray, np.ndarray] = field(repr=False, compare=False)

    @functools.cached_property
    def multipliers(self) -> pd.DataFrame:
        """The multipliers and their derivatives (class docstring)."""
        from oscillator.orbits.monodromy_derivative import monodromy_derivative, multiplier_derivatives

        segments, dy, dt_end = self._along
        monodromy, derivative = monodromy_derivative(segments, self.orbit.case.parameters, self.params, dy, dt_end)
        values, moved = multiplier_derivatives(monodromy, derivative)
        simple = ~np.isnan(moved).any(axis=1) if len(self.params) else np.ones(len(values), bool)
        table = pd.DataFrame({"value": values, "modulus": np.abs(values), "simple": simple})
        for j, name in enumerate(self.params):
            table[f"d/d{name}"] = moved[:, j]
        for j, name in enumerate(self.params):
            # d|mu| = Re(conj(mu) dmu) / |mu|
            with np.errstate(invalid="ignore", divide="ignore"):
                table[f"d|mu|/d{name}"] = (values.conj() * moved[:, j]).real / np.abs(values)
        return table

    @property
    def margin(self) -> float:
        """The smallest distance in :attr:`margins` (``inf`` without any)."""
        return float(self.margins.distance.min()) if len(self.margins) else float("inf")

    def levels(self, cutoff: float = 0.0) -> pd.DataFrame:
        """The spectral levels above ``cutoff`` Hz (dB: each contact's force and each mass's
        acceleration, every harmonic above the cut-off) and their exact derivatives
        (:func:`oscillator.orbits.level_derivatives.level_derivatives`, docs/noise.md)."""
        from oscillator.orbits.level_derivatives import level_derivatives

        return level_derivatives(self, cutoff)

    def above(self, cutoff: float = 0.0) -> pd.DataFrame:
        """:attr:`measures` with ``force_above_right``, ``force_above_left``, ``a_above_m1`` and
        ``a_above_m2`` above ``cutoff`` Hz (the RMS of every harmonic above it) and their exact
        derivatives (:func:`oscillator.orbits.level_derivatives.above_derivatives`)."""
        from oscillator.orbits.level_derivatives import above_derivatives

        table = self.measures.copy()
        if cutoff:
            found = above_derivatives(self, cutoff)
            table.loc[found.index] = found
        return table

    def of(self, measure: str) -> pd.Series:
        """The derivatives of one measure (``impact_max_right``, ...) in each parameter."""
        if measure not in self.measures.index:
            raise InputError(
                f"no response measure named {measure!r}; choose one of {', '.join(self.measures.index)}",
                field="measure",
            )
        return self.measures.loc[measure, [f"d/d{name}" for name in self.params]]


def sensitivities(orbit: Orbit, params: str | Sequence[str]) -> Sensitivities:
    """The exact derivatives of ``orbit`` in ``params`` through every switch (module docstring):
    of its map, its section point(s), its switch times and every response measure.  A system's
    orbit (a :class:`~oscillator.orbits.chain_orbits.ChainOrbit`) takes its numbers by element and
    field (:mod:`oscillator.orbits.chain_sensitivity`).

    Raises
    ------
    InputError
        A name that is not a parameter.
    SimulationFailed
        (``reason = "not_differentiable"``) the orbit sits on a grazing, sliding or rest-threshold
        point (:data:`MARGIN`): no derivative exists there.
    """
    from oscillator.orbits.chain_orbits import ChainOrbit
    from oscillator.orbits.response_derivatives import margins_of, measure_derivatives
    from oscillator.orbits.shooting import Orbit, period_map

    if isinstance(orbit, ChainOrbit):  # a system's orbit: its numbers by element and field
        return orbit.sensitivities(params)
    if not isinstance(orbit, Orbit):
        raise InputError(f"orbit must be an Orbit (find_orbit's), got {shown(orbit)}", field="orbit")
    names = check_params(params)
    case, p = orbit.case, orbit.case.parameters
    image = period_map(case, orbit.section, orbit.state, orbit.period)
    span = orbit.period * p.period
    dt_end = np.array([-span / p.Omega if name == "Omega" else 0.0 for name in names])
    k = len(names)
    first = tangent_pass(image.segments, p, names, np.zeros((4, k)), image.t1, dt_end)
    dP = first.end
    assert image.monodromy is not None
    system = np.eye(4) - image.monodromy
    for mass in orbit.resting:
        system[2 * mass - 2] = 0.0
        system[2 * mass - 2, 2 * mass - 2] = 1.0
        dP = dP.copy()
        dP[2 * mass - 2] = 0.0
    dy = np.linalg.solve(system, dP)
    marks = [orbit.section + n * p.period for n in range(orbit.period)]
    along = tangent_pass(image.segments, p, names, dy, image.t1, dt_end, marks)
    margins = margins_of(along, p)
    if len(margins) and margins.distance.iloc[0] < MARGIN:
        nearest = margins.iloc[0]
        raise _not_differentiable(f"{nearest.what} at t = {nearest.t:.10g} s", float(nearest.distance))
    columns = [f"d/d{name}" for name in names]
    return Sensitivities(
        orbit=orbit,
        params=names,
        map=pd.DataFrame(first.end, index=list(_STATE), columns=columns),
        state=pd.DataFrame(dy, index=list(_STATE), columns=columns),
        points=_points(along, marks, p, names, orbit),
        switches=_switch_table(along, names),
        measures=measure_derivatives(along, p, names, orbit.period, span, dt_end),
        margins=margins,
        _along=(image.segments, dy, dt_end),
    )


def _points(along: Pass, marks: list[float], p: Parameters, names: tuple[str, ...], orbit: Orbit) -> pd.DataFrame:
    """The section points ``y(section + n T)`` and their total derivatives (the time moves with ``Omega``)."""
    k = len(names)
    rows = []
    for n, (t, value) in enumerate(zip(marks, along.marks, strict=True)):
        y, sigma = value[:4], value[4:].reshape(4, k)
        moved = np.array([-(t - orbit.section) / p.Omega if name == "Omega" else 0.0 for name in names])
        mode = next(piece.mode for piece in along.pieces if piece.t0 <= t < piece.t1)
        f = np.array(state_derivative(t, y, p, mode))
        total = sigma + np.outer(f, moved)
        for row, name in enumerate(_STATE):
            derivatives = dict(zip([f"d/d{param}" for param in names], total[row], strict=True))
            rows.append({"point": n, "variable": name, "value": y[row]} | derivatives)
    return pd.DataFrame(rows)


def domains_text(mode: Mode) -> str:
    """``"(m1, m2)"`` domains of a mode and its contacts, e.g. ``"(2, 0) left"``."""
    contacts = " ".join(name for name in ("left", "right") if getattr(mode, name))
    return f"({mode.domain1}, {mode.domain2})" + (f" {contacts}" if contacts else "")


def _switch_table(along: Pass, names: tuple[str, ...]) -> pd.DataFrame:
    rows = [
        {
            "t": s.t,
            "before": domains_text(s.before),
            "after": domains_text(s.after),
            "speed": s.speed,
        }
        | {f"dt/d{name}": float(tau) for name, tau in zip(names, s.tau, strict=True)}
        for s in along.switches
    ]
    return pd.DataFrame(rows)
