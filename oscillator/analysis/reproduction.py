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
