"""The regime atlas: what the machine does at every point of a plane of two parameters.

The global continuation of :mod:`~oscillator.attractors.continuing` over a plane, row after row:
at each point ``(x, y)`` the attractors are found from a few starts, the case's own start and
``starts - 1`` more around it (*fresh* starts, with the longer transient) and *seeds*: the
attractors found at the three nearest points of the row before, one per regime
(:class:`~oscillator.attractors.seeding.OnePerRegime`; their last section points, with a short
transient, since they start close to an attractor).  Each point depends only on the row before,
so the atlas is the same for any number of workers.  Each attractor keeps its identity across the
plane (``attractor_id``: matched to the point below, in the first row to the point on its left,
by :class:`~oscillator.attractors.matching.NearestSame`), so that which attractor continues which,
and where one is born or dies, can be read off the table.

For each attractor of a point the atlas keeps its period, rest intervals of each mass and
contact onsets per forcing period, its largest Lyapunov exponent and the measures of
:data:`~oscillator.attractors.features.MEASURES` (:class:`~oscillator.attractors.features.Measured`).
Its *regime* is a label built from these (:func:`~oscillator.attractors.grouping.regime_of`:
``P1``, ``P1 m2 rests``, ``P2 contact``, ``chaotic``, ...), and a point where several attractors
coexist keeps each, with their number.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE, Axis, chain_plane, parameter_plane
from oscillator.analysis.execution import Executor
from oscillator.analysis.store import identity
from oscillator.attractors.chain_attractors import ChainRefined
from oscillator.attractors.continuing import Continued, Mapper, Subject, continue_attractors, plane_points
from oscillator.attractors.features import MEASURES, Measured
from oscillator.attractors.grouping import Attractor, regime_of
from oscillator.attractors.mapping import AttractorSettings
from oscillator.attractors.seeding import OnePerRegime
from oscillator.attractors.store import LandingStore
from oscillator.engines import check_engine
from oscillator.errors import InputError
from oscillator.io.cases import Case
from oscillator.model.chain_fields import state_of
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import check_count
from oscillator.orbits.chain_response import measure_names
from oscillator.orbits.spectra import check_cutoff
from oscillator.presenting import Presented, presenter
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = [
    "COLUMNS",
    "Atlas",
    "AtlasSettings",
    "atlas_settings",
    "atlas_store",
    "check_measures",
    "columns_of",
    "fresh_starts",
    "measures_of",
    "regime_atlas",
]


def _columns(rests: Sequence[str], measures: Sequence[str], state: Sequence[str]) -> dict[str, str]:
    """An atlas table's columns and their types: each mass's rests, the fixed measures, the state."""
    return {
        "row": "int64",
        "column": "int64",
        "attractor": "int64",
        "attractor_id": "int64",
        "coexisting": "int64",
        "regime": "str",
        "period": "int64",
        **{name: "float64" for name in rests},
        "contacts": "float64",
        **{name: "float64" for name in measures},
        "lyapunov": "float64",
        "starts": "int64",
        "status": "str",
        "message": "str",
        **{name: "float64" for name in state},
    }


#: The article's atlas table's columns and their types.
COLUMNS = _columns(("rests_m1", "rests_m2"), tuple(MEASURES), STATE)


def columns_of(system: Subject) -> dict[str, str]:
    """The columns of an atlas of ``system``: :data:`COLUMNS`, or a chain's (each mass's
    ``rests:<mass>``, its own state; the measures asked for follow)."""
    if isinstance(system, FrictionChain):
        return _columns([f"rests:{m.name}" for m in system.masses], (), system.system.state)
    return COLUMNS


@dataclass(frozen=True)
class AtlasSettings:
    """How each point is computed.

    Attributes
    ----------
    fresh_transient : int
        Forcing periods before recording, for the case's own start.
    seed_transient : int
        The same for a seed from the row before (it starts near an attractor).
    record : int
        Forcing periods recorded (the longest period found is ``record - 1``).
    lyapunov_periods : int
        Periods averaged for an aperiodic attractor's largest exponent.
    starts : int
        Fresh starts at every point (1 to 1000): the case's start, and ``starts - 1`` more
        (:func:`fresh_starts`), so that coexisting attractors are found at a point without a
        seed that reaches them.
    settle : bool
        End each transient once the motion has settled (:class:`~oscillator.attractors.mapping.AttractorSettings`).
    engine : str
        The integrator of the starts (:class:`~oscillator.attractors.mapping.AttractorSettings`):
        ``"dop853"``, compiled whole, or ``"cvode"``, the reference.
    cutoff : float
        The cut-off in Hz of the response measures ``force_above`` and ``a_above``
        (:class:`~oscillator.attractors.mapping.AttractorSettings`).
    """

    fresh_transient: int = 40
    seed_transient: int = 16
    record: int = 10
    lyapunov_periods: int = 100
    starts: int = 1
    settle: bool = True
    engine: str = "dop853"
    cutoff: float = 0.0

    def __post_init__(self) -> None:
        check_engine(self.engine)
        check_cutoff(self.cutoff)
        for name, least in (("fresh_transient", 1), ("seed_transient", 1), ("record", 2), ("lyapunov_periods", 1)):
            check_count(getattr(self, name), name, least, 1_000_000)
        check_count(self.starts, "starts", 1, 1000)
        if not isinstance(self.settle, bool):
            raise InputError(f"settle must be True or False, got {shown(self.settle)}", field="settle")

    def landing(self, transient: int) -> AttractorSettings:
        return AttractorSettings(
            transient=transient,
            record=self.record,
            max_period=self.record - 1,
            lyapunov_periods=0,
            settle=self.settle,
            engine=self.engine,
        )


#: A declared system's transients (its damping is its own: a lightly damped one takes long to
#: settle; each run ends where it has settled).
CHAIN_TRANSIENTS = {"fresh_transient": 200, "seed_transient": 100}


def atlas_settings(system: Subject, **given: Any) -> AtlasSettings:
    """The atlas settings for ``system`` with ``given`` ones: :class:`AtlasSettings`' defaults,
    a declared system's transients :data:`CHAIN_TRANSIENTS`."""
    defaults = CHAIN_TRANSIENTS if isinstance(system, FrictionChain) else {}
    return AtlasSettings(**(defaults | given))


