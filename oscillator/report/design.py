"""A design's folder: its tables, the figures of the search and of the responses before and after,
and the report (docs/design.md)."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.designing.judging import Judged, Seen, seen_table, survey_task
from oscillator.report import markup as mk
from oscillator.report.orbits import modified_blocks
from oscillator.report.outputs import quantity_label, wrapped_title

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.designing.optimise import Design
    from oscillator.designing.problem import Problem

__all__ = ["band_responses", "design_blocks", "design_figure", "design_plot", "read_design", "write_design"]

#: Band values of the responses drawn before and after.
RESPONSE_VALUES = 21


def band_responses(found: Design, count: int | None = None) -> pd.DataFrame:
    """Every attractor's measures over ``count`` values (default :data:`RESPONSE_VALUES`) across
    the band (and a little beyond) for the global search's best design (``design = "before"``)
    and the design found (``"after"``), landed with the design's settings."""
    problem, settings = found.problem, found.settings
    count = RESPONSE_VALUES if count is None else count
    name, low, high = problem.over
    margin = 0.25 * (high - low)
    values = np.linspace(low - margin, high + margin, count)
    seen: dict[str, list[Seen]] = {"before": [], "after": []}
    for label, judged in (("before", found.start), ("after", found.best)):
        for value in values:
            seen[label] += survey_task(problem, settings, tuple(judged.design), float(value))[0]
    frames = [seen_table(attractors, design=label) for label, attractors in seen.items()]  # one table a design
    return pd.concat(frames, ignore_index=True).rename(columns={"band": name})


def design_figure(found: Design, responses: pd.DataFrame) -> Figure:
    """The objective(s) and each constrained measure against the band's parameter, every attractor,
    before (the global search's best, grey) and after (the design found); the band shaded, each
    constraint's bound dashed."""
    from matplotlib.figure import Figure

    problem = found.problem
    name, low, high = problem.over
    measures = problem.measures  # the objectives, then the constrained measures, each once
    fig = Figure(figsize=(8, 2.8 * len(measures) + 0.6), layout="tight")
    axes = fig.subplots(len(measures), 1, sharex=True, squeeze=False)
    for ax, measure in zip(axes[:, 0], measures, strict=True):
        ax.axvspan(low, high, color="0.92", zorder=0, label="operating band")
        for label, style in (
            ("before", {"color": "0.55", "marker": "x", "s": 18}),
            ("after", {"color": "C0", "marker": "o", "s": 14}),
        ):
            rows = responses[responses.design == label]
            ax.scatter(rows[name], rows[measure], label=f"{label}: {_design_text(found, label)}", **style)
        for constraint in problem.constraints:
            if constraint.measure == measure:
                ax.axhline(
                    constraint.bound, color="C3", linestyle="--", linewidth=1, label=f"bound {constraint.bound:g}"
                )
        ax.set_ylabel(quantity_label(measure))
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="best")
    axes[-1, 0].set_xlabel(quantity_label(name))
    axes[-1, 0].ticklabel_format(useOffset=False, axis="x")
    shown = f"{float(responses[name].min()):g} to {float(responses[name].max()):g}" if len(responses) else "-"
    what = f"the measures judged before and after, {name} from {shown}; the operating band [{low:g}, {high:g}] shaded"
    fig.suptitle(wrapped_title(problem.case, what), fontsize=9)
    return fig


def design_plot(found: Design, figure: str = "search") -> Figure:
    """:meth:`Design.plot`: the figure ``figure`` of ``oscillator design``'s folder."""
    from oscillator.errors import InputError
    from oscillator.text import shown

    if figure == "search":
        return search_figure(found)
    if figure == "response":
        return design_figure(found, band_responses(found))
    if figure == "front" and len(found.front):
        return front_figure(found)
    if figure == "front":
        raise InputError(
            "figure: a design with one objective has no Pareto front; give 'search' or 'response'", field="figure"
        )
    raise InputError(f"figure must be 'search', 'response' or 'front', got {shown(figure)}", field="figure")


def _design_text(found: Design, label: str) -> str:
    judged = found.start if label == "before" else found.best
    return ", ".join(f"{n} = {v:.5g}" for n, v in found.problem.design(judged.design).items())


