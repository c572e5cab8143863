"""The response measures of a periodic motion: what a designer reads off an orbit (issue 38).

:func:`response` runs one return of the motion from its section point and reads the measures from
the run's own smooth pieces and events, not from samples: each piece (a mode's flow between two
switches, :class:`~oscillator.hybrid.record.Segment`) is integrated again from its start with
the integrals below carried along and the interior extrema located as roots (DOP853 at
``rtol = atol = 1e-12``, compiled: :mod:`oscillator.orbits.pieces`), and every switch is
read where it happened.  With ``T`` the
forcing period and ``nT`` the return's length, per mass ``i``:

* ``x_max``, ``x_min`` (m): the extreme displacements, each at a velocity zero (an event of the
  run: a reversal or the start of a rest) or constant through a rest; ``x_pp = x_max - x_min``;
* ``x_rms = sqrt(1/nT integral x_i^2 dt)`` (m), about the spring's rest position ``x_i = 0``;
* ``v_peak = max |v_i|`` (m/s), at an interior zero of the acceleration or at a switch (the
  acceleration jumps at a contact);
* ``a_rms = sqrt(1/nT integral a_i^2 dt)`` (m/s^2), ``a_i`` the field of the mode (0 at rest);
* ``a_above`` (m/s^2): the RMS of the acceleration's harmonics above the cut-off (``cutoff`` Hz, 0
  by default: ``sqrt(a_rms^2 - abar^2)``, every harmonic but the mean ``abar``, which is the
  velocity's change over the return divided by ``nT``: 0 on an orbit);
* ``rest``: the fraction of the return the mass rests;

per contact (``right``: m1 on the stop at ``x1 = d1``; ``left``: between the masses, ``z1 = -d``):

* ``onsets``: contacts begun per forcing period;
* ``impact_max``, ``impact_mean`` (m/s): the approach speed at each onset, ``|v1|`` on the right
  stop and ``|v1 - v2|`` between the masses (0 without contacts);
* ``force_peak`` (N): the largest contact force, ``K6 (x1 - d1)`` on the right stop and
  ``|K3 (x1 - x2 + d) + C3 (v1 - v2)|`` between the masses (its interior extrema located where
  ``K3 zdot1 + C3 (a1 - a2) = 0``);
* ``time``: the fraction of the return in contact;
* ``impact_rate`` (1/s): impacts per second, ``onsets / T``;
* ``impact_energy`` (J): the energy an impact loses, ``contact / onsets`` between the masses (the
  damper ``C3``) and 0 on the right stop (``K6`` has no damper: its impacts are elastic);
* ``impact_power`` (W): the power the contact dissipates, ``impact_rate * impact_energy``;
* ``impulse`` (N s): the mean impulse of an impact, ``integral F dt / (onsets n)`` with ``F`` the
  contact force, compressive positive (``K6 (x1 - d1)`` on the right stop, ``-(K3 (x1 - x2 + d) +
  C3 (v1 - v2))`` between the masses), integrated along the pieces in contact;
* ``impulse_rate`` (N): ``impact_rate * impulse``, the contact's mean force over the return;
* ``force_rms`` (N): the contact force's fluctuation about that mean, ``sqrt(1/nT integral F^2 dt
  - impulse_rate^2)``: by Parseval, its spectrum's every harmonic above 0 Hz, whose level is
  ``20 log10(force_rms / 1 N)`` dB (the noise measures of docs/noise.md that the integrals give
  exactly);
* ``force_above`` (N): the RMS of the force's harmonics above the cut-off (``cutoff`` Hz):
  ``sqrt(force_rms^2 - sum_{0 < k/nT <= cutoff} 2 |c_k|^2)``, ``c_k`` its Fourier coefficients
  (:mod:`oscillator.orbits.noise`); ``force_rms`` at the default cut-off 0; its level is
  ``20 log10(force_above / 1 N)`` dB, a design's "spectral level above a cut-off";

and per forcing period (J): ``forcing`` (work of ``Q_i sin(Omega t + phi_i)``), ``feedback``
(work of the constant forces ``-P_i s_i``), ``dampers`` (lost in ``C1, C2, C4, C5``),
``contact`` (lost in the contact damper ``C3``), ``friction`` (lost to kinetic friction).  Over a
return of a periodic orbit the mechanical energy comes back, so ``forcing + feedback = dampers +
contact + friction`` (:attr:`Response.balance`, zero to the integration's tolerance).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from oscillator.errors import InputError
from oscillator.hybrid.record import Segment
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, not_a_case, resolve_case
from oscillator.model.events import COLUMN, KINDS, WIDTH, EventKind
from oscillator.model.fields import C3, K3, D, coefficients
from oscillator.model.parameters import Parameters, check_count
from oscillator.orbits.pieces import ARTICLE_PIECE, IntegratedPiece, article_data, integrate_piece, mode_flags
from oscillator.orbits.spectra import check_cutoff, harmonics_below
from oscillator.orbits.tangent import INTEGRALS

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from oscillator.orbits.branch import Branch

__all__ = [
    "COLUMNS",
    "CONTACT_MEASURES",
    "ENERGY_MEASURES",
    "FORCE_INTEGRAL",
    "FORCE_SQUARE",
    "MASS_MEASURES",
    "UNITS",
    "Response",
    "above",
    "above_note",
    "branch_points",
    "branch_responses",
    "impact_speeds",
    "impacts",
    "integrated",
    "left_force",
    "measured",
    "measured_above",
    "response",
    "unit_of",
]

#: The measures of each mass and of each contact, in :class:`Response`'s order.
MASS_MEASURES = ("x_max", "x_min", "x_pp", "x_rms", "v_peak", "a_rms", "a_above", "rest")
CONTACT_MEASURES = (
    "onsets",
    "impact_max",
    "impact_mean",
    "force_peak",
    "time",
    "impact_rate",
    "impact_energy",
    "impact_power",
    "impulse",
    "impulse_rate",
    "force_rms",
    "force_above",
)
ENERGY_MEASURES = ("forcing", "feedback", "dampers", "contact", "friction")
#: Every measure's column, in :meth:`Response.columns`'s order: ``x_max_m1, ..., impact_max_right,
#: ..., energy_friction``.
COLUMNS = (
    *(f"{name}_m{mass}" for mass in (1, 2) for name in MASS_MEASURES),
    *(f"{name}_{stop}" for stop in ("right", "left") for name in CONTACT_MEASURES),
    *(f"energy_{name}" for name in ENERGY_MEASURES),
)
#: The unit of each measure (empty: a fraction or a count per period); energies in J per period.
UNITS = {"x_max": "m", "x_min": "m", "x_pp": "m", "x_rms": "m", "v_peak": "m/s", "a_rms": "m/s²", "rest": ""}
UNITS |= {"a_above": "m/s²"}
UNITS |= {"onsets": "per period", "impact_max": "m/s", "impact_mean": "m/s", "force_peak": "N", "time": ""}
UNITS |= {"impact_rate": "1/s", "impact_energy": "J", "impact_power": "W", "impulse": "N s", "impulse_rate": "N"}
UNITS |= {"force_rms": "N", "force_above": "N"}
UNITS |= {name: "J per period" for name in ENERGY_MEASURES}


def above_note(column: str, cutoff: float) -> str:
    """``", above 1 Hz"`` for a measure above a cut-off (``force_above_left``, ``a_above_m1``: the
    cut-off named where it is drawn), ``""`` for another."""
    return f", above {cutoff:g} Hz" if column.startswith(("force_above", "a_above")) else ""


def unit_of(column: str) -> str:
    """The unit of a measure's column (``impact_max_right``: ``m/s``)."""
    name = column.removeprefix("energy_") if column.startswith("energy_") else column.rsplit("_", 1)[0]
    return UNITS[name]


