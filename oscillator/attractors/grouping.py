"""The grouper: landings into attractors, and what an attractor is.

Landings are grouped into attractors in the starts' order (so the same starts give the same
attractors, numbered the same, for any number of workers): two periodic landings are one
attractor when their cycles of switches are the same and their cycles of section points agree,
in some rotation, within ``match`` (relative to the state's size); two aperiodic ones when each
one's points lie near the other's set (:func:`interleaving`).  The attractors are then numbered
in :func:`order_key` order, whatever the order the starts met them.  One classification
(:attr:`Attractor.kind`, :func:`regime_of`) and one threshold (:data:`CHAOTIC`) serve every
analysis.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from oscillator.attractors.mapping import AttractorSettings, Landing
from oscillator.orbits.shooting import Orbit

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.chain_orbits import ChainOrbit

__all__ = [
    "APERIODIC_PERIODS",
    "CHAOTIC",
    "Attractor",
    "group",
    "interleaving",
    "order_key",
    "ordered",
    "regime_of",
    "unsettled",
]

#: ``lambda_1 T`` above which an aperiodic attractor is called chaotic, and below whose size it is
#: called quasi-periodic (the exponent is zero within what the averaging resolves).
CHAOTIC = 0.01

#: Two aperiodic landings are one attractor when their points :func:`interleaving` at least this
#: much (1: as two samples of one set; 0: sets apart) ...
INTERLEAVED = 0.5

#: ... and the grouping is said not to be settled where two sets kept apart interleave more than this.
UNSETTLED = 0.1

#: The most section points an aperiodic attractor pools from its landings, to tell later ones by.
SET_POINTS = 4096

#: The most forcing periods an aperiodic attractor is measured over (:meth:`Attractor.window`).
APERIODIC_PERIODS = 100


@dataclass(frozen=True)
class Attractor:
    """One attractor: a period-n orbit of the stroboscopic map, or an aperiodic set.

    Attributes
    ----------
    id : int
        Its number, from 0, in the order the starts first reached it.
    period : int
        Forcing periods per return; 0 for an aperiodic set.
    points : ndarray
        Its section points (the system's state: ``x1, v1, x2, v2`` for the article's): the
        ``period`` points of the cycle, or the recorded points of the set.
    signature : str
        Each mass's cycle of switches over one return (periodic attractors; each switching
        element's for a friction chain).
    rests : tuple of float
        Rest intervals per forcing period of each mass of :attr:`masses`.
    contacts : float
        Contact onsets (either stop; a friction chain's stops and contacts) per forcing period.
    starts : int
        How many starts reached it.
    orbit : Orbit, ChainOrbit or None
        The periodic orbit refined by Newton from its cycle (multipliers, stability); None for an
        aperiodic set or when Newton failed (``note`` says why).
    lyapunov : float
        The largest Lyapunov exponent (1/s): ``log |mu_1| / (n T)`` of a refined periodic orbit
        (its largest Floquet multiplier; 0 where a mass rests all period, ``-inf`` where the
        flow collapses every direction), the QR average of an aperiodic set; NaN when not
        computed.
    note : str
        What the refinement met.
    forcing_period : float
        ``T`` of the case it was found in.
    rest_time : tuple of float
        The fraction of the time each mass rests (1: a mass that rests throughout, with no rest
        interval beginning).
    measures : dict
        The measures a describer added (:class:`~oscillator.attractors.finding.Refined`: the
        response measures of the refined orbit, :data:`~oscillator.orbits.response.COLUMNS`;
        :data:`~oscillator.attractors.features.MEASURES`: the
        largest impact velocity, ...), by name.
    masses : tuple of str
        The masses' names, in the order of ``rests`` and ``rest_time`` (a friction chain's own;
        a mass of a chain rests while it sticks to its floor or belt).
    """

    id: int
    period: int
    points: np.ndarray = field(repr=False)
    signature: str
    rests: tuple[float, ...]
    contacts: float
    starts: int
    orbit: Orbit | ChainOrbit | None = field(default=None, repr=False)
    lyapunov: float = math.nan
    note: str = ""
    forcing_period: float = math.nan
    rest_time: tuple[float, ...] = (0.0, 0.0)
    measures: dict[str, float] = field(default_factory=dict)
    masses: tuple[str, ...] = ("m1", "m2")

    @classmethod
    def of_landing(cls, ident: int, landing: Landing) -> Attractor:
        """The attractor a landing has reached, as far as the landing tells (one start, its cycle
        or its recorded set; not refined)."""
        points = landing.points[-landing.period :] if landing.period else landing.points
        return cls(
            ident,
            landing.period,
            points,
            landing.signature,
            landing.rests,
            landing.contacts,
            1,
            rest_time=landing.rest_time,
        )

    def window(self) -> tuple[np.ndarray, int]:
        """Where a run that measures the attractor starts (a section point) and over how many
        forcing periods: one return from its last section point (a periodic one); from its first
        over as many forcing periods as it has recorded points, at most
        :data:`APERIODIC_PERIODS` (an aperiodic one: a long run's average, its peaks the largest
        seen)."""
        if self.period:
            return self.points[-1], self.period
        return self.points[0], max(1, min(len(self.points), APERIODIC_PERIODS))

    def response_columns(self) -> dict[str, float]:
        """The response measures of its refined orbit by column
        (:data:`~oscillator.orbits.response.COLUMNS`), NaN where they were not measured (an
        aperiodic set, an orbit Newton did not refine)."""
        from oscillator.orbits.response import COLUMNS

        return {name: self.measures.get(name, math.nan) for name in COLUMNS}

    @property
    def kind(self) -> str:
        """``periodic``, ``chaotic`` (largest exponent positive), ``quasi-periodic`` (zero) or
        ``aperiodic`` (no period found and no exponent to tell)."""
        if self.period:
            return "periodic"
        if math.isnan(self.lyapunov) or math.isnan(self.forcing_period):
            return "aperiodic"
        scaled = self.lyapunov * self.forcing_period
        if scaled > CHAOTIC:
            return "chaotic"
        return "quasi-periodic" if scaled > -CHAOTIC else "aperiodic"

    @property
    def name(self) -> str:
        """A label for legends and tables: ``"A0: period-1, m2 rests 2/period"``."""
        what = f"period-{self.period}" if self.period else self.kind
        parts = [
            f"{mass} rests {rate:g}/period" if rate else f"{mass} rests throughout"
            for mass, rate, share in zip(self.masses, self.rests, self.rest_time, strict=True)
            if rate or share > 0
        ]
        if self.contacts:
            parts.append(f"{self.contacts:g} contacts/period")
        return f"A{self.id}: {what}" + (", " + ", ".join(parts) if parts else ", no rest")

    @property
    def stable(self) -> bool | None:
        """The refined orbit's stability (None when there is no refined orbit)."""
        return None if self.orbit is None else self.orbit.stable


