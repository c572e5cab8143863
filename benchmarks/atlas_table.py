"""The atlas's table from its points' attractors (issue 56): one DataFrame for all of them against
one per point (the code before, kept here as the baseline), in one run on the same attractors.

Computes a small atlas of Instance 1 (8 x 6 points, 1 start), takes what its points found, repeats
it to 80 x 60 points (the default atlas's size) and times ``oscillator.attractors.atlas._table``
against the per-point frames; checks that both give the same table.

Usage: python benchmarks/atlas_table.py
"""

import dataclasses
import datetime
import time
from typing import Any

import pandas as pd

import oscillator.attractors.atlas as atlas_module
from oscillator import Axis, load_case
from oscillator.attractors.atlas import AtlasSettings, columns_of, regime_atlas
from oscillator.attractors.features import MEASURES
from oscillator.attractors.grouping import regime_of


def per_point_frames(continued: Any, columns: int, system: Any) -> pd.DataFrame:
    """The table as it was built before: a frame per point, converted, then concatenated."""
    types = columns_of(system)
    rests = [name for name in types if name.startswith("rests")]
    parts = []
    for k, (found, ids) in enumerate(zip(continued.found, continued.ids, strict=True)):
        row, column = divmod(k, columns)
        if not found.attractors:
            parts.append(pd.DataFrame([atlas_module._failed(row, column, "every start failed", types)]).astype(types))
            continue
        rows = [
            {"row": row, "column": column, "attractor": a.id, "attractor_id": ids[a.id],
             "coexisting": len(found.attractors), "regime": regime_of(a), "period": a.period,
             **dict(zip(rests, a.rests, strict=True)), "contacts": a.contacts,
             **{name: a.measures.get(name, float("nan")) for name in MEASURES}, "lyapunov": a.lyapunov,
             "starts": a.starts, "status": "ok", "message": "",
             **dict(zip(system.system.state, (float(v) for v in a.points[-1]), strict=True))}
            for a in found.attractors
        ]  # fmt: skip
        parts.append(pd.DataFrame(rows).astype(types))
    return pd.concat(parts, ignore_index=True)


def main() -> None:
    case = load_case("instance-1")
    captured: dict[str, Any] = {}
    original = atlas_module._table

    def capture(continued: Any, columns: int, responses: Any, system: Any) -> pd.DataFrame:
        captured["continued"] = continued
        return original(continued, columns, responses, system)

    atlas_module._table = capture
    try:
        settings = AtlasSettings(starts=1, fresh_transient=20, record=8)
        regime_atlas(case, Axis("Omega", 1.3, 1.85, 8), Axis("Q2", 68.5, 72.0, 6), settings=settings, workers=1)
    finally:
        atlas_module._table = original
    small = captured["continued"]
    repeat = 4800 // len(small.found)
    big = dataclasses.replace(small, found=tuple(small.found) * repeat, ids=tuple(small.ids) * repeat)
    timings: dict[str, float] = {}
    tables = {}
    for name, build in (
        ("one frame (now)", lambda: original(big, 80, (), case)),
        ("a frame per point (before)", lambda: per_point_frames(big, 80, case)),
    ):
        started = time.perf_counter()
        tables[name] = build()
        timings[name] = time.perf_counter() - started
    same = tables["one frame (now)"].equals(tables["a frame per point (before)"])
    print(f"atlas table of {len(big.found)} points, {len(tables['one frame (now)'])} rows "
          f"({datetime.date.today()}); the same table: {same}")  # fmt: skip
    for name, seconds in timings.items():
        print(f"  {name:<28} {seconds:8.3f} s")
    print(f"  ratio: {timings['a frame per point (before)'] / timings['one frame (now)']:.1f}x")


if __name__ == "__main__":
    main()
