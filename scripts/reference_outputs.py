"""Small outputs of every global analysis, saved into a folder, and two such folders compared.

    python scripts/reference_outputs.py save FOLDER       # compute and save
    python scripts/reference_outputs.py save FOLDER full  # every transient run whole (issue 37)
    python scripts/reference_outputs.py compare A B       # equal by value (1e-12)?

Used to show that a refactoring leaves results unchanged: save at the commit before, save at the
commit after, compare.  About two minutes on two cores.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

CASE = "instance-1"
QUICK = {"transient": 30, "record": 12, "lyapunov_periods": 40}


def _api() -> dict:
    """The functions, under their names before issue 36 or after it."""
    import importlib

    def find(*places: str):
        for place in places:
            module, name = place.rsplit(".", 1)
            try:
                return getattr(importlib.import_module(module), name)
            except (ImportError, AttributeError):
                continue
        raise ImportError(places[0])

    return {
        "AtlasAxis": find("oscillator.Axis", "oscillator.attractors.atlas.AtlasAxis"),
        "AtlasSettings": find("oscillator.AtlasSettings", "oscillator.attractors.atlas.AtlasSettings"),
        "run_atlas": find("oscillator.regime_atlas", "oscillator.attractors.atlas.run_atlas"),
        "Axis": find("oscillator.Axis", "oscillator.attractors.basins.Axis"),
        "run_basins": find("oscillator.find_basins", "oscillator.attractors.basins.run_basins"),
        "basin_store": find("oscillator.attractors.basins.basin_store"),
    }


def save(folder: Path, full: bool = False) -> None:
    from oscillator import AttractorSettings, SweepSettings, follow_attractors, resolve_case
    from oscillator.analysis.sweeps import read_sweep, run_sweep
    from oscillator.orbits.curves import trace_curve

    api = _api()
    folder.mkdir(parents=True, exist_ok=False)
    case = resolve_case(CASE)
    whole = {"settle": False} if full else {}
    quick = AttractorSettings(**QUICK, **whole)
    x, y = api["AtlasAxis"]("Omega", 1.55, 1.65, 4), api["AtlasAxis"]("Q2", 70.9, 71.2, 3)
    settings = api["AtlasSettings"](
        fresh_transient=20, seed_transient=8, record=8, lyapunov_periods=30, starts=3, **whole
    )
    atlas = api["run_atlas"](case, x, y, settings=settings, workers=2)
    atlas.table.to_parquet(folder / "atlas.parquet")
    x, y = api["AtlasAxis"]("Omega", 1.599, 1.601, 3), api["AtlasAxis"]("Q2", 71.155, 71.175, 3)
    settings = api["AtlasSettings"](
        fresh_transient=60, seed_transient=16, record=16, lyapunov_periods=30, starts=4, **whole
    )
    api["run_atlas"](case, x, y, settings=settings, workers=2).table.to_parquet(folder / "atlas-window.parquet")
    x, y = api["AtlasAxis"]("Omega", 1.45, 1.52, 3), api["AtlasAxis"]("d", 1.5, 1.7, 2)
    settings = api["AtlasSettings"](
        fresh_transient=40, seed_transient=16, record=10, lyapunov_periods=30, starts=2, **whole
    )
    api["run_atlas"](case, x, y, settings=settings, workers=2).table.to_parquet(folder / "atlas-contact.parquet")
    bx, by = api["Axis"]("x2", 2.0, 6.0, 5), api["Axis"]("v2", -3.0, 3.0, 4)
    with tempfile.TemporaryDirectory() as scratch:
        store = api["basin_store"](Path(scratch) / "b", case, bx, by, quick)
        store.check()
        basins = api["run_basins"](case, bx, by, store, settings=quick, workers=2)
    basins.table().to_parquet(folder / "basins.parquet")
    basins.found.fractions().to_parquet(folder / "basins-attractors.parquet")
    starts = [(3.0, 0.0, 4.0, 0.0), (3.0, 0.0, 5.0, 2.0), (3.0, 0.0, 2.5, -1.0)]
    over = follow_attractors(CASE, "Q2", [71.10, 71.165, 71.20], states=starts, settings=quick, tol=1e-3, workers=2)
    over.table().to_parquet(folder / "over.parquet")
    over.ends_table().to_parquet(folder / "over-ends.parquet")
    curve = trace_curve(CASE, kind="sliding", x="Omega", y="Q2", at=(1.6, 71.1577416),
                        window=((1.598, 1.602), (70.98, 71.16)), step=0.15, max_points=5)  # fmt: skip
    curve.points.to_parquet(folder / "curve.parquet")
    sweep = SweepSettings(param="Omega", start=1.55, stop=1.65, steps=5, transient=20, record=10)
    with tempfile.TemporaryDirectory() as scratch:
        run_sweep(case, sweep, Path(scratch) / "s", workers=2)
        for name, table in read_sweep(Path(scratch) / "s").items():
            table.to_parquet(folder / f"sweep-{name}.parquet")


def compare(a: Path, b: Path) -> int:
    bad = 0
    for path in sorted(a.glob("*.parquet")):
        left, right = pd.read_parquet(path), pd.read_parquet(b / path.name)
        common = [c for c in left.columns if c in right.columns and c != "wall_time"]
        extra = sorted(set(right.columns) - set(left.columns))
        same = len(left) == len(right)
        for column in common if same else []:
            x, y = left[column].to_numpy(), right[column].to_numpy()
            if np.issubdtype(x.dtype, np.number) and np.issubdtype(y.dtype, np.number):
                same &= bool(np.allclose(x, y, rtol=1e-12, atol=1e-12, equal_nan=True))
            else:
                same &= bool((left[column].astype(str) == right[column].astype(str)).all())
        missing = sorted(set(left.columns) - set(right.columns))
        print(f"{path.name}: {len(left)} rows, {'equal' if same and not missing else 'DIFFERENT'}"
              + (f"; new columns {extra}" if extra else "") + (f"; missing {missing}" if missing else ""))  # fmt: skip
        bad += not same or bool(missing)
    return bad


if __name__ == "__main__":
    if sys.argv[1] == "save":
        save(Path(sys.argv[2]), full=sys.argv[3:] == ["full"])
    else:
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])))