def search_figure(found: Design) -> Figure:
    """The global search's candidates in the plane of the first two varied parameters (or the
    worst objective against the one), coloured by their worst objective (infeasible: grey
    crosses), the refinement's path and the design found."""
    from matplotlib.figure import Figure

    problem, table = found.problem, found.candidates
    names = problem.names
    fig = Figure(figsize=(6.5, 5), layout="tight")
    ax = fig.subplots()
    feasible = table[table.violation == 0]
    infeasible = table[table.violation > 0]
    history = found.history[found.history.how == "followed"] if len(found.history) else found.history
    if len(names) >= 2:
        x, y = names[0], names[1]
        shown = ax.scatter(feasible[x], feasible[y], c=feasible.objective, cmap="viridis", s=40, label="candidates")
        fig.colorbar(shown, ax=ax, label=quantity_label(problem.objective, "worst "))
        ax.scatter(infeasible[x], infeasible[y], color="0.6", marker="x", label="breaks a constraint")
        if len(history):
            ax.plot(history[x], history[y], color="C3", linewidth=1, marker=".", label="refinement")
        best = problem.design(found.best.design)
        ax.scatter([best[x]], [best[y]], color="C3", marker="*", s=160, zorder=5, label="design found")
        ax.set_xlabel(quantity_label(x))
        ax.set_ylabel(quantity_label(y))
    else:
        x = names[0]
        ax.scatter(feasible[x], feasible.objective, color="C0", label="candidates")
        ax.scatter(infeasible[x], infeasible.objective, color="0.6", marker="x", label="breaks a constraint")
        ax.scatter([found.best.design[0]], [found.best.objective], color="C3", marker="*", s=160, label="design found")
        ax.set_xlabel(quantity_label(x))
        ax.set_ylabel(quantity_label(problem.objective, "worst "))
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax.set_title(wrapped_title(problem.case, "the global search and the refinement"), fontsize=9)
    return fig


def front_figure(found: Design) -> Figure:
    """The two worst cases of every candidate (grey; infeasible: crosses) and the Pareto front's
    refined designs (joined), each labelled with its parameters."""
    from matplotlib.figure import Figure

    problem, table, front = found.problem, found.candidates, found.front
    (second,) = problem.also
    fig = Figure(figsize=(8.5, 5), layout="tight")
    ax = fig.subplots()
    feasible, infeasible = table[table.violation == 0], table[table.violation > 0]
    ax.scatter(feasible.second, feasible.objective, color="0.6", label="candidates")
    ax.scatter(infeasible.second, infeasible.objective, color="0.6", marker="x", label="breaks a constraint")
    ax.plot(front.second, front.objective, color="C3", label="Pareto front")
    refined = front[front.refined.astype(bool)]
    ax.scatter(refined.second, refined.objective, color="C3", zorder=3, label="refined designs")
    sketched = front[~front.refined.astype(bool)]
    ax.scatter(
        sketched.second, sketched.objective, facecolor="white", edgecolor="C3", zorder=3, label="candidates on it"
    )
    key = []  # each point numbered beside it, its parameters listed beside the axes: a flat front crowds labels
    for k, (_, row) in enumerate(front.iterrows(), start=1):
        ax.annotate(str(k), (row.second, row.objective), fontsize=7, xytext=(4, 4), textcoords="offset points")
        key.append(f"{k}: " + ", ".join(f"{n} = {row[n]:.4g}" for n in problem.names))
    ax.text(
        1.02,
        1.0,
        "\n".join(key),
        transform=ax.transAxes,
        fontsize=7,
        ha="left",
        va="top",
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.8"},
    )
    ax.set_xlabel(quantity_label(second, "worst "))
    ax.set_ylabel(quantity_label(problem.objective, "worst "))
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax.set_title(wrapped_title(problem.case, "the Pareto front of the two worst cases"), fontsize=9)
    return fig