@dataclass(frozen=True)
class Response:
    """The response measures of one return (module docstring): ``mass[i][name]`` for ``i = 1, 2``,
    ``contact[stop][name]`` for ``stop = "right", "left"``, ``energy[name]`` per forcing period."""

    periods: int
    mass: dict[int, dict[str, float]]
    contact: dict[str, dict[str, float]]
    energy: dict[str, float]

    @property
    def balance(self) -> float:
        """``forcing + feedback - dampers - contact - friction`` per period (J): zero for a periodic orbit."""
        e = self.energy
        return e["forcing"] + e["feedback"] - e["dampers"] - e["contact"] - e["friction"]

    def columns(self) -> dict[str, float]:
        """Every measure as a flat mapping: ``x_max_m1``, ``impact_max_left``, ``energy_forcing``, ..."""
        flat = {f"{name}_m{i}": value for i, values in self.mass.items() for name, value in values.items()}
        flat |= {f"{name}_{stop}": value for stop, values in self.contact.items() for name, value in values.items()}
        return flat | {f"energy_{name}": value for name, value in self.energy.items()}


def response(case: Case, periods: int = 1, cutoff: float = 0.0) -> Response:
    """The response measures of the case's motion from its start over ``periods`` forcing periods
    (module docstring): of an orbit, over its return (:meth:`oscillator.Orbit.response`); of
    another start, ``response(resolve_case(case, x1=..., v1=..., x2=..., v2=...), periods)``.
    ``force_above`` and ``a_above`` are the RMS of the harmonics above ``cutoff`` Hz."""
    if not isinstance(case, Case):  # a declared system's measures: orbit_measures(find_orbit(chain))
        raise InputError(not_a_case(case), field="case")
    check_count(periods, "periods", 1, 100_000)
    check_cutoff(cutoff)
    span = periods * case.parameters.period
    result = simulate(case, t_end=case.initial.t0 + span, save=SaveAt(steps=False, segments=True))
    return measured_above(result, periods, cutoff)


