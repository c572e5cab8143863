"""The derivatives of the response measures along a tangent pass, and the distances to the points
where they do not exist (docs/sensitivities.md).

Every measure of :mod:`oscillator.orbits.response` is a value at an instant or an integral over
the return.  A value ``q(t, y, c)`` read at a switch or at the end of a piece, whose time moves by
``tau``, changes by ``dq = q_y (sigma + f tau) + q_t tau + q_c`` (``f`` the piece's own field: the
acceleration jumps at a switch, the state does not); a value at an interior extremum changes by
``q_y sigma + q_c`` (there ``dq/dt = 0``).  An integral over the pieces changes by the integral of
its integrand's derivative, carried by the tangent system, plus ``g(t1) tau1 - g(t0) tau0`` at each
piece's ends (the integrand may jump at a switch: a contact damper's loss does).  A fraction of
the return (``rest``, contact ``time``) is a sum of durations ``t1 - t0`` over the span ``n T``,
which moves with ``Omega``.  A count (``onsets``) does not move; a rate (``impact_rate``,
``impact_power``, ``impulse_rate``) is a count or an integral over the span, a mean per
impact (``impact_energy``, ``impulse``) an integral over the count, and ``force_rms`` the root of
a mean square less a squared mean, each an integral over the span.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pandas as pd

from oscillator.model.fields import (
    C3,
    D1,
    K3,
    K6,
    D,
    coefficients,
    force_scale,
    kinetic_threshold,
    non_friction_force,
    static_threshold,
)
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.system import ARTICLE
from oscillator.orbits.response import COLUMNS, ENERGY_MEASURES, FORCE_INTEGRAL, FORCE_SQUARE
from oscillator.orbits.sensitivity import Pass, Piece, domains_text
from oscillator.orbits.tangent import INTEGRALS, tangent_rates

__all__ = ["margins_of", "measure_derivatives"]

#: Two candidates for a largest value tie within this relative difference.
TIE = 1e-9
#: A value and its derivatives (k).
Valued = tuple[float, np.ndarray]


def _field(t: float, y: np.ndarray, c: np.ndarray, mode: Mode) -> tuple[np.ndarray, np.ndarray]:
    """The mode's field ``f`` (4) and the response integrands ``g`` (13) at ``(t, y)``."""
    state = np.concatenate([y, np.zeros(INTEGRALS)])
    out = np.empty_like(state)
    tangent_rates(t, state, c, np.zeros(0, dtype=np.int64), mode.sign(1), mode.sign(2), mode.left, mode.right, out)
    return out[:4], out[4:]