def design_blocks(found: Design, plots: bool) -> list[mk.Block]:
    """The report: the problem, the design found with its worst case and simulations, how the
    refinement ended, the best candidates, the figures."""
    problem = found.problem
    name, low, high = problem.over
    ranges = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, a, b in problem.vary)
    constraints = "; ".join(str(c) for c in problem.constraints) or "none"
    blocks: list[mk.Block] = [mk.Heading(1, (f"{problem.case.name}: design over {name} in [{low:g}, {high:g}]",))]
    aim = (
        f"Minimise the worst {problem.objective} over {problem.band} values of {name} and every attractor "
        f"that {problem.starts} fresh starts reach at each, choosing {ranges}; constraints: {constraints}."
    )
    blocks += [mk.Paragraph((aim,))]
    blocks += modified_blocks(problem.case)
    verdict = (
        "meets every constraint" if found.best.feasible else f"breaks the constraints by {found.best.violation:.4g}"
    )
    rows = tuple((n, f"{v:.10g}") for n, v in found.values.items())
    rows += ((f"worst {problem.objective}", f"{found.best.objective:.10g}"), ("constraints", verdict))
    rows += tuple((f"simulations: {stage}", str(count)) for stage, count in found.runs.items())
    blocks += [mk.Heading(2, ("The design found",)), mk.Table(("", "value"), rows), mk.Paragraph((found.message,))]
    best = found.candidates.sort_values(["violation", "objective"]).head(10)
    header = (*problem.names, f"worst {problem.objective}", "violation", "simulations")
    table = tuple(
        (*(f"{r[n]:.6g}" for n in problem.names), f"{r.objective:.6g}", f"{r.violation:.3g}", str(int(r.runs)))
        for _, r in best.iterrows()
    )
    blocks += [mk.Heading(2, ("The global search's best candidates",)), mk.Table(header, table)]
    if len(found.front):
        blocks += _front_blocks(found, plots)
    if plots:
        blocks += [mk.Figure("design-search", "the candidates, the refinement and the design found")]
        blocks += [mk.Figure("design-response", f"the measures against {name}, before and after")]
    return blocks


def _front_blocks(found: Design, plots: bool) -> list[mk.Block]:
    problem = found.problem
    (second,) = problem.also
    header = (*problem.names, f"worst {problem.objective}", f"worst {second}", "refined under", "simulations")
    rows = tuple(
        (
            *(f"{r[n]:.8g}" for n in problem.names),
            f"{r.objective:.8g}",
            f"{r.second:.8g}",
            ("alone" if r.refined else "a candidate") if np.isnan(r.eps) else f"{second} <= {r.eps:.6g}",
            str(int(r.runs)),
        )
        for _, r in found.front.iterrows()
    )
    blocks: list[mk.Block] = [mk.Heading(2, (f"The Pareto front of {problem.objective} and {second}",))]
    blocks += [mk.Table(header, rows)]
    if plots:
        blocks += [mk.Figure("design-front", f"worst {problem.objective} against worst {second}")]
    return blocks


#: How a design folder that cannot be read is made again.
_REMAKE = "run the oscillator design command that made it again with the same --out"


def _judged(judged: Judged) -> dict[str, object]:
    """What ``best.json`` keeps of a judged design besides its attractors (in a table)."""
    return {
        "design": [float(v) for v in judged.design],
        "objective": judged.objective,
        "violation": judged.violation,
        "runs": judged.runs,
        "how": judged.how,
        "worst": dict(judged.worst),
    }


def write_design(found: Design, folder: Path, *, plots: bool = True) -> list[str]:
    """``candidates.parquet``, ``history.parquet``, ``attractors.parquet`` (the design found's
    attractors at each band value), ``start-attractors.parquet`` (those of the global search's
    best, where the refinement began), ``front.parquet`` (with two objectives), ``best.json``, the
    figures and the report; what could not be drawn (the tables stay)."""
    from oscillator.io.files import atomic_path
    from oscillator.report.outputs import write_folder
    from oscillator.report.runs import json_text

    best = {"design": found.values, "objective": found.best.objective, "violation": found.best.violation}
    best |= {"feasible": found.best.feasible, "runs": found.runs, "message": found.message}
    best |= {"judged": {"best": _judged(found.best), "start": _judged(found.start)}}
    with atomic_path(folder / "best.json") as temporary:
        temporary.write_text(json_text(best), encoding="utf-8")
    tables = {"candidates": found.candidates, "history": found.history, "attractors": seen_table(list(found.best.seen))}
    tables["start-attractors"] = seen_table(list(found.start.seen))
    figures: list[tuple[str, Callable[[], Figure]]] = []
    if plots:
        figures = [
            ("design-search", functools.partial(search_figure, found)),
            ("design-response", lambda: design_figure(found, band_responses(found))),
        ]
        if len(found.front):
            figures.append(("design-front", functools.partial(front_figure, found)))
    if len(found.front):
        tables["front"] = found.front
    title = f"{found.problem.case.name}: design"
    return write_folder(folder, tables, figures, design_blocks(found, plots), title)


