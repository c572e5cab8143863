"""Transition-log reports: the run told as a story, in Markdown and one self-contained HTML file.

The report reads only what a run folder holds (``case.toml``, ``events``, ``trajectory``,
``run.json``, ``figures/``), so ``oscillator report DIR`` rebuilds it without running again.
"""

from __future__ import annotations

import base64
import html
import math
import re
from pathlib import Path

import markdown
import pandas as pd

from oscillator.cases import Case
from oscillator.phase_space import domain_label
from oscillator.plotting import FIGURES

__all__ = ["domain_intervals", "render_html", "render_markdown", "transition_log"]


def _f(value: float, digits: int = 5) -> str:
    return f"{value:.{digits}g}"


def _sign(value: float) -> str:
    return "< 0" if value < 0 else ("> 0" if value > 0 else "= 0")


def _theorem(row) -> str:
    number = row.equation.strip("()")
    if row.theorem.startswith("Def."):
        return f"{row.theorem}, Eq. {number}"
    return f"Theorem {row.theorem}, Eq. {number}"


def _domain(mass: int, domain: int, boundary: str) -> str:
    return boundary if domain == 0 else f"Ω{domain}({mass})"


def _sentence(row) -> str:
    """One event of one mass, in words: what happened and why."""
    mass, kind = row.mass, row.kind
    to = _domain(mass, row.to_domain, row.boundary)
    frm = _domain(mass, row.from_domain, row.boundary)
    why = _theorem(row)
    if kind == "passable":
        return (
            f"m{mass} passes {row.boundary} from {frm} into {to}: {row.G_alpha} = {_f(row.G0_alpha)} brings it "
            f"to the boundary and {row.G_beta} = {_f(row.G0_beta)} carries it across ({why})"
        )
    if kind == "sliding_onset":
        return (
            f"m{mass} comes to rest on {row.boundary} (sliding): {row.G_alpha} = {_f(row.G0_alpha)} brings it "
            f"to the boundary and {row.G_beta} = {_f(row.G0_beta)} pushes it back ({why})"
        )
    if kind == "sliding_vanish":
        how = (
            f"{row.G_alpha} reaches 0 with DF {_sign(row.G1_alpha)}"
            if abs(row.G0_alpha) <= 1e-6 * (1 + abs(row.G0_beta))
            else f"{row.G_alpha} = {_f(row.G0_alpha)} is already past 0"
        )
        return f"m{mass} leaves rest on {row.boundary} into {to}: {how} ({why})"
    if kind == "grazing":
        if row.theorem == "5.5":
            return (
                f"m{mass} grazes {row.boundary} in {frm}: {row.G_alpha} = 0 with DF {_sign(row.G1_alpha)}, "
                f"closest |v{mass}| = {_f(row.distance)} m/s ({why})"
            )
        return f"m{mass} grazes {row.boundary}: {row.G_alpha} = 0 at {_f(row.distance)} m from the stop ({why})"
    if kind in ("right_contact_onset", "right_contact_release"):
        verb = "reaches" if kind.endswith("onset") else "leaves"
        speed = f"v1 = {_f(row.G0_alpha)} {_sign(row.G0_alpha)}"
        return f"m1 {verb} the right stop on {row.boundary}, {frm} → {to}: {speed} ({why})"
    return ""  # left contact: told for both masses at once, see transition_log


def transition_log(events: pd.DataFrame) -> list[str]:
    """One line per event (a left-contact change, which moves both masses, is one line)."""
    lines = []
    rows = list(events.itertuples(index=False))
    i = 0
    while i < len(rows):
        row = rows[i]
        if row.kind in ("left_contact_onset", "left_contact_release"):
            pair = [r for r in rows[i : i + 2] if r.kind == row.kind and r.t == row.t]
            starts = row.kind.endswith("onset")
            moves = ", ".join(
                f"m{r.mass} {_domain(r.mass, r.from_domain, r.boundary)} → {_domain(r.mass, r.to_domain, r.boundary)}"
                for r in pair
            )
            text = (
                f"left contact {'starts' if starts else 'ends'} on {row.boundary} ({moves}): "
                f"ż1 = {_f(row.G0_alpha)} {_sign(row.G0_alpha)} ({_theorem(row)})"
            )
            i += len(pair)
        else:
            text = _sentence(row)
            i += 1
        lines.append(f"t = {row.t:.4f} s — {text}")
    return lines


def domain_intervals(events: pd.DataFrame, case: Case, t_final: float) -> pd.DataFrame:
    """The intervals each mass spends in each domain (or resting on a boundary), in order."""
    rows = []
    t0 = case.initial.t0
    for mass in (1, 2):
        mine = events[(events.mass == mass) & (events.from_domain != events.to_domain)]
        start, current, where = t0, None, ""
        for row in mine.itertuples(index=False):
            if current is None:
                current, where = row.from_domain, row.boundary
            if row.t > start:  # a switch at the start leaves no interval behind it
                rows.append((mass, current, where, start, row.t))
            start, current, where = row.t, row.to_domain, row.boundary
        if current is None:
            continue
        rows.append((mass, current, where, start, t_final))
    table = pd.DataFrame(rows, columns=["mass", "domain", "boundary", "from", "to"])
    table["duration"] = table["to"] - table["from"]
    table["where"] = [
        f"resting on {b}" if d == 0 else domain_label(m, d, left=False)
        for m, d, b in zip(table["mass"], table["domain"], table["boundary"], strict=True)
    ]
    return table[["mass", "where", "from", "to", "duration"]]