def measured_above(result: Result, periods: int, cutoff: float) -> Response:
    """:func:`measured`, with ``force_above`` and ``a_above`` above ``cutoff`` Hz: the low harmonics
    from the same run's pieces, integrated again with their dense output (the noise measures')."""
    below = harmonics_below(cutoff, periods * result.case.parameters.period)
    if not below:
        return measured(result, periods)
    from oscillator.orbits.noise import response_above

    return response_above(result, periods, below)


def above(found: Response, low: np.ndarray) -> Response:
    """``found`` with ``force_above`` and ``a_above`` above a cut-off: less the harmonics ``1..K``
    whose Fourier coefficients are ``low``'s rows ``1..K`` (columns: the right stop's force, the
    left contact's, m1's and m2's accelerations, :func:`oscillator.orbits.noise.noise`'s)."""
    removed = 2 * np.sum(np.abs(low[1:]) ** 2, axis=0)
    contact = {stop: dict(values) for stop, values in found.contact.items()}
    mass = {i: dict(values) for i, values in found.mass.items()}
    for k, stop in enumerate(("right", "left")):
        contact[stop]["force_above"] = math.sqrt(max(contact[stop]["force_rms"] ** 2 - removed[k], 0.0))
    for i in (1, 2):
        mass[i]["a_above"] = math.sqrt(max(mass[i]["a_above"] ** 2 - removed[1 + i], 0.0))
    return replace(found, mass=mass, contact=contact)


def measured(result: Result, periods: int, solved: Sequence[IntegratedPiece] | None = None) -> Response:
    """The response measures of a run of ``periods`` forcing periods that kept its segments;
    ``solved``: its pieces of positive length already integrated again (:func:`integrated`)."""
    p = result.case.parameters
    span = periods * p.period
    segments = [segment for segment in result.segments if segment.t1 > segment.t0]
    again = [None] * len(segments) if solved is None else list(solved)
    pieces = [_Piece.of(segment, p, piece) for segment, piece in zip(segments, again, strict=True)]
    mass = {i: _mass_measures(pieces, i, span) for i in (1, 2)}
    rows = result.event_rows
    events = result.events if rows is None else rows  # the rows while the table is not built: none built
    contact = {stop: _contact_measures(pieces, events, stop, span, periods) for stop in ("right", "left")}
    totals = np.sum([piece.integrals for piece in pieces], axis=0)
    energy = {name: float(totals[_ENERGY + k]) / periods for k, name in enumerate(ENERGY_MEASURES)}
    for stop, lost in (("right", 0.0), ("left", energy["contact"])):
        pushed = float(totals[FORCE_INTEGRAL[stop]]) / periods
        contact[stop] |= impacts(contact[stop]["onsets"], lost, pushed, p.period)
        squared = float(totals[FORCE_SQUARE[stop]]) / periods
        contact[stop]["force_rms"] = math.sqrt(max(squared / p.period - (pushed / p.period) ** 2, 0.0))
        contact[stop]["force_above"] = contact[stop]["force_rms"]  # above 0 Hz; above a cut-off: above()
    return Response(periods, mass, contact, energy)


def impacts(onsets: float, lost: float, pushed: float, period: float) -> dict[str, float]:
    """A contact's ``impact_rate``, ``impact_energy``, ``impact_power``, ``impulse`` and
    ``impulse_rate`` (module docstring) from its ``onsets``, the energy ``lost`` in it and the
    impulse ``pushed`` (its force's integral) per forcing ``period``."""
    return {
        "impact_rate": onsets / period,
        "impact_energy": lost / onsets if onsets else 0.0,
        "impact_power": lost / period,
        "impulse": pushed / onsets if onsets else 0.0,
        "impulse_rate": pushed / period,
    }