def cycle_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The smallest, over rotations of ``b``, largest distance between the two cycles' points."""
    return min(float(np.max(np.linalg.norm(a - np.roll(b, r, axis=0), axis=1))) for r in range(len(b)))


def interleaving(a: np.ndarray, b: np.ndarray) -> float:
    """How much two point sets interleave: the share of all their points whose nearest other
    point belongs to the other set, over the share expected were both samples of one set
    (``2 |a| |b| / (n (n - 1))``).  About 1 for two samples of one attractor, however sparse;
    near 0 for two sets apart.  Distances are taken in units of the union's extent in each
    component, so that displacements and velocities weigh alike."""
    from scipy.spatial import cKDTree

    both = np.vstack([a, b])
    n = len(both)
    if len(a) == 0 or len(b) == 0 or n < 3:
        return 0.0
    extent = np.ptp(both, axis=0)
    scaled = both / np.where(extent > 0, extent, 1.0)
    _, nearest = cKDTree(scaled).query(scaled, k=2)
    owner = np.arange(n) >= len(a)
    crossing = float(np.mean(owner[nearest[:, 1]] != owner))
    return crossing / (2.0 * len(a) * len(b) / (n * (n - 1)))


def _same_cycle(landing: Landing, attractor: Attractor, settings: AttractorSettings) -> bool:
    if landing.period != attractor.period or landing.signature != attractor.signature:
        return False
    mine = landing.points[-attractor.period :]
    scale = 1.0 + max(float(np.max(np.abs(mine))), float(np.max(np.abs(attractor.points))))
    return cycle_distance(mine, attractor.points) <= settings.match * scale


def _pooled(keep: Attractor, points: np.ndarray, starts: int) -> Attractor:
    """An aperiodic attractor with more starts and their points pooled into its own (at most
    :data:`SET_POINTS`, the earlier ones kept)."""
    pool = np.vstack([keep.points, points])[:SET_POINTS]
    return dataclasses.replace(keep, points=pool, starts=keep.starts + starts)