def read_design(folder: Path) -> Design:
    """The design a folder holds (``oscillator design``'s, finished, or a
    :meth:`~oscillator.Design.save`'s): the problem and settings from ``design.json`` and
    ``case.toml``, the rest from its tables and ``best.json``; every file checked, nothing
    computed.

    Raises
    ------
    InputError
        A file missing (an unfinished folder: the command resumes it) or damaged, named.
    """
    import json

    from oscillator.designing.judging import seen_columns, seen_from_table
    from oscillator.designing.optimise import Design
    from oscillator.errors import InputError
    from oscillator.io.files import read_untrusted
    from oscillator.report.orbit_folders import checked_table
    from oscillator.text import printable

    problem, settings = _problem_of(folder)
    where = folder / "best.json"
    if not where.is_file():
        raise InputError(
            f"{printable(str(folder))} is not a finished design: best.json is missing; {_REMAKE}", field="best.json"
        )
    tables = {}
    for table in ("attractors", "start-attractors"):
        path = folder / f"{table}.parquet"
        tables[table] = checked_table(path, seen_columns(), folder="design folder", remake=_REMAKE)
    scores = dict.fromkeys([*problem.names, "objective", "violation", "runs"], "number")
    tables["candidates"] = checked_table(folder / "candidates.parquet", scores, folder="design folder", remake=_REMAKE)
    history = checked_table(folder / "history.parquet", {}, folder="design folder", remake=_REMAKE)
    if len(history.columns):  # none where the refinement did not run
        history = checked_table(folder / "history.parquet", scores, folder="design folder", remake=_REMAKE)
    front = pd.DataFrame()
    if (folder / "front.parquet").exists():
        front = checked_table(folder / "front.parquet", scores, folder="design folder", remake=_REMAKE)
    try:
        info = json.loads(read_untrusted(where, what="design file", field="best.json", limit=16 << 20))
        judged = {
            which: _judged_from(problem, info["judged"][which], seen_from_table(tables[table]))
            for which, table in (("best", "attractors"), ("start", "start-attractors"))
        }
        runs = {str(stage): int(count) for stage, count in info["runs"].items()}
        message = str(info["message"])
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError) as error:
        raise InputError(
            f"{printable(str(where))} is damaged ({printable(str(error))[:200]}); {_REMAKE}", field="best.json"
        ) from None
    return Design(
        problem, judged["best"], judged["start"], tables["candidates"], history, runs, message, front, settings
    )


def _problem_of(folder: Path) -> tuple[Problem, AttractorSettings]:
    """The problem and the settings a design folder's ``design.json`` and ``case.toml`` hold."""
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.designing.optimise import DesignStore
    from oscillator.designing.problem import Problem
    from oscillator.errors import InputError, OscillatorError
    from oscillator.report.global_results import marker_identity
    from oscillator.report.outputs import folder_case
    from oscillator.text import printable

    remake = "run the oscillator design command that made it again with a new --out"
    known = marker_identity(folder / "design.json", DesignStore.FORMAT, remake)
    case = folder_case(folder, "design.json")
    try:
        vary = {str(name): (float(low), float(high)) for name, low, high in known["vary"]}
        ((name, low, high),) = [known["over"]]
        objective = [known["objective"], *known.get("also", [])]
        problem = Problem.of(
            case, vary, {name: (low, high)}, objective, known["constraints"], known["band"], known["starts"]
        )
        return problem, AttractorSettings(**known["settings"])
    except (KeyError, TypeError, ValueError, OscillatorError) as error:
        raise InputError(
            f"{printable(str(folder))}/design.json is damaged ({printable(str(error))[:200]}); {_REMAKE}",
            field="folder",
        ) from None


def _judged_from(problem: Problem, info: dict[str, Any], seen: list[Seen]) -> Judged:
    """:func:`_judged` read back, with its attractors (``None``, JSON's infinity, read as ``inf``)."""

    def number(value: object) -> float:
        return math.inf if value is None else float(value)  # type: ignore[arg-type]

    design = np.array([float(v) for v in info["design"]], dtype=float)
    if design.shape != (len(problem.names),) or not np.isfinite(design).all():
        raise ValueError("a design's parameters are not the problem's")
    worst = {str(measure): number(value) for measure, value in info["worst"].items()}
    how = info["how"]
    if not isinstance(how, str):
        raise TypeError("a design's 'how' is not text")
    runs = info["runs"]
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 0:
        raise ValueError("a design's runs are not a count")
    return Judged(design, tuple(seen), number(info["objective"]), number(info["violation"]), runs, how, worst)