def fresh_starts(case: Subject, count: int) -> np.ndarray:
    """``count`` starts ``(x1, v1, x2, v2)`` (a chain's ``system.state``): the case's own start
    first, then the points of a Halton sequence (unscrambled: the same starts every time) in the
    box centred on it whose half-width in every component is ``max(1, max |start|)`` (in m and
    m/s)."""
    from scipy.stats import qmc

    start = np.array(state_of(case) if isinstance(case, FrictionChain) else case.initial.y, dtype=float)
    if count == 1:
        return start[None, :]
    width = max(1.0, float(np.max(np.abs(start))))
    unit = qmc.Halton(d=len(start), scramble=False).random(count)[1:]  # the first point is the box's corner
    return np.vstack([start, start - width + 2.0 * width * unit])


@dataclass(frozen=True)
class Atlas(Presented):
    """The atlas of a plane: ``table`` has one row per attractor of each point (``row``,
    ``column`` and the two parameters' values first); ``case`` the article's case or a declared
    system; ``cutoff`` (Hz) that of its measures ``force_above`` and ``a_above``."""

    case: Subject
    x: Axis
    y: Axis
    table: pd.DataFrame
    cutoff: float = 0.0

    def plot(self, by: str = "regime") -> Figure:
        """The plane coloured by ``by``: ``regime``, ``period``, ``coexisting``, ``lyapunov``,
        ``impact_velocity`` or a response measure the atlas was computed with (``measures``:
        its largest value over the attractors), as ``oscillator atlas`` draws it."""
        return presenter().plot_global(self, by=by)

    @property
    def measures(self) -> tuple[str, ...]:
        """The response measures the table has a column for (``regime_atlas``'s ``measures``)."""
        from oscillator.orbits.response import COLUMNS

        known = measure_names(self.case) if isinstance(self.case, FrictionChain) else COLUMNS
        return tuple(name for name in self.table.columns if name in known)

    def grid(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """``(codes, coexisting, regimes)``: at each point the code of its regime (the regime of
        its first attractor; an index into ``regimes``, sorted) and how many attractors coexist,
        both ``(y.count, x.count)``."""
        first = self.table[self.table.attractor <= 0].drop_duplicates(["row", "column"])
        regimes = sorted(first.regime.unique())
        codes = np.full((self.y.count, self.x.count), -1)
        coexisting = np.zeros((self.y.count, self.x.count), dtype=int)
        codes[first.row, first.column] = [regimes.index(r) for r in first.regime]
        coexisting[first.row, first.column] = first.coexisting
        return codes, coexisting, regimes

    def identities(self) -> pd.DataFrame:
        """One row per attractor kept across the plane (``attractor_id``): at how many points it
        was found, the range of each parameter over them (where it was born and where it dies
        within the plane), its periods and its regimes there (``; ``-joined, in order met)."""
        found = self.table[self.table.status == "ok"]
        rows = []
        for ident, points in found.groupby("attractor_id", sort=True):
            row: dict[str, Any] = {"attractor_id": int(ident), "points": len(points)}
            for axis in (self.x, self.y):
                row[f"{axis.name}_low"], row[f"{axis.name}_high"] = points[axis.name].min(), points[axis.name].max()
            row["periods"] = "; ".join(str(p) for p in dict.fromkeys(points.period))
            row["regimes"] = "; ".join(dict.fromkeys(points.regime))
            rows.append(row)
        return pd.DataFrame(rows)


def atlas_store(
    folder: Path, case: Subject, x: Axis, y: Axis, settings: AtlasSettings, measures: Sequence[str] = ()
) -> LandingStore:
    """The resumable folder of this atlas (:class:`~oscillator.attractors.store.LandingStore`);
    the response ``measures`` are part of its identity where there are any."""
    extra = {"measures": list(check_measures(measures, known=measures_of(case)))} if measures else {}
    return LandingStore.of(folder, "atlas.json", identity(case, x=x, y=y, settings=settings, **extra), case)


def measures_of(system: Subject) -> Sequence[str]:
    """The response measures an atlas of ``system`` can carry: the article's columns, or the
    measures of a chain's orbits."""
    from oscillator.orbits.response import COLUMNS

    return measure_names(system) if isinstance(system, FrictionChain) else COLUMNS


def check_measures(measures: object, field: str = "measures", known: Sequence[str] | None = None) -> tuple[str, ...]:
    """Response measures by column name (:data:`~oscillator.orbits.response.COLUMNS`, or the
    ``known`` names: a chain's), each once; a bad one refused for ``field``."""
    from oscillator.orbits.response import COLUMNS

    known = COLUMNS if known is None else known
    names = (measures,) if isinstance(measures, str) else tuple(measures)  # type: ignore[arg-type]
    for name in names:
        if name not in known:
            raise InputError(
                f"{field}: {shown(name)} is not a response measure; give names of {printable(', '.join(known))}",
                field=field,
            )
    return tuple(dict.fromkeys(names))


def regime_atlas(
    case: Case | FrictionChain,
    x: Axis,
    y: Axis,
    *,
    settings: AtlasSettings | None = None,
    store: LandingStore | None = None,
    workers: int = 1,
    client: Any = None,
    measures: Sequence[str] = (),
    progress: Callable[[int, int], None] | None = None,
) -> Atlas:
    """The atlas over the plane of the parameters ``x`` and ``y``, row by row (each row's points
    in parallel, seeded from the row before).

    Parameters
    ----------
    case : Case or FrictionChain
        The article's case, or a declared system: its axes two of its numbers by name
        (``Omega``, ``platform.F``), its starts run by
        :func:`~oscillator.attractors.chain_attractors.land_chain` on CVODE, each periodic
        attractor refined by Newton (:class:`~oscillator.attractors.chain_attractors.ChainRefined`).
    x, y : Axis
        Two parameters' axes (every corner admitted by the model, else refused before any work).
    settings : AtlasSettings, optional
        :class:`AtlasSettings`' defaults; a declared system's with :data:`CHAIN_TRANSIENTS`.
    store : LandingStore, optional
        Keep each row's landings as it finishes, and read back the rows already there (a run that
        resumes).
    workers, client
        Local processes or a Dask client, as for :func:`~oscillator.attractors.finding.find_attractors`.
    measures : sequence of str
        Response measures (:data:`~oscillator.orbits.response.COLUMNS`: ``x_pp_m2``,
        ``impact_max_right``, ...) each attractor gets as a column, over one return from its last
        section point; an aperiodic one over its recorded points' span, at most
        :data:`~oscillator.attractors.grouping.APERIODIC_PERIODS` periods.  About 20 ms a periodic
        attractor.  A chain's:
        names of :func:`~oscillator.orbits.chain_response.measure_names` (``x_max:blade``,
        ``impact_velocity:wall``), of its refined orbit.
    progress : callable, optional
        ``progress(done, total)`` in points, after every row.
    """
    settings = settings or atlas_settings(case)
    if not isinstance(settings, AtlasSettings):
        raise InputError(f"settings must be an AtlasSettings or None, got {shown(settings)}", field="settings")
    responses = check_measures(measures, known=measures_of(case))
    describe: Callable[[Any, Attractor], Attractor]
    if isinstance(case, FrictionChain):
        case = case.checked()
        x, y = chain_plane(case, x, y)
        describe = ChainRefined(settings.lyapunov_periods)
    else:
        x, y = parameter_plane(case, x, y)
        describe = Measured(settings.lyapunov_periods, responses=responses, cutoff=settings.cutoff)
    executor = Executor(workers, client, progress)
    mapper = Mapper(
        fresh_starts(case, settings.starts),
        settings.landing(settings.fresh_transient),
        settings.landing(settings.seed_transient),
    )
    with executor:
        continued = continue_attractors(
            case,
            plane_points(x, y),
            mapper,
            describe=describe,
            seeding=OnePerRegime(),
            executor=executor,
            store=store,
            progress=progress,
        )
    frame = _table(continued, x.count, responses, case)
    frame.insert(2, x.name, x.values[frame.column.to_numpy()])
    frame.insert(3, y.name, y.values[frame.row.to_numpy()])
    return Atlas(case, x, y, frame, settings.cutoff)


def _table(continued: Continued, columns: int, responses: tuple[str, ...], system: Subject) -> pd.DataFrame:
    """One row per attractor of each point, in the points' order (or one failed row for a point
    where every start failed)."""
    types = columns_of(system)
    rests = [name for name in types if name.startswith("rests")]
    fixed = MEASURES if not isinstance(system, FrictionChain) else ()
    rows: list[dict[str, Any]] = []  # one frame at the end: a frame per point cost 5 ms each (issue 56)
    for k, (found, ids) in enumerate(zip(continued.found, continued.ids, strict=True)):
        row, column = divmod(k, columns)
        if not found.attractors:
            messages = [m for m in found.labels.message if m]
            rows.append(_failed(row, column, messages[0] if messages else "every start failed", types))
            continue
        rows += [
            {
                "row": row,
                "column": column,
                "attractor": a.id,
                "attractor_id": ids[a.id],
                "coexisting": len(found.attractors),
                "regime": regime_of(a),
                "period": a.period,
                **dict(zip(rests, a.rests, strict=True)),
                "contacts": a.contacts,
                **{name: a.measures.get(name, math.nan) for name in fixed},
                "lyapunov": a.lyapunov,
                "starts": a.starts,
                "status": "ok",
                "message": "",
                **dict(zip(system.system.state, (float(v) for v in a.points[-1]), strict=True)),
            }
            for a in found.attractors
        ]
    table = pd.DataFrame(rows, columns=list(rows[0])).astype(types)
    for name in responses:  # after the fixed columns, in the order asked
        by_point = [[a.measures.get(name, math.nan) for a in f.attractors] or [math.nan] for f in continued.found]
        table[name] = np.concatenate([np.asarray(values, dtype=float) for values in by_point])
    return table


def _failed(row: int, column: int, message: str, types: dict[str, str]) -> dict[str, Any]:
    """The row of a point where every start failed."""
    values: dict[str, Any] = {name: (math.nan if kind == "float64" else 0) for name, kind in types.items()}
    values.update(
        row=row, column=column, attractor=-1, attractor_id=-1, regime="failed", status="failed", message=message
    )
    return values