def _tick(value: bool) -> str:
    return "✓" if value else "✗"


def _markdown_table(frame: pd.DataFrame, formats: dict | None = None) -> str:
    formats = formats or {}
    header = "| " + " | ".join(frame.columns) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    body = []
    for row in frame.itertuples(index=False):
        cells = []
        for column, value in zip(frame.columns, row, strict=True):
            if column in formats:
                cells.append(formats[column](value))
            elif isinstance(value, float):
                cells.append("—" if math.isnan(value) else f"{value:.4f}")
            else:
                cells.append(str(value))
        body.append("| " + " | ".join(cells) + " |")
    return "\n".join([header, rule, *body])


def render_markdown(
    case: Case, events: pd.DataFrame, run: dict, *, comparison: pd.DataFrame | None = None, figures: bool = True
) -> str:
    """The transition-log report of a run, in Markdown (figures referenced as files)."""
    p, start = case.parameters, case.initial
    t_final = run.get("t_final", case.t_end)
    lines = [f"# {case.name}: {case.title}" if case.title else f"# {case.name}", ""]
    if case.description:
        lines += [" ".join(case.description.split()), ""]
    status = run.get("status", "complete")
    if status != "complete":
        lines += [
            f"**Incomplete run ({status}) at t = {t_final} s, before t_end = {case.t_end} s:** "
            f"{run.get('failure') or 'no reason recorded'}",
            "",
        ]
    lines += [
        f"Start t0 = {start.t0} s at x1 = {start.x1} m, v1 = {start.v1} m/s, x2 = {start.x2} m, v2 = {start.v2} m/s; "
        f"run to {t_final} s. Forcing Q1 = {_f(p.Q1)} N, Q2 = {_f(p.Q2)} N at Ω = {_f(p.Omega)} rad/s "
        f"(period {_f(p.period)} s); friction μk = {p.mu_k}, μs = {p.mu_s}; stops at d = {p.d} m (left, "
        f"z1 = −d) and d1 = {p.d1} m (right, x1 = d1).",
        "",
        "## Transition log",
        "",
    ]
    log = transition_log(events)
    lines += [f"- {line}" for line in log] if log else ["No switching event: each mass stays in its domain."]
    lines += ["", "## Time in each domain", ""]
    intervals = domain_intervals(events, case, t_final)
    if intervals.empty:
        lines.append("No domain change.")
    else:
        lines.append(_markdown_table(intervals))
    energy = run.get("energy", {})
    if energy:
        lines += [
            "",
            "## Energy audit",
            "",
            "Change of mechanical energy = forcing work + feedback work − damper losses − friction losses:",
            "",
            f"- E(t0) = {energy['E0']:.6f} J, E(t_end) = {energy['E1']:.6f} J",
            f"- forcing {energy['forcing']:+.6f} J, feedback {energy['feedback']:+.6f} J, "
            f"dampers −{energy['damping']:.6f} J, friction −{energy['friction']:.6f} J",
            f"- residual {energy['residual']:.2e} J",
        ]
    if comparison is not None and not comparison.empty:
        shown = comparison[["label", "article", "reference", "ours", "within_article", "within_reference"]]
        ok = bool((comparison.within_article & comparison.within_reference).all())
        lines += [
            "",
            "## Comparison with the article",
            "",
            "*article*: the article's time; *reference*: an independent implementation (MODEL.md Sec. 6).",
            "",
            _markdown_table(shown, dict.fromkeys(("within_article", "within_reference"), _tick)),
            "",
            "All expected times are within tolerance." if ok else "**Some expected times are out of tolerance.**",
        ]
        for row in comparison.itertuples(index=False):
            if row.note:
                lines += ["", f"*{row.label}*: {row.note}"]
    if figures:
        lines += ["", "## Figures", ""]
        for name, caption in FIGURES.items():
            lines += [f"![{caption}](figures/{name}.png)", ""]
    counts = run.get("counts", {})
    if counts:
        lines += [
            "",
            "## Run",
            "",
            f"{counts.get('events', 0)} events, {counts.get('returns', 0)} solver returns, "
            f"{counts.get('rhs_evaluations', 0)} right-hand-side evaluations, {counts.get('restarts', 0)} restarts; "
            f"wall time {run.get('wall_time', float('nan')):.3f} s; "
            f"oscillator {run.get('versions', {}).get('oscillator', '?')}.",
        ]
    return "\n".join(lines) + "\n"


_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem; line-height: 1.45; }
table { border-collapse: collapse; margin: 0.5rem 0; } td, th { border: 1px solid #ccc; padding: 0.2rem 0.5rem; }
th { background: #f3f3f3; } img { max-width: 100%; } li { margin: 0.2rem 0; }
"""


def render_html(markdown_text: str, folder: Path) -> str:
    """One self-contained HTML page: the Markdown rendered, figures embedded as data URIs."""
    body = markdown.markdown(markdown_text, extensions=["tables"])

    def embed(match: re.Match) -> str:
        path = folder / match.group(1)
        if not path.is_file():
            return match.group(0)
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        return f'src="data:image/png;base64,{data}"'

    body = re.sub(r'src="(figures/[^"]+\.png)"', embed, body)
    title = html.escape(markdown_text.splitlines()[0].lstrip("# "))
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{title}</title>'
        f"<style>{_STYLE}</style></head><body>\n{body}\n</body></html>\n"
    )
