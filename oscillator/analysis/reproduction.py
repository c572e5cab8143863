"""Compare a run's switching times with the times a case expects (article and reference)."""

from __future__ import annotations

import math

import pandas as pd

from oscillator.io.cases import Case, ExpectedEvent

__all__ = ["compare", "match_event"]

COMPARISON_COLUMNS = (
    "label",
    "mass",
    "kind",
    "to_domain",
    "article",
    "reference",
    "ours",
    "ours_minus_article",
    "ours_minus_reference",
    "tolerance",
    "reference_tolerance",
    "within_article",
    "within_reference",
    "note",
)


def match_event(events: pd.DataFrame, expected: ExpectedEvent) -> pd.Series | None:
    """The simulated event of the same mass, kind (and domain entered) nearest in time.

    An expected event without a time (neither ``t`` nor ``reference``) expects the event to
    happen: the first one of that mass, kind and domain matches.
    """
    rows = events[(events["mass"] == expected.mass) & (events["kind"] == str(expected.kind))]
    if expected.to_domain is not None:
        rows = rows[rows["to_domain"] == expected.to_domain]
    if rows.empty:
        return None
    when = expected.t if expected.t is not None else expected.reference
    if when is None:
        return rows.iloc[0]
    return rows.loc[(rows["t"] - when).abs().idxmin()]


def compare(case: Case, events: pd.DataFrame) -> pd.DataFrame:
    """One row per expected event: the article's, the reference's and our time, and verdicts.

    ``within_article`` is true where the article gives no time; ``within_reference`` where the
    case gives no reference.  A missing simulated event leaves ``ours`` NaN and both verdicts
    false.
    """
    rows = []
    for expected in case.expected:
        match = match_event(events, expected)
        ours = math.nan if match is None else float(match["t"])
        article = math.nan if expected.t is None else expected.t
        reference = math.nan if expected.reference is None else expected.reference
        found = match is not None
        rows.append(
            {
                "label": expected.label,
                "mass": expected.mass,
                "kind": str(expected.kind),
                "to_domain": expected.to_domain,
                "article": article,
                "reference": reference,
                "ours": ours,
                "ours_minus_article": ours - article,
                "ours_minus_reference": ours - reference,
                "tolerance": expected.tolerance,
                "reference_tolerance": expected.reference_tolerance,
                "within_article": found and (expected.t is None or abs(ours - article) <= expected.tolerance),
                "within_reference": found
                and (expected.reference is None or abs(ours - reference) <= expected.reference_tolerance),
                "note": " ".join(expected.note.split()),
            }
        )
    return pd.DataFrame(rows, columns=list(COMPARISON_COLUMNS))


def _time(value: float, digits: int = 4) -> str:
    return "—" if math.isnan(value) else f"{value:.{digits}f}"


def _summary(tables: dict[str, pd.DataFrame]) -> str:
    """What matches, in one sentence, from the comparison tables of the cases."""
    rows = pd.concat([table.assign(label=name + ", " + table.label) for name, table in tables.items()],
                     ignore_index=True)  # fmt: skip
    articles = rows[rows.article.notna()]
    close = (articles.ours_minus_article.abs() <= 1e-3).sum()
    far = articles[articles.ours_minus_article.abs() > 1e-3]
    references = rows[rows.reference.notna()]
    equal = (references.ours.round(4) == references.reference).sum()
    differs = references[references.ours.round(4) != references.reference]
    text = (
        f"Of the {len(articles)} times the article gives, {close} are within 1e-3 s of ours"
        + "".join(f"; {row.label} differs by {abs(row.ours_minus_article):.1e} s" for row in far.itertuples())
        + f". Of the {len(references)} reference times, {equal} equal ours rounded to their 4 decimals"
        + "".join(f"; {row.label} differs by {abs(row.ours_minus_reference):.1e} s" for row in differs.itertuples())
        + "."
    )
    return text


def render_markdown(names: list[str]) -> str:
    """The reproduction page: for each case, the article's, the reference's and our times.

    Generated from the case files by ``scripts/reproduction.py``; never edited by hand.
    """
    from oscillator.hybrid.simulate import simulate
    from oscillator.io.cases import load_case
    from oscillator.model.parameters import SolverOptions
    from oscillator.report.markup import Heading, Paragraph, Span, Table, to_markdown

    defaults = SolverOptions()
    blocks: list = [Heading(1, ("Reproduction of the article's switching times",))]
    sections: list = []
    tables = {}
    for name in names:
        case = load_case(name)
        result = simulate(case, record_trajectory=False)
        table = compare(case, result.events)
        tables[name] = table
        rows = []
        for row in table.itertuples(index=False):
            mark_a = "" if math.isnan(row.article) else (" ✓" if row.within_article else " ✗")
            mark_r = "" if math.isnan(row.reference) else (" ✓" if row.within_reference else " ✗")
            deltas = (f"{_signed(row.ours_minus_article)}{mark_a}", f"{_signed(row.ours_minus_reference)}{mark_r}")
            rows.append((row.label, _time(row.article), _time(row.reference), _time(row.ours, 6), *deltas))
        sections += [
            Heading(2, (f"{name}: {case.title}",)),
            Table(("event", "article", "reference", "ours", "ours − article", "ours − reference"), tuple(rows)),
        ]
        for row in table.itertuples(index=False):
            if row.note:
                tolerances = (f" (tolerance {row.tolerance:g} s vs article, {row.reference_tolerance:g} s vs "
                              f"reference): {row.note}")  # fmt: skip
                sections.append(Paragraph((Span(row.label, "em"), tolerances)))
        energy = result.energy
        sections.append(Paragraph((
            f"Events: {len(result.events)}; energy-audit residual below {_bound(energy.residual)} J "
            f"(E0 = {energy.E0:.4f} J, E1 = {energy.E1:.4f} J).",
        )))  # fmt: skip
    blocks += [
        Paragraph((
            "Generated by ", Span("python scripts/reproduction.py", "code"), " from the case files in ",
            Span("cases/", "code"), "; do not edit. Times in s. ", Span("article", "em"),
            ": the article's text; ", Span("reference", "em"),
            ": an independent implementation at tolerance 1e-12, rounded to 4 decimals (docs/model.md, Sec. 9); ",
            Span("ours", "em"), f": oscillator.simulate with default settings (rtol = {defaults.rtol:g}, "
            f"atol = {defaults.atol:g}). A check mark means within the row's tolerance of that column.",
        )),
        Paragraph((_summary(tables),)),
    ]  # fmt: skip
    return to_markdown(blocks + sections)


def _signed(value: float) -> str:
    return "—" if math.isnan(value) else f"{value:+.1e}"


def _bound(value: float) -> str:
    """The next power of ten above ``|value|`` (stable across machines, unlike the digits)."""
    return f"1e{math.ceil(math.log10(abs(value))) if value else -16}"
