"""``oscillator report`` on a global analysis's folder: its tables, figures and report written
again from what the folder keeps (the landings; nothing is computed that a finished folder does
not hold), the folder checked as untrusted."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from oscillator.errors import InputError
from oscillator.report.attractors import write_basins
from oscillator.report.global_results import marker_identity
from oscillator.report.outputs import folder_case
from oscillator.report.plane import read_curve, write_atlas, write_curve
from oscillator.text import printable

__all__ = ["rebuild"]


def rebuild(folder: Path) -> tuple[str, list[str]] | None:
    """Rebuild the tables, figures and report of a finished basins, atlas or curve folder from
    what it keeps (for ``oscillator report``): what was rebuilt and what could not be drawn (the
    tables stay), or None for a folder of another kind.  The landings and rows are read back,
    never computed: an unfinished folder is refused (the command that made it resumes it)."""
    if (folder / "curve.json").exists():
        return "the curve (drawn without an atlas)", write_curve(read_curve(folder), folder)
    if (folder / "attractors.json").exists():
        raise InputError(
            f"{printable(str(folder))}: an attractors folder is rebuilt by running the command that made it again with "
            "the same --out: it reads its landings back and computes none",
            field="folder",
        )
    if (folder / "lyapunov.json").exists():
        raise InputError(
            f"{printable(str(folder))}: a Lyapunov folder keeps no state to redraw from; run the same lyapunov "
            "command with a new --out (it takes seconds)",
            field="folder",
        )
    kinds = (("basins.json", "the basins", _rebuild_basins), ("atlas.json", "the atlas", _rebuild_atlas))
    for marker, what, again in kinds:
        if (folder / marker).exists():
            return what, again(folder, marker_identity(folder / marker), folder_case(folder, marker))
    return None


def _plane(folder: Path, identity: dict[str, Any], settings_type: Any, marker: str) -> tuple[Any, Any, Any]:
    """The two axes and the settings a folder's identity holds (``marker`` names it if damaged)."""
    from oscillator.analysis.axes import Axis

    try:
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        return x, y, settings_type(**identity["settings"])
    except (KeyError, TypeError) as error:
        raise InputError(f"{printable(str(folder))}/{marker} is damaged ({error})", field="folder") from None


def _rebuild_basins(folder: Path, identity: dict[str, Any], case: Any) -> list[str]:
    from oscillator.attractors.basins import basin_store, find_basins, grid_starts
    from oscillator.attractors.mapping import AttractorSettings

    x, y, settings = _plane(folder, identity, AttractorSettings, "basins.json")
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


def _rebuild_atlas(folder: Path, identity: dict[str, Any], case: Any) -> list[str]:
    from oscillator.attractors.atlas import AtlasSettings, atlas_store, regime_atlas

    x, y, settings = _plane(folder, identity, AtlasSettings, "atlas.json")
    store = atlas_store(folder, case, x, y, settings)
    store.check()  # this very computation, or refused
    _finished(store, y.count, "rows", batches=True)
    return write_atlas(regime_atlas(case, x, y, settings=settings, store=store), folder)
