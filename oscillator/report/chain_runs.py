"""A friction chain's run folder: its tables, its system file and ``run.json`` written whole
(then put in place), its figures and report after (their failure keeps the tables).

::

    events.csv / events.parquet   one row per event (the element, the rule, the G-values)
    trajectory.parquet            t, x:<mass>, v:<mass>, z:<slider>, mode:<element>
    energy.csv                    each element's work, stored energy change, dissipation
    system.toml                   the system as run (read back by ``oscillator run``)
    run.json                      how the run ended, the counts, the energy residual
    figures/motion.png, .svg      one panel per mass and per slider
    figures/schematic.png, .svg   the machine
    report.md, report.html        the events and the audit, the figures
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from oscillator.errors import InputError
from oscillator.hybrid.chain_run import ChainResult, chain_records_of
from oscillator.io.chains import chain_to_toml
from oscillator.io.files import FolderClaim
from oscillator.report.markup import Bullets, Figure, Heading, Paragraph, Span, Table, to_html, to_markdown
from oscillator.report.runs import claim_output, finish_or_warn, json_text, run_metadata, write_tables
from oscillator.text import printable

__all__ = ["finish_chain_run", "read_chain_run", "save_chain_result", "write_chain_run"]


def _info(result: ChainResult, command: list[str] | None) -> dict[str, Any]:
    energy = result.energy
    return {
        "kind": "system",
        "title": result.chain.title,
        "status": str(result.status),
        "message": result.message,
        "t0": result.chain.t0,
        "t_end": result.t_end,
        "masses": len(result.chain.masses),
        "elements": len(result.chain.elements),
        "events": len(result.events),
        "energy_residual": energy.residual,
        **run_metadata(command),
    }


def write_chain_run(
    result: ChainResult, claim: FolderClaim, *, formats: str = "both", command: list[str] | None = None
) -> Path:
    """Write the tables, ``system.toml`` and ``run.json`` and put the folder in place; on any
    failure nothing is left behind.  The folder's path."""
    temporary = claim.temporary
    try:
        write_tables(result.events, result.trajectory, temporary, formats)
        result.energy.table.to_csv(temporary / "energy.csv", index=False)
        (temporary / "system.toml").write_text(chain_to_toml(result.chain), encoding="utf-8")
        (temporary / "run.json").write_text(json_text(_info(result, command)), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise


def _report(result: ChainResult) -> list[Any]:
    chain, events, energy = result.chain, result.events, result.energy
    counts = events.groupby(["element", "kind"]).size() if len(events) else None
    blocks: list[Any] = [
        Heading(1, (chain.title or "Friction chain",)),
        Paragraph(
            (
                f"{len(chain.masses)} masses, {len(chain.elements)} elements; from t = {chain.t0:g} s to "
                f"{result.t_end:g} s: {len(events)} events, ",
                Span(str(result.status), "strong"),
                ".",
            )
        ),
        Figure("schematic", "The machine"),
        Figure("motion", "Displacements, velocities and slider forces; grey: stuck, rose: in contact"),
        Heading(2, ("Events",)),
    ]
    if counts is not None:
        blocks.append(Table(("element", "kind", "count"), tuple((e, k, str(n)) for (e, k), n in counts.items())))
        first = events.head(30)
        blocks.append(
            Table(
                ("t (s)", "element", "kind", "theorem", "G0", "G1"),
                tuple(
                    (f"{r.t:.9f}", r.element, r.kind, f"{r.theorem} {r.equations}", f"{r.G0:.6g}", f"{r.G1:.6g}")
                    for r in first.itertuples(index=False)
                ),
            )
        )
    else:
        blocks.append(Paragraph(("No switching event.",)))
    blocks += [
        Heading(2, ("Energy audit",)),
        Bullets(((f"kinetic energy change {energy.kinetic_change:.9g} J; residual {energy.residual:.3e} J",),)),
        Table(
            ("element", "type", "work (J)", "stored (J)", "dissipated (J)"),
            tuple(
                (r.element, r.type, f"{r.work:.9g}", f"{r.stored:.9g}", f"{r.dissipated:.9g}")
                for r in energy.table.itertuples(index=False)
            ),
        ),
    ]
    return blocks


def finish_chain_run(folder: Path, result: ChainResult, *, figures: bool = True, report: bool = True) -> None:
    """The figures and the report of a written run folder."""
    from oscillator.report.chain_figures import motion_figure, schematic_figure
    from oscillator.report.figures import save_figure

    if figures:
        directory = folder / "figures"
        directory.mkdir(exist_ok=True)
        save_figure(schematic_figure(result.chain), directory, "schematic")
        save_figure(motion_figure(result), directory, "motion")
    if report:
        blocks = _report(result)
        (folder / "report.md").write_text(to_markdown(blocks), encoding="utf-8")
        title = result.chain.title or "Friction chain"
        (folder / "report.html").write_text(to_html(blocks, folder=folder, title=title), encoding="utf-8")


def save_chain_result(result: ChainResult, folder: Path | str, *, figures: bool = True, report: bool = True) -> Path:
    """Write ``result`` as ``oscillator run FILE`` does into ``folder``, a new one; a failure of the
    figures or the report keeps the tables (a warning says so)."""
    folder = Path(folder)
    path = write_chain_run(result, claim_output(folder, folder.name), command=["python", "oscillator.ChainResult.save"])
    if figures or report:
        finish_or_warn(lambda: finish_chain_run(path, result, figures=figures, report=report), path)
    return path


def _damaged(folder: Path, what: str) -> InputError:
    return InputError(f"{printable(str(folder))} is damaged: {what}; run the system again", field="DIR")


def read_chain_run(folder: Path) -> ChainResult:
    """A chain's run folder read back (what :func:`write_chain_run` wrote), each table checked."""
    import numpy as np
    import pandas as pd

    from oscillator.hybrid.chain_run import ChainResult, state_columns
    from oscillator.hybrid.result import Status
    from oscillator.io.chains import load_system
    from oscillator.model.chain_rules import ChainEvent

    chain = load_system(folder / "system.toml")
    try:
        info = json.loads((folder / "run.json").read_text(encoding="utf-8"))
        events = pd.read_parquet(folder / "events.parquet") if (folder / "events.parquet").is_file() else None
        events = pd.read_csv(folder / "events.csv", keep_default_na=False) if events is None else events
        trajectory = pd.read_parquet(folder / "trajectory.parquet")
        energy = pd.read_csv(folder / "energy.csv", keep_default_na=False)
    except (OSError, ValueError) as error:
        raise _damaged(folder, f"a table cannot be read ({type(error).__name__})") from None
    if list(events.columns) != list(ChainEvent.columns()):
        raise _damaged(folder, "the event table's columns are not a chain's")
    if not set(state_columns(chain)) <= set(trajectory.columns) or trajectory.empty:
        raise _damaged(folder, "the trajectory lacks the system's columns")
    names = [e.name for e in chain.elements]
    if list(energy.get("element", [])) != names:
        raise _damaged(folder, "energy.csv does not list the system's elements")
    work = dict(zip(names, energy["work"].astype(float), strict=True))
    end = trajectory[list(state_columns(chain))].iloc[-1].to_numpy(dtype=float)
    y_end = np.concatenate([end, np.array([work[name] for name in names])])
    status = Status(info.get("status", "complete")) if info.get("status") in set(Status) else Status.COMPLETE
    t_end = float(info.get("t_end", trajectory.t.iloc[-1]))
    records = chain_records_of(chain, events, trajectory)
    return ChainResult(chain, work, status, str(info.get("message", "")), t_end, y_end, records)