class _Ends:
    """Each piece's two ends: the state, its total derivative (``sigma + f tau``) and the integrands."""

    def __init__(self, pieces: list[Piece], c: np.ndarray) -> None:
        self.points: list[tuple[Piece, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        for piece in pieces:
            for t, y, sigma, tau in (
                (piece.t0, piece.y0, piece.sigma0, piece.tau0),
                (piece.t1, piece.y1, piece.sigma1, piece.tau1),
            ):
                f, g = _field(t, y, c, piece.mode)
                self.points.append((piece, y, sigma + np.outer(f, tau), g, tau))

    def integral(self, q: int) -> Valued:
        """``sum over pieces of the integral of g_q`` and its derivative (module docstring)."""
        total, derivative = 0.0, 0.0
        pieces = {id(piece): piece for piece, *_ in self.points}
        for piece in pieces.values():
            total += float(piece.integrals[q])
            derivative = derivative + piece.derivatives[q]
        for k, (_, _, _, g, tau) in enumerate(self.points):
            derivative = derivative + (g[q] * tau if k % 2 else -g[q] * tau)
        return total, np.asarray(derivative, dtype=float)

    def duration(self, inside: Callable[[Mode], bool]) -> Valued:
        """The time spent in the pieces whose mode passes ``inside``, and its derivative."""
        total, derivative = 0.0, 0.0
        for piece, *_ in self.points[::2]:
            if inside(piece.mode):
                total += piece.t1 - piece.t0
                derivative = derivative + piece.tau1 - piece.tau0
        return total, np.asarray(derivative, dtype=float)


def _largest(candidates: list[Valued], k: int) -> Valued:
    """The largest value and its derivative; ``nan`` where two candidates tie for it (to
    :data:`TIE`) but move apart: the largest of the two has a kink there, one derivative each way."""
    if not candidates:
        return 0.0, np.zeros(k)
    value, derivative = max(candidates, key=lambda item: item[0])
    tied = [d for v, d in candidates if abs(v - value) <= TIE * max(abs(value), 1e-300)]
    spread = np.ptp(np.array(tied), axis=0) if len(tied) > 1 else np.zeros(k)
    apart = (spread > 1e-6 * np.max(np.abs(tied), axis=0)) & (spread > 1e-9 * abs(value))
    return value, np.where(apart, np.nan, derivative)


def _negated(item: Valued) -> Valued:
    return -item[0], -item[1]


def _fraction(part: Valued, span: float, dspan: np.ndarray) -> Valued:
    value = part[0] / span
    return value, (part[1] - value * dspan) / span


def _root_mean(square: Valued, span: float, dspan: np.ndarray) -> Valued:
    mean = _fraction(square, span, dspan)
    value = math.sqrt(max(mean[0], 0.0))
    return value, (mean[1] / (2.0 * value) if value > 0 else np.zeros_like(mean[1]))


def _mass(ends: _Ends, along: Pass, mass: int, span: float, dspan: np.ndarray, k: int) -> dict[str, Valued]:
    x, v = 2 * mass - 2, 2 * mass - 1
    places = [(float(y[x]), total[x]) for _, y, total, _, _ in ends.points]
    speeds = [(abs(float(y[v])), math.copysign(1.0, y[v]) * total[v]) for _, y, total, _, _ in ends.points]
    speeds += [
        (abs(float(y[v])), math.copysign(1.0, y[v]) * sigma[v])
        for piece in along.pieces
        for which, _, y, sigma in piece.extrema
        if which == f"v{mass}" and piece.mode.sign(mass) != 0
    ]
    high = _largest(places, k)
    low = _negated(_largest([(-v, -d) for v, d in places], k))
    return {
        "x_max": high,
        "x_min": low,
        "x_pp": (high[0] - low[0], high[1] - low[1]),
        "x_rms": _root_mean(ends.integral(mass - 1), span, dspan),
        "v_peak": _largest(speeds, k),
        "a_rms": _root_mean(ends.integral(1 + mass), span, dspan),
        "rest": _fraction(ends.duration(lambda mode: mode.sign(mass) == 0), span, dspan),
    }


def _impacts(along: Pass, stop: str, c: np.ndarray) -> list[Valued]:
    """The approach speed at each onset on ``stop`` and its derivative (the onset moves by ``tau``)."""
    speeds = []
    for switch in along.switches:
        if getattr(switch.after, stop) and not getattr(switch.before, stop):
            f, _ = _field(switch.t, switch.y, c, switch.before)
            total = switch.sigma_before + np.outer(f, switch.tau)
            closing = switch.y[1] - (switch.y[3] if stop == "left" else 0.0)
            rate = total[1] - (total[3] if stop == "left" else 0.0)
            speeds.append((abs(float(closing)), math.copysign(1.0, closing) * rate))
    return speeds


def _forces(ends: _Ends, along: Pass, stop: str, c: np.ndarray, dc: np.ndarray) -> list[Valued]:
    """The contact force at the ends of the pieces in contact with ``stop`` (and, between the masses,
    at its interior extrema) and its derivative."""
    points = [(y, total) for piece, y, total, _, _ in ends.points if getattr(piece.mode, stop)]
    if stop == "right":
        return [
            (max(float(c[K6] * (y[0] - c[D1])), 0.0), (y[0] - c[D1]) * dc[K6] + c[K6] * (total[0] - dc[D1]))
            for y, total in points
        ]
    points += [
        (y, sigma)
        for piece in along.pieces
        if piece.mode.left
        for which, _, y, sigma in piece.extrema
        if which == "left"
    ]
    forces = []
    for y, total in points:
        gap, closing = y[0] - y[2] + c[D], y[1] - y[3]
        force = c[K3] * gap + c[C3] * closing
        rate = gap * dc[K3] + c[K3] * (total[0] - total[2] + dc[D]) + closing * dc[C3] + c[C3] * (total[1] - total[3])
        forces.append((abs(float(force)), math.copysign(1.0, force) * rate))
    return forces


def _contact(
    ends: _Ends, along: Pass, stop: str, span: float, dspan: np.ndarray, periods: int, c: np.ndarray, dc: np.ndarray
) -> dict[str, Valued]:
    k = len(dspan)
    speeds = _impacts(along, stop, c)
    mean = (
        (float(np.mean([s for s, _ in speeds])), np.mean([d for _, d in speeds], axis=0))
        if speeds
        else (0.0, np.zeros(k))
    )
    return {
        "onsets": (len(speeds) / periods, np.zeros(k)),
        "impact_max": _largest(speeds, k),
        "impact_mean": mean,
        "force_peak": _largest(_forces(ends, along, stop, c, dc), k),
        "time": _fraction(ends.duration(lambda mode: bool(getattr(mode, stop))), span, dspan),
    }


def _impact_rates(onsets: int, lost: Valued, pushed: Valued, span: float, dspan: np.ndarray) -> dict[str, Valued]:
    """A contact's impact rate, energy and impulse per impact, power and impulse rate
    (:func:`~oscillator.orbits.response.impacts`) from its ``onsets``, the energy ``lost`` in it
    and its force's integral ``pushed`` over the return, with their derivatives: the count does not
    move, the span moves with ``Omega``."""

    def each(total: Valued) -> Valued:
        return (total[0] / onsets, total[1] / onsets) if onsets else (0.0, np.zeros_like(dspan))

    return {
        "impact_rate": _fraction((float(onsets), np.zeros_like(dspan)), span, dspan),
        "impact_energy": each(lost),
        "impact_power": _fraction(lost, span, dspan),
        "impulse": each(pushed),
        "impulse_rate": _fraction(pushed, span, dspan),
    }


def _fluctuation(square: Valued, mean: Valued) -> Valued:
    """``sqrt(mean square - mean^2)``, a signal's RMS about its mean, and its derivative."""
    spread = square[0] - mean[0] ** 2
    value = math.sqrt(max(spread, 0.0))
    derivative = (square[1] - 2.0 * mean[0] * mean[1]) / (2.0 * value) if value > 0 else np.zeros_like(square[1])
    return value, derivative


def measure_derivatives(
    along: Pass, p: Parameters, names: tuple[str, ...], periods: int, span: float, dspan: np.ndarray
) -> pd.DataFrame:
    """Every response measure over the return of ``along`` (a pass along an orbit, from its own
    derivative) and its derivative in each parameter: index :data:`~oscillator.orbits.response.COLUMNS`,
    columns ``value`` and ``d/d<param>``."""
    from oscillator.orbits.sensitivity import selector_of

    c = coefficients(p)
    k = len(names)
    dc = selector_of(names)
    ends = _Ends(along.pieces, c)
    found: dict[str, Valued] = {}
    for mass in (1, 2):
        found |= {f"{name}_m{mass}": value for name, value in _mass(ends, along, mass, span, dspan, k).items()}
    for stop in ("right", "left"):
        measured = _contact(ends, along, stop, span, dspan, periods, c, dc)
        found |= {f"{name}_{stop}": value for name, value in measured.items()}
    for q, name in enumerate(ENERGY_MEASURES):
        total, derivative = ends.integral(4 + q)
        found[f"energy_{name}"] = (total / periods, derivative / periods)
    lost = {"right": (0.0, np.zeros(k)), "left": ends.integral(4 + ENERGY_MEASURES.index("contact"))}
    for stop in ("right", "left"):
        onsets = round(found[f"onsets_{stop}"][0] * periods)
        pushed = ends.integral(FORCE_INTEGRAL[stop])
        rates = _impact_rates(onsets, lost[stop], pushed, span, dspan)
        rates["force_rms"] = _fluctuation(
            _fraction(ends.integral(FORCE_SQUARE[stop]), span, dspan), rates["impulse_rate"]
        )
        rates["force_above"] = rates["force_rms"]  # above 0 Hz; above a cut-off: Sensitivities.above
        found |= {f"{name}_{stop}": value for name, value in rates.items()}
    for mass in (1, 2):  # on an orbit the acceleration's mean, the velocity's change, is 0
        found[f"a_above_m{mass}"] = found[f"a_rms_m{mass}"]
    rows = {column: [found[column][0], *np.asarray(found[column][1], dtype=float)] for column in COLUMNS}
    return pd.DataFrame.from_dict(rows, orient="index", columns=["value", *(f"d/d{name}" for name in names)])


def _interior_minima(values: np.ndarray) -> np.ndarray:
    """The indices of the samples lower than both neighbours (ends excluded)."""
    inner = np.flatnonzero((values[1:-1] < values[:-2]) & (values[1:-1] <= values[2:])) + 1
    return inner


def margins_of(along: Pass, p: Parameters) -> pd.DataFrame:
    """The relative distance from every point of ``along`` where the map is not differentiable
    (module docstring of :mod:`oscillator.orbits.sensitivity`), nearest first: each switch's
    transversality (its crossing speed against the largest rate of the state it crosses in);
    at each arrival at zero velocity, how far the force is from the static
    threshold (stop or reverse); in each piece, the closest approach of a boundary it does not
    cross (a stop in free flight, a contact's end, zero velocity, the flow barrier at rest),
    read at its interior minima on 33 samples a piece."""
    samples = np.concatenate([piece.samples for piece in along.pieces])
    reach = {name: float(np.ptp(samples[:, k])) + 1e-300 for k, name in enumerate(ARTICLE.state)}
    c = coefficients(p)
    fields = np.array([_field(piece.t0, y, c, piece.mode)[0] for piece in along.pieces for y in piece.samples])
    rates = np.max(np.abs(fields), axis=0) + 1e-300
    rows = [
        (
            f"the switch {domains_text(s.before)} -> {domains_text(s.after)}",
            s.t,
            abs(s.speed) / float(np.abs(s.normal) @ rates),
        )
        for s in along.switches
    ]
    for s in along.switches:
        for mass in (1, 2):
            if s.before.sign(mass) != 0 and s.after.sign(mass) != s.before.sign(mass):
                # Theorem 5.1: a mass at zero velocity passes where the force across exceeds the
                # kinetic threshold (5.12)-(5.13), else it comes to rest: there it is decided
                forces = non_friction_force(s.t, s.y, p, s.after.left, s.after.right)
                gap = abs(abs(forces[mass - 1]) - kinetic_threshold(p, mass))
                gap /= force_scale(s.t, s.y, p, s.after, mass)
                rows.append((f"m{mass} at zero velocity with its force on the kinetic threshold", s.t, gap))
    for piece in along.pieces:
        rows += _approaches(piece, p, reach)
    table = pd.DataFrame(rows, columns=["what", "t", "distance"])
    return table.sort_values("distance", kind="stable").reset_index(drop=True)


def _approaches(piece: Piece, p: Parameters, reach: dict[str, float]) -> list[tuple[str, float, float]]:
    """The interior closest approaches of the boundaries ``piece`` does not cross."""
    y = piece.samples
    times = np.linspace(piece.t0, piece.t1, len(y))
    mode = piece.mode
    watched: list[tuple[str, np.ndarray, float]] = []
    relative = y[:, 0] - y[:, 2] + p.d
    watched.append(
        (
            "a grazing contact between the masses" if not mode.left else "a contact between the masses about to end",
            relative if not mode.left else -relative,
            max(reach["x1"], reach["x2"], abs(p.d)),
        )
    )
    watched.append(
        (
            "a grazing of the right stop" if not mode.right else "a contact with the right stop about to end",
            (p.d1 - y[:, 0]) if not mode.right else (y[:, 0] - p.d1),
            max(reach["x1"], abs(p.d1)),
        )
    )
    for mass in (1, 2):
        sign = mode.sign(mass)
        if sign != 0:
            watched.append((f"m{mass} nearly sticking", sign * y[:, 2 * mass - 1], reach[f"v{mass}"]))
        else:
            forces = np.array(
                [
                    non_friction_force(t, row, p, mode.left, mode.right)[mass - 1]
                    for t, row in zip(times, y, strict=True)
                ]
            )
            scale = max(force_scale(piece.t0, piece.y0, p, mode, mass), 1e-300)
            watched.append((f"m{mass} nearly leaving rest", static_threshold(p, mass) - np.abs(forces), scale))
    found = []
    for what, values, scale in watched:
        for index in _interior_minima(values):
            found.append((what, float(times[index]), max(float(values[index]), 0.0) / scale))
    return found
