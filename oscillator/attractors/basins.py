"""Basins of attraction over a plane of starting states, computed into a folder that resumes.

A slice of the state space: two of ``x1 v1 x2 v2`` on a grid (:class:`~oscillator.analysis.axes.Axis`), the other two
and the section ``t0`` from the case's start.  Every cell's start is run by
:func:`~oscillator.attractors.finding.land`, and the landings are kept in the folder as they
finish (``parts/``: one Parquet file per batch, written atomically), so that a run that was
killed or interrupted resumes with the same command, no start lost or run twice.  When all are
in, they are grouped into attractors exactly as :func:`~oscillator.attractors.finding.find_attractors`
does (in the starts' order, so the result does not depend on the number of workers).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE, Axis, state_plane
from oscillator.analysis.execution import Executor
from oscillator.analysis.store import identity
from oscillator.attractors.finding import Attractors, assemble
from oscillator.attractors.mapping import MAX_STARTS, AttractorSettings, Landing, check_settings, land
from oscillator.attractors.store import LandingStore
from oscillator.errors import InputError
from oscillator.io.cases import Case
from oscillator.model.chains import FrictionChain
from oscillator.presenting import Presented, presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.attractors.chain_attractors import ChainBasins

__all__ = ["Basins", "basin_store", "find_basins", "grid_landings", "grid_starts"]
#: Landings written per part file.
BATCH = 64


def grid_starts(case: Case, x: Axis, y: Axis) -> np.ndarray:
    """The slice's starts, ``(x.count * y.count, 4)``, cell ``(i, j)`` (``i`` along x) at row
    ``j * x.count + i``; the two other components are the case's start."""
    x, y = state_plane(x, y)
    if x.count * y.count > MAX_STARTS:
        raise InputError(
            f"the slice has {x.count} x {y.count} = {x.count * y.count:,} starts, more than {MAX_STARTS:,}; give "
            "fewer cells",
            field="axis",
        )
    starts = np.tile(np.array(case.initial.y, dtype=float), (x.count * y.count, 1))
    xs, ys = np.meshgrid(x.values, y.values)
    starts[:, STATE.index(x.name)] = xs.ravel()
    starts[:, STATE.index(y.name)] = ys.ravel()
    return starts


@dataclass(frozen=True)
class Basins(Presented):
    """The basins of a slice: the attractors, and each cell's attractor.

    Attributes
    ----------
    found : Attractors
        The attractors and the labels of every start (row ``j * x.count + i``).
    x, y : Axis
        The slice's axes.
    """

    found: Attractors
    x: Axis
    y: Axis

    @property
    def grid(self) -> np.ndarray:
        """The attractor of each cell, ``(y.count, x.count)``; -1 where the run failed."""
        labels: np.ndarray = self.found.labels.attractor.to_numpy()
        return labels.reshape(self.y.count, self.x.count)

    def table(self) -> pd.DataFrame:
        """One row per cell: the two axes' values, the attractor, the run's status and reason."""
        labels = self.found.labels
        frame = pd.DataFrame({self.x.name: labels[self.x.name], self.y.name: labels[self.y.name]})
        for column in ("attractor", "period", "status", "reason", "message"):
            frame[column] = labels[column]
        return frame

    def plot(self) -> Figure:
        """The slice coloured by attractor, each attractor's section points on top (as ``oscillator
        basins`` draws it)."""
        return presenter().plot_global(self)


def basin_store(
    folder: Path, case: Case | FrictionChain, x: Axis, y: Axis, settings: AttractorSettings
) -> LandingStore:
    """The resumable folder of these basins (:class:`~oscillator.attractors.store.LandingStore`):
    a case's, or a declared system's (its state and masses its own)."""
    return LandingStore.of(folder, "basins.json", identity(case, x=x, y=y, settings=settings), case)


@overload
def find_basins(
    case: Case,
    x: Axis,
    y: Axis,
    store: LandingStore | None = None,
    *,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> Basins: ...


@overload
def find_basins(
    case: FrictionChain,
    x: Axis,
    y: Axis,
    store: LandingStore | None = None,
    *,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> ChainBasins: ...


def find_basins(
    case: Case | FrictionChain,
    x: Axis,
    y: Axis,
    store: LandingStore | None = None,
    *,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> Basins | ChainBasins:
    """Compute the starts not yet in ``store`` (checked), keep them as they finish, and group all.

    ``progress(done, total)`` after every start.  On an interrupt or an error the landings
    finished so far are in the folder (the batch in hand is written first).  Without a
    ``store`` nothing is kept.  A declared system's basins (over two of its ``system.state``,
    ``Axis("x:blade", -1, 1, 40)``) are :func:`~oscillator.attractors.chain_attractors.find_chain_basins`'s."""
    settings = check_settings(settings)
    if isinstance(case, FrictionChain):
        from oscillator.attractors.chain_attractors import find_chain_basins

        return find_chain_basins(
            case, x, y, store, settings=settings, workers=workers, client=client, progress=progress
        )
    executor = Executor(workers, client, progress)
    starts = grid_starts(case, x, y)
    if store is not None:
        store.open()
    with executor:
        landings = grid_landings(case, settings, starts, store, executor, progress)
        if store is not None:
            store.write_status("computed", starts=len(starts), failed=sum(not item.ok for item in landings))
        return Basins(assemble(case, settings, landings, executor=executor), x, y)


def grid_landings(
    system: Case | FrictionChain,
    settings: AttractorSettings,
    starts: np.ndarray,
    store: LandingStore | None,
    executor: Executor,
    progress: Callable[[int, int], None] | None,
    land_one: Callable[..., Landing] = land,
) -> list[Landing]:
    """Every start's landing (``land_one(system, settings, index, start)``: the article's
    :func:`~oscillator.attractors.mapping.land` or a chain's): those in ``store`` read back, the
    others computed and kept in batches as they finish (the batch in hand written first on an
    interrupt or an error)."""
    landings = [] if store is None else store.read(starts)
    done = {item.index for item in landings}
    tasks = [(index, tuple(row)) for index, row in enumerate(starts) if index not in done]
    total = len(starts)
    if progress is not None:
        progress(len(landings), total)
    pending: list[Landing] = []
    try:
        for landing in executor.map(land_one, tasks, shared=(system, settings)):
            pending.append(landing)
            if len(pending) >= BATCH:
                if store is not None:
                    store.write(pending)
                landings += pending
                pending = []
            if progress is not None:
                progress(len(landings) + len(pending), total)
    finally:
        if store is not None:
            store.write(pending)
    return landings + pending