#: Newton's tolerance on ``|P(y) - y|`` where a branch point is refined before it is measured: the
#: continuation's corrector stops at 1e-9, which a multiplier near 1 (weak damping, a resting mass)
#: turns into 1e-6 of the state.
REFINE = 1e-12


def branch_points(branch: Branch) -> Iterator[tuple[dict[str, Any], Case]]:
    """Each point of a continued branch: its row's parameter, ``stable`` and ``piece``, and the
    case that starts on its orbit at the branch's section."""
    if branch.case is None:
        raise InputError(
            "the branch carries no case to run its orbits from; continue it with continue_orbit", field="branch"
        )
    for point in branch.points.itertuples(index=False):
        values = point._asdict()
        state = {name: float(values[name]) for name in branch.case.system.state}
        case = resolve_case(branch.case, **{branch.param: float(values[branch.param])}, t0=branch.section, **state)
        yield {branch.param: values[branch.param], "stable": values["stable"], "piece": values["piece"]}, case


def branch_responses(branch: Branch, cutoff: float = 0.0) -> pd.DataFrame:
    """The response measures at every point of a continued branch: one row per point with the
    parameter, ``stable``, ``piece`` and every measure of :meth:`Response.columns` (the
    frequency response of the branch, when the parameter is ``Omega``; ``force_above`` and
    ``a_above`` above ``cutoff`` Hz).  Each point's orbit is refined by Newton to :data:`REFINE`
    first, or to where the period map's noise stops it (:func:`~oscillator.orbits.shooting.newton`'s
    ``floor``), and measured on Newton's last run;
    it stays as it is where Newton fails (a grazing or sliding point)."""
    import pandas as pd

    from oscillator.errors import OscillatorError
    from oscillator.orbits.shooting import newton, tightened

    check_cutoff(cutoff)
    rows = []
    for row, case in branch_points(branch):
        state = np.array(case.initial.y, dtype=float)
        try:
            tight = tightened(case, {})
            _, image, _ = newton(tight, branch.section, state, branch.period, tol=REFINE, max_iterations=20, floor=True)
            measures = measured_above(image.result, branch.period, cutoff)
        except OscillatorError:
            measures = response(case, branch.period, cutoff)
        rows.append(row | measures.columns())
    return pd.DataFrame(rows)


# The integrals carried along a piece: x1^2, x2^2, a1^2, a2^2, the energies, the contact forces.
_SQUARES, _ENERGY = 0, 4
#: Each contact's force integral among them (its impulse over the piece).
FORCE_INTEGRAL = {"right": 9, "left": 10}
#: And the integral of its square.
FORCE_SQUARE = {"right": 11, "left": 12}
#: The re-integration's tolerances (the run's own are CVODE's 1e-10).
TOLERANCE = 1e-12


@dataclass(frozen=True)
class _Piece:
    """One smooth piece integrated again: its mode, span, the integrals over it, and the extreme
    speeds and contact force in it (ends and interior extrema)."""

    segment: Segment
    integrals: np.ndarray
    speed: tuple[float, float]
    force: tuple[float, float]

    @classmethod
    def of(cls, segment: Segment, p: Parameters, solved: IntegratedPiece | None = None) -> _Piece:
        """The piece's measures, from ``solved`` (:func:`integrated`) where it is given."""
        c, mode = coefficients(p), segment.mode
        solved = integrated(segment, c) if solved is None else solved
        ends = [segment.y0, solved.end[:4]]
        speeds = [[abs(y[2 * i - 1]) for y in ends] for i in (1, 2)]
        for i in (1, 2):
            speeds[i - 1] += [abs(y[2 * i - 1]) for y in solved.states[solved.which == i - 1]]
        forces = [abs(float(left_force(y, c))) for y in [*ends, *solved.states[solved.which == 2]]]
        right = [max(float(p.K6 * (y[0] - p.d1)), 0.0) for y in ends]
        return cls(
            segment,
            solved.end[4:],
            (max(speeds[0]), max(speeds[1])),
            (max(right) if mode.right else 0.0, max(forces) if mode.left else 0.0),
        )