def group(landings: Iterable[Landing], settings: AttractorSettings) -> tuple[list[Attractor], dict[int, int]]:
    """The attractors of the landings, and each landing's attractor (``index -> id``, failed ones
    absent), in :func:`ordered` order: the same starts give the same attractors, numbered the
    same, for any number of workers and in any command.

    A periodic landing joins the attractor with its period, its cycle of switches and its cycle of
    section points (within ``match``); an aperiodic one joins the aperiodic attractor whose
    points it :func:`interleaving` most, if at least :data:`INTERLEAVED`, and adds its points to
    it.  Then aperiodic attractors whose pooled points interleave are merged (two samples of one
    set that met no common landing on the way)."""
    found: list[Attractor] = []
    members: list[list[int]] = []
    for landing in sorted(landings, key=lambda item: item.index):
        if not landing.ok:
            continue
        k = _joined(landing, found, settings)
        if k is None:
            found.append(Attractor.of_landing(len(found), landing))
            members.append([landing.index])
            continue
        if landing.period:
            found[k] = dataclasses.replace(found[k], starts=found[k].starts + 1)
        else:
            found[k] = _pooled(found[k], landing.points, 1)
        members[k].append(landing.index)
    found, members = _merge_interleaved(found, members)
    return ordered(found, members)


def _joined(landing: Landing, found: list[Attractor], settings: AttractorSettings) -> int | None:
    """The attractor of ``found`` the landing belongs to, or None."""
    if landing.period:
        return next((k for k, a in enumerate(found) if _same_cycle(landing, a, settings)), None)
    scores = [(interleaving(landing.points, a.points), k) for k, a in enumerate(found) if not a.period]
    best = max(scores, default=(0.0, -1))
    return best[1] if best[0] >= INTERLEAVED else None


def _merge_interleaved(found: list[Attractor], members: list[list[int]]) -> tuple[list[Attractor], list[list[int]]]:
    """The aperiodic attractors whose points interleave, merged (the first one keeps the rest)."""
    merged = True
    while merged:
        merged = False
        aperiodic = [k for k, a in enumerate(found) if not a.period]
        for i, j in itertools.combinations(aperiodic, 2):
            if interleaving(found[i].points, found[j].points) >= INTERLEAVED:
                found[i] = _pooled(found[i], found[j].points, found[j].starts)
                members[i] += members[j]
                del found[j], members[j]
                merged = True
                break
    return found, members


def order_key(attractor: Attractor) -> tuple[Any, ...]:
    """What orders attractors, whatever the order the starts met them: periodic ones first by
    period, rests, contacts and cycle of switches, then by their section points; aperiodic ones
    last, by the centre of their points."""
    if attractor.period:
        first = min(tuple(np.round(point, 6)) for point in attractor.points)
        return (0, attractor.period, attractor.rests, attractor.contacts, attractor.signature, first)
    return (
        1,
        0,
        attractor.rests,
        attractor.contacts,
        "",
        tuple(np.round(np.asarray(attractor.points).mean(axis=0), 3)),
    )


def ordered(found: list[Attractor], members: list[list[int]]) -> tuple[list[Attractor], dict[int, int]]:
    """The attractors sorted by :func:`order_key` and numbered from 0, and each member's number."""
    order = sorted(range(len(found)), key=lambda k: order_key(found[k]))
    attractors = [dataclasses.replace(found[k], id=new) for new, k in enumerate(order)]
    labels = {index: new for new, k in enumerate(order) for index in members[k]}
    return attractors, labels


def unsettled(attractors: Sequence[Attractor]) -> list[str]:
    """Warnings where the grouping of aperiodic sets is not settled: two sets kept apart whose
    points interleave more than :data:`UNSETTLED` (they may be one attractor, sampled too thinly)."""
    aperiodic = [a for a in attractors if not a.period]
    said = []
    for a, b in itertools.combinations(aperiodic, 2):
        score = interleaving(a.points, b.points)
        if score >= UNSETTLED:
            said.append(
                f"A{a.id} and A{b.id} may be one aperiodic attractor: their section points interleave "
                f"({score:.2f}; 1 for two samples of one set, 0 for sets apart); record more periods (--record) to "
                "tell"
            )
    return said


def regime_of(attractor: Attractor) -> str:
    """The regime's label: ``P<n>`` (or its :attr:`~Attractor.kind`: ``chaotic``,
    ``quasi-periodic``, ``aperiodic``), then ``m1 rests`` / ``m2 rests`` (a chain's masses by
    name: rest intervals, or at rest throughout) and ``contact`` when they happen."""
    label = f"P{attractor.period}" if attractor.period else attractor.kind
    resting = zip(attractor.masses, attractor.rests, attractor.rest_time, strict=True)
    parts = [label] + [f"{mass} rests" for mass, rate, share in resting if rate or share > 0]
    if attractor.contacts:
        parts.append("contact")
    return " ".join(parts)
