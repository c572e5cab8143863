"""``oscillator report`` on a basins or atlas folder: its tables, figures and report written again
from what the folder keeps (the landings; nothing is computed that a finished folder does not
hold), the folder checked as untrusted (:mod:`oscillator.report.kinds` registers them)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from oscillator.errors import InputError
from oscillator.report.attractors import write_basins
from oscillator.report.global_results import marker_identity
from oscillator.report.outputs import folder_case, folder_system
from oscillator.report.plane import write_atlas
from oscillator.text import printable

__all__ = ["rebuild_atlas", "rebuild_basins"]


def _plane(folder: Path, identity: dict[str, Any], settings_type: Any, marker: str) -> tuple[Any, Any, Any]:
    """The two axes and the settings a folder's identity holds (``marker`` names it if damaged)."""
    from oscillator.analysis.axes import Axis

    try:
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        return x, y, settings_type(**identity["settings"])
    except (KeyError, TypeError) as error:
        raise InputError(f"{printable(str(folder))}/{marker} is damaged ({error})", field="folder") from None


def rebuild_basins(folder: Path) -> list[str]:
    """A finished basins folder's tables, figures and report written again (its orbits refined
    again from the landings it keeps); what could not be drawn."""
    from oscillator.attractors.basins import basin_store, find_basins, grid_starts
    from oscillator.attractors.mapping import AttractorSettings

    case = folder_case(folder, "basins.json")
    x, y, settings = _plane(folder, marker_identity(folder / "basins.json"), AttractorSettings, "basins.json")
    store = basin_store(folder, case, x, y, settings)
    store.check()  # this very computation, or refused
    _finished(store, len(grid_starts(case, x, y)), "starts")
    return write_basins(find_basins(case, x, y, store, settings=settings), folder)


def _finished(store: Any, total: int, what: str, *, batches: bool = False) -> None:
    """Refuse a folder whose computation has not finished: ``report`` reads back, never computes."""
    parts = sorted(store.parts.glob("batch-*.parquet" if batches else "*.parquet"))
    done = len(parts) if batches else sum(len(pd.read_parquet(part)) for part in parts)
    if done < total:
        raise InputError(
            f"{printable(str(store.folder))} is not finished ({done} of {total} {what}); run the command that made it "
            "again with the same --out to resume it",
            field="folder",
        )


def rebuild_atlas(folder: Path) -> list[str]:
    """A finished atlas folder's tables, figures and report written again from its rows; what
    could not be drawn."""
    from oscillator.attractors.atlas import AtlasSettings, atlas_store, regime_atlas

    case = folder_system(folder, "atlas.json")
    known = marker_identity(folder / "atlas.json")
    x, y, settings = _plane(folder, known, AtlasSettings, "atlas.json")
    measures = known.get("measures", [])  # the response measures asked for, part of its identity
    store = atlas_store(folder, case, x, y, settings, measures)
    store.check()  # this very computation, or refused
    _finished(store, y.count, "rows", batches=True)
    return write_atlas(regime_atlas(case, x, y, settings=settings, store=store, measures=measures), folder)