def integrated(segment: Segment, c: np.ndarray, *, dense: bool = False) -> IntegratedPiece:
    """``segment`` integrated again from its start with the response integrals (``c`` the
    coefficients, :func:`~oscillator.model.fields.coefficients`), with its dense output if
    ``dense``: the one place a piece is measured from."""
    data = article_data(mode_flags(segment.mode), np.zeros(0, np.int64), c)
    start = np.concatenate([segment.y0, np.zeros(INTEGRALS)])
    span = (segment.t0, segment.t1)
    return integrate_piece(ARTICLE_PIECE, data, span, start, rtol=TOLERANCE, atol=TOLERANCE, dense=dense)


def left_force(y: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The force between the masses in contact (N): ``K3 (x1 - x2 + d) + C3 (v1 - v2)`` (negative
    while the contact pushes m1 away from m2's stop); ``y`` a state ``(x1, v1, x2, v2)`` or one
    such row of states each, ``c`` the coefficients (:func:`~oscillator.model.fields.coefficients`)."""
    force: np.ndarray = c[K3] * (y[0] - y[2] + c[D]) + c[C3] * (y[1] - y[3])
    return force


def _mass_measures(pieces: list[_Piece], mass: int, span: float) -> dict[str, float]:
    """The measures of mass ``mass`` over the pieces (module docstring)."""
    column = 2 * (mass - 1)
    ends = [piece.segment.y0[column] for piece in pieces] + [piece.segment.y1[column] for piece in pieces]
    rest = sum(piece.segment.t1 - piece.segment.t0 for piece in pieces if piece.segment.mode.sign(mass) == 0)
    squares = sum(float(piece.integrals[_SQUARES + mass - 1]) for piece in pieces)
    accelerations = sum(float(piece.integrals[_SQUARES + 1 + mass]) for piece in pieces)
    high, low = max(ends), min(ends)
    mean = (pieces[-1].segment.y1[column + 1] - pieces[0].segment.y0[column + 1]) / span  # of a_i: dv_i/nT
    return {
        "x_max": float(high),
        "x_min": float(low),
        "x_pp": float(high - low),
        "x_rms": math.sqrt(max(squares, 0.0) / span),
        "v_peak": float(max(piece.speed[mass - 1] for piece in pieces)),
        "a_rms": math.sqrt(max(accelerations, 0.0) / span),
        "a_above": math.sqrt(max(accelerations / span - mean**2, 0.0)),
        "rest": rest / span,
    }


def impact_speeds(events: pd.DataFrame | np.ndarray, stop: str) -> np.ndarray:
    """The approach speed at each contact onset on ``stop`` (``"right"`` or ``"left"``) of an event
    table, or of a run's event rows (:attr:`~oscillator.Result.event_rows`: no table built), in
    order (m/s): ``|v1|`` on the right stop, ``|v1 - v2|`` between the masses (a contact between
    the masses is written for both, and counted once)."""
    if isinstance(events, np.ndarray):
        rows = events.reshape(-1, WIDTH)
        kinds = [KINDS[int(code)] for code in rows[:, COLUMN["kind"]]]
        masses, v1, v2 = rows[:, COLUMN["mass"]], rows[:, COLUMN["v1"]], rows[:, COLUMN["v2"]]
    else:
        kinds = [EventKind(kind) for kind in events.kind]
        masses, v1, v2 = events["mass"].to_numpy(), events.v1.to_numpy(float), events.v2.to_numpy(float)
    onsets = [
        k
        for k, (kind, mass) in enumerate(zip(kinds, masses, strict=True))
        if kind.contact_starts and kind.contact == stop and kind.stands_for_event(int(mass))
    ]
    speeds: np.ndarray = np.abs(v1[onsets] - v2[onsets] if stop == "left" else v1[onsets]).astype(float)
    return speeds


def _contact_measures(
    pieces: list[_Piece], events: pd.DataFrame | np.ndarray, stop: str, span: float, periods: int
) -> dict[str, float]:
    """The measures of the contact on ``stop`` (module docstring)."""
    speeds = impact_speeds(events, stop)
    inside = [piece for piece in pieces if (piece.segment.mode.left if stop == "left" else piece.segment.mode.right)]
    return {
        "onsets": len(speeds) / periods,
        "impact_max": float(np.max(speeds)) if len(speeds) else 0.0,
        "impact_mean": float(np.mean(speeds)) if len(speeds) else 0.0,
        "force_peak": max((piece.force[0 if stop == "right" else 1] for piece in inside), default=0.0),
        "time": sum(piece.segment.t1 - piece.segment.t0 for piece in inside) / span,
    }
