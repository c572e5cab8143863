"""What a result, an orbit or a branch shows of itself in Jupyter (``_repr_html_``; an
analysis's result shows its report's text: :func:`oscillator.report.kinds.html`).

Each is built as the report's blocks (:mod:`oscillator.report.markup`) and written as an HTML
fragment, so that text from a case file (its name, its title) is escaped like everywhere else.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from oscillator.report import markup as mk

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from oscillator.hybrid.result import Result
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.shooting import Orbit

__all__ = ["branch_html", "orbit_html", "result_html"]

#: Events shown in a notebook; the rest are counted.
SHOWN_EVENTS = 8
_EVENT_COLUMNS = ("t", "mass", "kind", "boundary", "from_domain", "to_domain", "theorem")


def _events_table(events: pd.DataFrame) -> list[mk.Block]:
    if events.empty:
        return [mk.Paragraph(("no switching events",))]
    head = events.head(SHOWN_EVENTS)
    rows = tuple(
        tuple(f"{value:.10g}" if isinstance(value, float) else str(value) for value in row)
        for row in head[list(_EVENT_COLUMNS)].itertuples(index=False)
    )
    blocks: list[mk.Block] = [mk.Table(_EVENT_COLUMNS, rows)]
    if len(events) > SHOWN_EVENTS:
        blocks.append(mk.Paragraph((f"… and {len(events) - SHOWN_EVENTS} more events (.events holds them all)",)))
    return blocks


def _heading(name: str, title: str) -> mk.Heading:
    return mk.Heading(4, (mk.Span(name, "strong"), f": {title}" if title else ""))


def result_html(result: Result) -> str:
    case, energy, stats = result.case, result.energy, result.stats
    t_final = result.final_state[0]
    status: list[mk.Inline] = [
        mk.Span(str(result.status), "strong"),
        f" at t = {t_final:.10g} s (from {case.initial.t0:g} s)",
    ]
    if result.message:
        status.append(f": {result.message}")
    facts = (
        f"{stats.events} switching events, {stats.returns} solver returns, engine {stats.engine}; "
        f"energy audit residual {energy.residual:.2e} J (E0 = {energy.E0:.6g} J, E1 = {energy.E1:.6g} J)"
    )
    blocks: list[mk.Block] = [_heading(case.name, case.full_title), mk.Paragraph(tuple(status)), mk.Paragraph((facts,))]
    return mk.html_fragment([*blocks, *_events_table(result.events)])


def orbit_html(orbit: Orbit) -> str:
    case = orbit.case
    state = ", ".join(f"{name} = {value:.10g}" for name, value in zip(case.system.state, orbit.state, strict=True))
    header = ("multiplier", "modulus")
    rows = tuple((f"{mu.real:+.6e} {mu.imag:+.6e}i", f"{abs(mu):.6e}") for mu in orbit.multipliers)
    found = (
        f" at the section t = {orbit.section:.10g} s: {state}; residual {orbit.residual:.1e} after "
        f"{orbit.iterations} Newton step(s)"
    )
    blocks: list[mk.Block] = [
        _heading(case.name, case.full_title),
        mk.Paragraph((mk.Span(f"period-{orbit.period} orbit", "strong"), found)),
        mk.Paragraph((mk.Span(orbit.verdict, "em"),)),
        mk.Table(header, rows),
    ]
    if orbit.note:
        blocks.append(mk.Paragraph((f"note: {orbit.note}",)))
    return mk.html_fragment([*blocks, *_events_table(orbit.events)])


def branch_html(branch: Branch) -> str:
    points, rows, param = branch.points, branch.bifurcations, branch.param
    values = points[param].to_numpy(float)
    increasing = values[-1] > values[0]
    ended = "complete" if branch.complete else f"ended early: {branch.message}"
    summary = (
        f"{len(points)} points, traced from {param} = {values[0]:.10g} {'up' if increasing else 'down'} to "
        f"{values[-1]:.10g} (period {branch.period}, section t = {branch.section:.10g} s); {ended}"
    )
    blocks: list[mk.Block] = [mk.Paragraph((mk.Span(f"branch in {param}", "strong"), ": ", summary))]
    if len(rows):
        table = tuple(
            (
                f"{row[param]:.10g}",
                str(row.kind),
                *((str(row.before), str(row.after)) if increasing else (str(row.after), str(row.before))),
            )
            for _, row in rows.iterrows()
        )
        header = (param, f"kind (as {param} increases)", f"events at lower {param}", f"events at higher {param}")
        blocks.append(mk.Table(header, table))
    else:
        blocks.append(mk.Paragraph(("no bifurcation located",)))
    return mk.html_fragment(blocks)
