"""Transition-log reports: the run told as a story, in Markdown and one self-contained HTML file.

The report reads only what a run folder holds (``case.toml``, ``events``, ``trajectory``,
``run.json``, ``figures/``), so ``oscillator report DIR`` rebuilds it without running again.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from oscillator.analysis.intervals import spans
from oscillator.io.cases import Case
from oscillator.io.files import replace_file
from oscillator.model.events import EventKind, one_row_per_event
from oscillator.model.phase_space import domain_label
from oscillator.report.figures import FIGURES
from oscillator.report.markup import Block, Bullets, Figure, Heading, Paragraph, Span, Table, to_html, to_markdown

__all__ = [
    "LOGGED_EVENTS",
    "available_figures",
    "domain_intervals",
    "report_document",
    "transition_log",
    "write_report",
]


def _f(value: float, digits: int = 5) -> str:
    return f"{value:.{digits}g}"


def _sign(value: float) -> str:
    return "< 0" if value < 0 else ("> 0" if value > 0 else "= 0")


def _theorem(row: Any) -> str:
    number = row.equation.strip("()")
    if row.theorem.startswith("Def."):
        return f"{row.theorem}, Eq. {number}"
    return f"Theorem {row.theorem}, Eq. {number}"


def _domain(mass: int, domain: int, boundary: str) -> str:
    return boundary if domain == 0 else f"Ω{domain}({mass})"


def _passes(row: Any, frm: str, to: str, why: str) -> str:
    return (
        f"m{row.mass} passes {row.boundary} from {frm} into {to}: {row.G_alpha} = {_f(row.G0_alpha)} brings it "
        f"to the boundary and {row.G_beta} = {_f(row.G0_beta)} carries it across ({why})"
    )


def _comes_to_rest(row: Any, frm: str, to: str, why: str) -> str:
    return (
        f"m{row.mass} comes to rest on {row.boundary} (sliding): {row.G_alpha} = {_f(row.G0_alpha)} brings it "
        f"to the boundary and {row.G_beta} = {_f(row.G0_beta)} pushes it back ({why})"
    )


def _leaves_rest(row: Any, frm: str, to: str, why: str) -> str:
    how = (
        f"{row.G_alpha} = {_f(row.G0_alpha)} is already past 0"
        if row.branch == "already_past"
        else f"{row.G_alpha} reaches 0 with DF {_sign(row.G1_alpha)}"
    )
    return f"m{row.mass} leaves rest on {row.boundary} into {to}: {how} ({why})"


def _grazes(row: Any, frm: str, to: str, why: str) -> str:
    if row.theorem == "5.5":
        return (
            f"m{row.mass} grazes {row.boundary} in {frm}: {row.G_alpha} = 0 with DF {_sign(row.G1_alpha)}, "
            f"closest |v{row.mass}| = {_f(row.distance)} m/s ({why})"
        )
    return f"m{row.mass} grazes {row.boundary}: {row.G_alpha} = 0 at {_f(row.distance)} m from the stop ({why})"


def _right_contact(row: Any, frm: str, to: str, why: str) -> str:
    verb = "reaches" if EventKind(row.kind).contact_starts else "leaves"
    speed = f"v1 = {_f(row.G0_alpha)} {_sign(row.G0_alpha)}"
    return f"m1 {verb} the right stop on {row.boundary}, {frm} → {to}: {speed} ({why})"


def _left_contact(rows: Sequence[Any]) -> str:
    """A left-contact change moves both masses: one sentence for its rows (one per mass)."""
    row = rows[0]
    moves = ", ".join(
        f"m{r.mass} {_domain(r.mass, r.from_domain, r.boundary)} → {_domain(r.mass, r.to_domain, r.boundary)}"
        for r in rows
    )
    return (
        f"left contact {'starts' if EventKind(row.kind).contact_starts else 'ends'} on {row.boundary} ({moves}): "
        f"ż1 = {_f(row.G0_alpha)} {_sign(row.G0_alpha)} ({_theorem(row)})"
    )


#: The sentence of one mass's event, by kind; a kind that moves both masses at once
#: (:attr:`EventKind.both_masses`) is told once for its rows, by :func:`_left_contact`.
SENTENCES: dict[EventKind, Callable[[Any, str, str, str], str]] = {
    EventKind.PASSABLE: _passes,
    EventKind.SLIDING_ONSET: _comes_to_rest,
    EventKind.SLIDING_VANISH: _leaves_rest,
    EventKind.GRAZING: _grazes,
    EventKind.RIGHT_CONTACT_ONSET: _right_contact,
    EventKind.RIGHT_CONTACT_RELEASE: _right_contact,
}
#: The sentence of the rows of an event of both masses, by kind.
BOTH_MASSES_SENTENCES: dict[EventKind, Callable[[Sequence[Any]], str]] = {
    EventKind.LEFT_CONTACT_ONSET: _left_contact,
    EventKind.LEFT_CONTACT_RELEASE: _left_contact,
}


def _sentence(row: Any) -> str:
    """One event of one mass, in words: what happened and why."""
    to = _domain(row.mass, row.to_domain, row.boundary)
    frm = _domain(row.mass, row.from_domain, row.boundary)
    return SENTENCES[EventKind(row.kind)](row, frm, to, _theorem(row))


def transition_log(events: pd.DataFrame) -> list[str]:
    """One line per event (an event of both masses, a left-contact change, is one line)."""
    lines = []
    rows = list(events.itertuples(index=False))
    i = 0
    while i < len(rows):
        row = rows[i]
        kind = EventKind(row.kind)
        if kind.both_masses:
            pair = [r for r in rows[i : i + 2] if r.kind == row.kind and r.t == row.t]
            text = BOTH_MASSES_SENTENCES[kind](pair)
            i += len(pair)
        else:
            text = _sentence(row)
            i += 1
        lines.append(f"t = {row.t:.4f} s — {text}")
    return lines


#: The most events a report lists one by one; a longer run's log shows the first and the last
#: half of this many, and counts the events between by kind.
LOGGED_EVENTS = 200


def _summarised_log(events: pd.DataFrame) -> list[str]:
    """The transition log, or for a long run its beginning and end and a count of the rest."""
    if len(events) <= LOGGED_EVENTS:
        return transition_log(events)
    half = LOGGED_EVENTS // 2
    middle = events.iloc[half:-half]
    counted = middle[one_row_per_event(middle.kind, middle["mass"])]  # a left-contact change once
    counts = ", ".join(f"{kind} {count:,}" for kind, count in counted.kind.value_counts().items())
    gap = (
        f"… {len(counted):,} events from t = {middle.t.iloc[0]:.4f} s to t = {middle.t.iloc[-1]:.4f} s are not "
        f"listed here ({counts}); events.parquet holds them all"
    )
    return [*transition_log(events.iloc[:half]), gap, *transition_log(events.iloc[-half:])]


def _time_in_each_domain(intervals: pd.DataFrame) -> pd.DataFrame:
    """The intervals summed per mass and domain: how many, how long in all."""
    total = intervals.groupby(["mass", "where"], sort=True).agg(
        intervals=("duration", "size"), duration=("duration", "sum")
    )
    return total.reset_index()


def domain_intervals(events: pd.DataFrame, case: Case, t_final: float) -> pd.DataFrame:
    """The intervals each mass spends in each domain (or resting on a boundary), in order."""
    rows = []
    t0 = case.initial.t0
    for mass in (1, 2):
        mine = events[(events.mass == mass) & (events.from_domain != events.to_domain)]
        if mine.empty:
            continue
        first = mine.iloc[0]
        times = [t0, *mine.t]
        states = [(int(first.from_domain), first.boundary), *zip(mine.to_domain, mine.boundary, strict=True)]
        found = spans(times, states, t_final)
        # a switch at an instant (the start among them) leaves no interval behind it; the last one stays
        rows += [
            (mass, domain, where, a, b)
            for k, ((domain, where), a, b) in enumerate(found)
            if b > a or k == len(found) - 1
        ]
    table = pd.DataFrame(rows, columns=["mass", "domain", "boundary", "from", "to"])
    table["duration"] = table["to"] - table["from"]
    table["where"] = [
        f"resting on {b}" if d == 0 else domain_label(m, d, left=False)
        for m, d, b in zip(table["mass"], table["domain"], table["boundary"], strict=True)
    ]
    return table[["mass", "where", "from", "to", "duration"]]


def _table(run: dict[str, Any], key: str) -> dict[str, Any]:
    """A table of ``run.json``, or an empty one where it holds something else."""
    value = run.get(key)
    return value if isinstance(value, dict) else {}


def _tick(value: bool) -> str:
    return "✓" if value else "✗"


def _cells(frame: pd.DataFrame, formats: dict[str, Any] | None = None) -> Table:
    """A table block of a frame: floats to 4 decimals (NaN as a dash), other values as text."""
    formats = formats or {}
    rows = []
    for row in frame.itertuples(index=False):
        cells = []
        for column, value in zip(frame.columns, row, strict=True):
            if column in formats:
                cells.append(formats[column](value))
            elif isinstance(value, float):
                cells.append("—" if math.isnan(value) else f"{value:.4f}")
            else:
                cells.append(str(value))
        rows.append(tuple(cells))
    return Table(tuple(str(c) for c in frame.columns), tuple(rows))


def _number(value: object, spec: str) -> str:
    """A number from ``run.json`` formatted, or a dash for anything else."""
    return format(value, spec) if isinstance(value, (int, float)) and not isinstance(value, bool) else "—"


def _header(case: Case, run: dict[str, Any]) -> list[Block]:
    """Title, description, the reason a run is incomplete, and the start and the system in one line."""
    p, start = case.parameters, case.initial
    t_final = _number(run.get("t_final", case.t_end), ".10g")
    blocks: list[Block] = [Heading(1, (f"{case.name}: {case.title}" if case.title else case.name,))]
    if case.description:
        blocks.append(Paragraph((case.description,)))
    modified = run.get("modified")
    if modified and isinstance(modified, list):
        changes = ", ".join(str(change) for change in modified)
        blocks.append(
            Paragraph(
                (
                    Span("Modified case:", "strong"),
                    f" {changes}. The expected times of the case as written (the article's) do not apply to it "
                    f"and are not compared.",
                )
            )
        )
    status = run.get("status", "complete")
    if status != "complete":
        reason = run.get("failure") or "no reason recorded"
        headline = f"Incomplete run ({status}) at t = {t_final} s, before t_end = {case.t_end:.10g} s:"
        blocks.append(Paragraph((Span(headline, "strong"), f" {reason}")))
    where = (
        f"Start t0 = {start.t0:.10g} s at x1 = {start.x1:.10g} m, v1 = {start.v1:.10g} m/s, "
        f"x2 = {start.x2:.10g} m, v2 = {start.v2:.10g} m/s; run to {t_final} s. "
    )
    system = (
        f"Forcing Q1 = {_f(p.Q1)} N, Q2 = {_f(p.Q2)} N at Ω = {_f(p.Omega)} rad/s (period {_f(p.period)} s); "
        f"friction μk = {p.mu_k:g}, μs = {p.mu_s:g}; stops at d = {p.d:g} m (left, z1 = −d) and "
        f"d1 = {p.d1:g} m (right, x1 = d1)."
    )
    return [*blocks, Paragraph((where + system,))]


def _energy(energy: dict[str, Any]) -> list[Block]:
    g = {key: _number(energy.get(key), ".6f") for key in ("E0", "E1", "forcing", "feedback", "damping", "friction")}
    balance = "Change of mechanical energy = forcing work + feedback work − damper losses − friction losses:"
    return [
        Heading(2, ("Energy audit",)),
        Paragraph((balance,)),
        Bullets(
            (
                (f"E(t0) = {g['E0']} J, E(t_end) = {g['E1']} J",),
                (
                    f"forcing {g['forcing']} J, feedback {g['feedback']} J, dampers −{g['damping']} J, "
                    f"friction −{g['friction']} J",
                ),
                (f"residual {_number(energy.get('residual'), '.2e')} J",),
            )
        ),
    ]


def _comparison(comparison: pd.DataFrame) -> list[Block]:
    table = comparison[["label", "article", "reference", "ours", "within_article", "within_reference"]]
    ok = bool((comparison.within_article & comparison.within_reference).all())
    verdict = (
        ("All expected times are within tolerance.",)
        if ok
        else (Span("Some expected times are out of tolerance.", "strong"),)
    )
    legend = (
        Span("article", "em"),
        ": the article's time; ",
        Span("reference", "em"),
        ": an independent implementation, to 4 decimals (docs/model.md, Sec. 9).",
    )
    blocks: list[Block] = [
        Heading(2, ("Comparison with the article",)),
        Paragraph(legend),
        _cells(table, dict.fromkeys(("within_article", "within_reference"), _tick)),
        Paragraph(verdict),
    ]
    return blocks + [Paragraph((Span(row.label, "em"), f": {row.note}")) for row in comparison.itertuples() if row.note]


def _counts(run: dict[str, Any], counts: dict[str, Any]) -> list[Block]:
    versions = _table(run, "versions")
    n = {key: _number(counts.get(key), "d") for key in ("events", "returns", "rhs_evaluations", "restarts")}
    text = (
        f"{n['events']} events, {n['returns']} solver returns, {n['rhs_evaluations']} right-hand-side evaluations, "
        f"{n['restarts']} restarts; wall time {_number(run.get('wall_time'), '.3f')} s; "
        f"oscillator {versions.get('oscillator', '?')}."
    )
    return [Heading(2, ("Run",)), Paragraph((text,))]


def report_document(
    case: Case,
    events: pd.DataFrame,
    run: dict[str, Any],
    *,
    comparison: pd.DataFrame | None = None,
    figures: Sequence[str] = (),
) -> list[Block]:
    """The transition-log report of a run as a document (see :mod:`oscillator.report.markup`).

    ``figures`` names the figure files (of :data:`~oscillator.report.figures.FIGURES`) that the run
    folder holds; only those are shown.
    """
    blocks = _header(case, run)
    blocks.append(Heading(2, ("Transition log",)))
    if case.keep_events_from is not None and math.isfinite(case.keep_events_from):
        blocks.append(
            Paragraph(
                (
                    f"Only the events at or after t = {case.keep_events_from:.10g} s were kept "
                    "(keep_events_from); the log and the times below start there.",
                )
            )
        )
    log = _summarised_log(events)
    none = Paragraph(("No switching event: each mass stays in its domain.",))
    blocks.append(Bullets(tuple((line,) for line in log)) if log else none)
    blocks.append(Heading(2, ("Time in each domain",)))
    intervals = domain_intervals(events, case, run.get("t_final", case.t_end))
    if len(intervals) > LOGGED_EVENTS:
        blocks.append(Paragraph((f"{len(intervals):,} intervals; in all, per mass and domain:",)))
        blocks.append(_cells(_time_in_each_domain(intervals)))
    else:
        blocks.append(Paragraph(("No domain change.",)) if intervals.empty else _cells(intervals))
    if run.get("energy"):
        blocks += _energy(run["energy"])
    if comparison is not None and not comparison.empty:
        blocks += _comparison(comparison)
    if figures:
        blocks.append(Heading(2, ("Figures",)))
        drawn = _table(run, "figures")
        if drawn.get("label"):
            blocks.append(Paragraph((f"The figures show {drawn['label']}.",)))
        blocks += [Figure(name, FIGURES[name]) for name in FIGURES if name in figures]
    if run.get("counts"):
        blocks += _counts(run, run["counts"])
    return blocks


def available_figures(folder: Path) -> list[str]:
    """The figures of :data:`~oscillator.report.figures.FIGURES` whose PNG the run folder holds."""
    return [name for name in FIGURES if (folder / "figures" / f"{name}.png").is_file()]


def write_report(folder: Path, blocks: list[Block]) -> None:
    """Write ``report.md`` and the self-contained ``report.html`` into a run folder, atomically."""
    first = blocks[0] if blocks else None
    title = (
        "".join(p if isinstance(p, str) else p.text for p in first.content) if isinstance(first, Heading) else "report"
    )
    replace_file(folder / "report.md", to_markdown(blocks))
    replace_file(folder / "report.html", to_html(blocks, folder=folder, title=title))
