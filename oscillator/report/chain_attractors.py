"""A declared system's basins as ``oscillator basins FILE`` writes them: the cells' table, the
attractors' table (each with its orbit's multipliers, exponent and measures, each mass's rests by
name), the figure and the report; every text from the system file escaped by the markup."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from oscillator.attractors.chain_attractors import ChainBasins, chain_columns
from oscillator.attractors.finding import share_text
from oscillator.io.chains import chain_to_toml
from oscillator.io.files import atomic_path
from oscillator.report import markup as mk
from oscillator.report.attractors import attractor_rows, basins_figure, failed_rows
from oscillator.report.outputs import write_folder

__all__ = ["chain_attractor_table", "write_chain_basins"]


def chain_attractor_table(basins: ChainBasins) -> pd.DataFrame:
    """One row per attractor: ``attractor, name, kind, period, signature, starts, fraction, low,
    high, stable, largest_multiplier, lyapunov``, each mass's ``rests:<mass>`` and
    ``rest_time:<mass>``, the refined orbit's measures (``x_pp:<mass>``, ``stuck:<element>``, ...),
    its section ``points`` (JSON) and ``note``; a ``failed`` row for the starts that failed."""
    found = basins.found
    rows = []
    for attractor, row in attractor_rows(found.attractors, found.fractions()):
        rows.append(row | chain_columns(attractor))
    rows += failed_rows(found.fractions())
    return pd.DataFrame(rows)


def cells_table(basins: ChainBasins) -> pd.DataFrame:
    """One row per cell: the two axes' values, the attractor, the run's period, status, reason
    and message."""
    labels = basins.found.labels
    frame = pd.DataFrame({basins.x.name: labels[basins.x.name], basins.y.name: labels[basins.y.name]})
    for column in ("attractor", "period", "status", "reason", "message"):
        frame[column] = labels[column]
    return frame


def _blocks(basins: ChainBasins, table: pd.DataFrame) -> list[mk.Block]:
    chain, x, y, settings = basins.found.chain, basins.x, basins.y, basins.found.settings
    rows = tuple(
        (
            str(row["name"]),
            str(row["kind"]),
            f"{row['starts']}",
            share_text(row["fraction"], row["low"], row["high"]),
            "" if pd.isna(row.get("stable")) else ("stable" if row["stable"] else "unstable"),
            "" if pd.isna(row.get("largest_multiplier")) else f"{row['largest_multiplier']:.4g}",
            "" if pd.isna(row.get("signature")) else str(row["signature"]),
        )
        for row in table.to_dict("records")
    )
    text = (
        f"{x.count} x {y.count} starts at t0 = {chain.t0:g} s, {x.name} from {x.low:g} to {x.high:g} and {y.name} "
        f"from {y.low:g} to {y.high:g}, the other coordinates at the system's start; each run until its section "
        f"points repeat (at most {settings.transient} forcing periods), then {settings.record} recorded. "
        f"{len(basins.found.attractors)} attractor(s) found."
    )
    blocks: list[mk.Block] = [mk.Heading(1, (f"{chain.title or 'friction chain'}: basins of attraction",))]
    blocks.append(mk.Paragraph((text,)))
    blocks += [mk.Paragraph((f"Warning: {warning}.",)) for warning in basins.found.warnings]
    header = ("attractor", "kind", "starts", "share [95% interval]", "orbit", "largest |multiplier|", "switches")
    caption = "the basins; the markers are each attractor's own section points, projected on the slice's plane"
    return [*blocks, mk.Table(header, rows), mk.Figure("basins", caption)]


def write_chain_basins(basins: ChainBasins, folder: Path, *, plots: bool = True) -> list[str]:
    """``basins.parquet`` (the cells), ``attractors.parquet``, ``system.toml``,
    ``figures/basins.png`` and the report into the basins folder (each file atomically); what
    could not be drawn (the tables are written first)."""
    table = chain_attractor_table(basins)
    with atomic_path(folder / "system.toml") as temporary:
        temporary.write_text(chain_to_toml(basins.found.chain), encoding="utf-8")
    figures = [("basins", lambda: basins_figure(basins))] if plots else []
    title = f"{basins.found.chain.title or 'friction chain'}: basins of attraction"
    tables = {"basins": cells_table(basins), "attractors": table}
    return write_folder(folder, tables, figures, _blocks(basins, table), title)
