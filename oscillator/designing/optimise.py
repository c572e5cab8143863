"""Robust design over an operating band: a global search, then gradient refinement with the exact
sensitivities, then a check from fresh starts (docs/design.md).

1. **Global**: ``candidates`` designs spread over the box of ``vary`` (a Halton sequence,
   unscrambled: the same designs every time), each surveyed at every band value from ``starts``
   fresh starts (:func:`~oscillator.designing.judging.survey_task`, on every core or Dask).  The best
   is the feasible one with the smallest worst objective (or, with none feasible, the one that
   breaks the constraints least).
2. **Refinement**: from it, SciPy's SLSQP on the epigraph form ``min t`` subject to
   ``m_k(x) <= t`` for the objective on every attractor ``k`` at every band value and
   ``c_ik(x) <= b_i`` for every constraint, each function and its gradient given by continuing the
   attractors to ``x`` (:func:`~oscillator.designing.judging.follow`: Newton and the exact
   sensitivities).  The worst case over the attractors is a maximum of smooth functions; the
   epigraph form is smooth where each is.
3. **Check**: the refined design surveyed again from fresh starts.  An attractor the refinement
   did not follow (one born on the way) that is worse is added and the refinement runs again (at
   most :data:`ROUNDS` times); so it does from the refined design where SLSQP stopped short of
   convergence (its line search failed: a kink it met on the way).  The design returned is judged by that survey.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.execution import Executor, keyed
from oscillator.analysis.store import TableFolder, identity
from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.front import pareto_front
from oscillator.designing.judging import (
    Judged,
    Seen,
    follow,
    seen_from_table,
    seen_table,
    survey,
    survey_part,
    survey_task,
)
from oscillator.designing.problem import Constraint, Problem
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.io.cases import Case
from oscillator.model.parameters import check_count
from oscillator.presenting import Presented, presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["ROUNDS", "Design", "DesignStore", "design", "design_store", "refine"]

#: The most refinements (each followed by a survey that may find a worse attractor, or from where
#: SLSQP stopped short of convergence).
ROUNDS = 3
#: What SLSQP's message says where it converged.
CONVERGED = "terminated successfully"


@dataclass(frozen=True)
class Design(Presented):
    """What :func:`design` found: ``save(folder)`` writes it as ``oscillator design`` writes its
    folder, :func:`oscillator.read_run` reads either back, and it shows itself in Jupyter.

    Attributes
    ----------
    problem : Problem
    best : Judged
        The design returned, judged by a survey from fresh starts: ``best.design`` (in
        ``problem.names``' order), ``best.objective`` (its worst case), ``best.violation``.
    start : Judged
        The global search's best, where the refinement began.
    candidates : DataFrame
        The global search: one row per candidate (its parameters, ``objective``, ``violation``,
        ``runs``).
    history : DataFrame
        Every design the refinement judged (``round``, its parameters, ``objective``,
        ``violation``, ``runs``, ``how``: ``followed`` or ``survey``).
    runs : dict
        Simulations by stage: ``global``, ``refine``, ``check`` (the front's points included).
    message : str
        Why the refinement stopped where it did.
    front : DataFrame
        With two objectives, the Pareto front (:mod:`oscillator.designing.front`): one row per
        design on it, its parameters, ``eps`` (the bound on the second objective it was refined
        under; ``nan`` for ``best`` and the candidates), ``objective`` and ``second`` (the two
        worst cases), ``refined`` (False for a candidate of the global search that no refined
        design beats), ``violation``, ``runs``; empty with one objective.
    settings : AttractorSettings
        The surveys' landings (the figure of the responses before and after lands with them).
    """

    problem: Problem
    best: Judged
    start: Judged
    candidates: pd.DataFrame = field(repr=False)
    history: pd.DataFrame = field(repr=False)
    runs: dict[str, int]
    message: str
    front: pd.DataFrame = field(default_factory=pd.DataFrame, repr=False)
    settings: AttractorSettings = field(default_factory=AttractorSettings, repr=False)

    @property
    def values(self) -> dict[str, float]:
        """The best design by parameter name."""
        return self.problem.design(self.best.design)

    def plot(self, figure: str = "search") -> Figure:
        """One of ``oscillator design``'s figures: ``"search"`` (the candidates, the refinement and
        the design found), ``"response"`` (the worst objective over the band before and after:
        it lands at each of 21 band values, a few seconds) or ``"front"`` (with two objectives)."""
        return presenter().plot_global(self, figure=figure)


def _row(problem: Problem, judged: Judged, **extra: object) -> dict[str, object]:
    """A table's row: ``extra``, the design, its worst objective (and ``second``, the worst of the
    second objective, when there is one), violation, simulations and how it was judged."""
    scores = {"objective": judged.objective}
    if problem.also:
        scores["second"] = judged.worst.get(problem.also[0], np.nan)
    scores |= {"violation": judged.violation, "runs": judged.runs}
    return extra | problem.design(judged.design) | scores | {"how": judged.how}


class DesignStore(TableFolder):
    """The resumable folder of a design (``design.json``): one part per survey of the global
    search (``survey-KKKK-BBB``: candidate ``K`` at band value ``B``), its attractors as
    :func:`~oscillator.designing.judging.seen_table` and its simulations in the metadata.  The
    refinement and the check are computed again on resuming (a few percent of the work)."""

    #: 2: a survey's table has a failure column; 3: each part keyed by its task; 4: the impulses and
    #: force_rms among a survey's measures (a folder of an earlier format is refused, not read as damaged);
    #: 5: force_above and a_above among them.
    FORMAT = 5

    def __init__(self, folder: Path, identity: dict[str, Any], *, name: str = "") -> None:
        super().__init__(folder, "design.json", identity, name=name)


def design_store(folder: Path, problem: Problem, settings: AttractorSettings | None, candidates: int) -> DesignStore:
    """The resumable folder of this design (:class:`DesignStore`)."""
    from oscillator.attractors.mapping import check_settings

    pieces: dict[str, Any] = {"vary": [list(v) for v in problem.vary], "over": list(problem.over)}
    pieces |= {"objective": problem.objective, "constraints": [str(c) for c in problem.constraints]}
    pieces |= {"band": problem.band, "starts": problem.starts, "candidates": candidates}
    if problem.also:
        pieces["also"] = list(problem.also)
    return DesignStore(
        folder, identity(problem.case, settings=check_settings(settings), **pieces), name=problem.case.name
    )


def _global(
    problem: Problem,
    settings: AttractorSettings,
    count: int,
    executor: Executor,
    progress: Callable[[int, int], None] | None,
    store: DesignStore | None,
) -> list[Judged]:
    """Every candidate of the global stage, judged by a survey (read back from ``store`` where it
    holds one, and kept there as each finishes)."""
    from scipy.stats import qmc

    unit = qmc.Halton(d=len(problem.vary), scramble=False).random(count + 1)[1:]
    designs = problem.lower + unit * (problem.upper - problem.lower)
    bands = problem.band_values()
    found: dict[int, list[tuple[int, list[Seen], int]]] = {k: [] for k in range(count)}
    tasks = []
    expected = {(k, j): survey_part(k, j, x, float(b)) for k, x in enumerate(designs) for j, b in enumerate(bands)}
    for k, x in enumerate(designs):
        for j, b in enumerate(bands):
            kept = store.read(f"survey-{k:04d}-{j:03d}", expected[k, j]) if store is not None else None
            if kept is not None:
                found[k].append((j, seen_from_table(kept[0]), int(kept[1]["runs"])))
            else:
                tasks.append(((k, j), survey_task, problem, settings, tuple(x), float(b)))
    total = len(designs) * len(bands)
    done = total - len(tasks)
    for (k, j), (seen, cost) in executor.map(keyed, tasks):
        if store is not None:
            store.write(f"survey-{k:04d}-{j:03d}", seen_table(seen), {"runs": cost}, key=expected[k, j].key)
        found[k].append((j, seen, cost))
        done += 1
        if progress is not None:
            progress(done, total)
    judged = []
    for k, x in enumerate(designs):
        parts = sorted(found[k], key=lambda part: part[0])
        seen = [s for _, part, _ in parts for s in part]
        judged.append(Judged.of(problem, x, seen, sum(cost for _, _, cost in parts), "survey"))
    return judged


def _check_any_ran(problem: Problem, judged: list[Judged]) -> None:
    """Refuse a global search in which every start of every survey failed: no design was judged
    (each would be the worst), and the failures are said, the commonest first."""
    failures = pd.Series([s.failure for j in judged for s in j.seen])
    if len(failures) and (failures != "").all():
        common = failures.value_counts()
        said = "; ".join(f"{count} x {why}" for why, count in common.head(3).items())
        raise SimulationFailed(
            f"every start failed at every band value of all {len(judged)} candidates, so no design could be judged "
            f"({said}); check the case's settings (e.g. max_num_steps) and the ranges of `vary` and `over`",
            reason=Reason.SOLVER_FAILURE,
        )


class _Epigraph:
    """SLSQP's functions on ``z = (u, t)``, ``x = lower + u (upper - lower)``: each design followed
    once (a cache), every design it judged kept."""

    def __init__(self, problem: Problem, base: Judged, cutoff: float) -> None:
        self.problem, self.base, self.cutoff = problem, base, cutoff
        self.scale = problem.upper - problem.lower
        self.judged: list[Judged] = []
        self._cache: dict[tuple[float, ...], Judged] = {}

    def at(self, z: np.ndarray) -> Judged:
        u = np.clip(z[:-1], 0.0, 1.0)
        key = tuple(u)
        if key not in self._cache:
            base = self.judged[-1] if self.judged else self.base
            judged = follow(self.problem, base, self.problem.lower + u * self.scale, cutoff=self.cutoff)
            self._cache[key] = judged
            self.judged.append(judged)
        return self._cache[key]

    def _rows(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The inequalities ``g(z) >= 0`` and their gradients."""
        judged = self.at(z)
        t = z[-1]
        values, gradients = [], []
        bounds: list[tuple[str, float, float]] = [(self.problem.objective, math.nan, 1.0)]
        bounds += [(c.measure, c.bound, 0.0) for c in self.problem.constraints]
        for seen in judged.seen:
            for measure, bound, weight in bounds:
                gradient = seen.gradients.get(measure)
                if gradient is None:
                    continue
                if not np.isfinite(gradient).all():
                    raise OscillatorError(
                        f"{measure} has no derivative at a tie of two largest values (band value {seen.band:g})"
                    )
                limit = t if weight else bound
                values.append(limit - seen.value(measure))
                gradients.append(np.concatenate([-gradient * self.scale, [weight]]))
        return np.array(values), np.array(gradients)

    def constraints(self) -> dict[str, Any]:
        return {"type": "ineq", "fun": lambda z: self._rows(z)[0], "jac": lambda z: self._rows(z)[1]}


def refine(
    problem: Problem, start: Judged, *, max_iterations: int = 50, cutoff: float = 0.0
) -> tuple[list[Judged], str]:
    """SLSQP from ``start`` (module docstring, stage 2): every design judged, and why it stopped;
    ``cutoff`` (Hz) that of the measures ``force_above`` and ``a_above``."""
    from scipy.optimize import minimize

    epigraph = _Epigraph(problem, start, cutoff)
    u0 = (start.design - problem.lower) / epigraph.scale
    z0 = np.concatenate([u0, [start.objective]])
    bounds = [(0.0, 1.0)] * len(u0) + [(None, None)]
    try:
        solved = minimize(
            lambda z: z[-1],
            z0,
            jac=lambda z: np.concatenate([np.zeros(len(u0)), [1.0]]),
            method="SLSQP",
            bounds=bounds,
            constraints=[epigraph.constraints()],
            options={"maxiter": max_iterations, "ftol": 1e-10},
        )
        message = f"SLSQP: {solved.message} after {solved.nit} iterations"
        epigraph.at(solved.x)
    except OscillatorError as error:
        message = f"the refinement stopped: {error}"
    return epigraph.judged, message


def _refined(
    problem: Problem, settings: AttractorSettings, start: Judged, spent: dict[str, int]
) -> tuple[Judged, list[dict[str, object]], str]:
    """Stages 2 and 3 (module docstring) from a feasible ``start``: the design, the history's rows
    and why the refinement stopped; ``spent`` gains their simulations."""
    best, rows, message = start, [], "no refinement"
    for round_ in range(1, ROUNDS + 1):
        steps, message = refine(problem, best, cutoff=settings.cutoff)
        spent["refine"] += sum(j.runs for j in steps)
        rows += [_row(problem, j, round=round_) for j in steps]
        refined = min(steps, key=Judged.key) if steps else best
        checked = survey(problem, settings, refined.design)
        spent["check"] += checked.runs
        rows.append(_row(problem, checked, round=round_))
        settled = (checked.violation, checked.objective) <= (
            refined.violation,
            refined.objective + 1e-6 * abs(refined.objective),
        )
        settled = settled and CONVERGED in message  # SLSQP stopped short (a line search failed): again from there
        if settled or round_ == ROUNDS:
            return (checked if checked.key() <= start.key() else start), rows, message
        best = Judged.of(problem, refined.design, list(refined.seen) + list(checked.seen), 0, "followed")
    return best, rows, message


def design(
    case: Case | str,
    vary: Mapping[str, Sequence[float]],
    over: Mapping[str, Sequence[float]],
    objective: str | Sequence[str],
    constraints: Sequence[str | Constraint] = (),
    *,
    band: int = 5,
    starts: int = 4,
    candidates: int = 16,
    front: int = 5,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    store: DesignStore | None = None,
) -> Design:
    """The design of ``vary``'s parameters that makes the worst ``objective`` over the band of
    ``over`` and every attractor there smallest, subject to ``constraints`` (module docstring).
    Given a :class:`~oscillator.model.chains.FrictionChain` (a declared machine), one number over
    one band, no constraints: :func:`~oscillator.designing.chain_design.chain_design`, ``band``
    the sweep's values over the band (21 when left at 5; docs/damper-design.md).

    Parameters
    ----------
    case : Case or str
    vary : mapping
        The parameters chosen and their ranges, e.g. ``{"d1": (3.3, 4.2), "K6": (0.5, 4.0)}``.
    over : mapping
        The operating band: one parameter and its range, e.g. ``{"Omega": (1.4, 1.6)}``.
    objective : str or two str
        A response measure's column (:data:`oscillator.orbits.response.COLUMNS`), minimised in
        the worst case; or two, traded along a Pareto front (:attr:`Design.front`), ``best``
        minimising the first.
    constraints : sequence of str
        ``"measure <= bound"`` on every attractor at every band value.
    band : int
        Band values judged (ends included).
    starts : int
        Fresh starts at each band value (:func:`~oscillator.attractors.atlas.fresh_starts`).
    candidates : int
        Designs of the global search.
    front : int
        Points of the Pareto front, with two objectives (each a refined design).
    settings : AttractorSettings, optional
        The multistart's transient, recorded periods and tolerances.
    workers, client
        Local processes or a Dask client for the global search and the checks' surveys.
    progress : callable, optional
        ``progress(done, total)`` over the global search's surveys.
    store : DesignStore, optional
        Keep each survey of the global search in this folder as it finishes, and read back those
        it holds (:func:`design_store`): an interrupted design resumes.
    """
    from oscillator.attractors.mapping import check_settings
    from oscillator.model.chains import FrictionChain

    if isinstance(case, FrictionChain):  # a declared machine: one number over one band
        from oscillator.designing.chain_design import chain_design

        if not isinstance(objective, str) or constraints:
            raise InputError("a system's design takes one objective and no constraints for now", field="objective")
        return chain_design(case, vary, over, objective, sweep=band if band != 5 else 21)  # type: ignore[return-value]
    problem = Problem.of(case, vary, over, objective, constraints, band=band, starts=starts)
    if store is not None and not isinstance(store, DesignStore):
        raise InputError(f"store must be a DesignStore (design_store(folder, ...)), got {shown(store)}", field="store")
    settings = check_settings(settings)
    candidates = check_count(candidates, "candidates", 1, 100_000)
    front = check_count(front, "front", 1, 100)
    with Executor(workers, client, progress) as executor:
        if store is not None:
            store.check()
            store.open()
        judged = _global(problem, settings, candidates, executor, progress, store)
    _check_any_ran(problem, judged)
    start = min(judged, key=Judged.key)
    spent = {"global": sum(j.runs for j in judged), "refine": 0, "check": 0}
    if start.feasible:
        best, rows, message = _refined(problem, settings, start, spent)
    else:
        best, rows = start, []
        message = (
            f"no candidate of the global search meets the constraints (the least violation is {start.violation:.4g}, "
            f"at {problem.design(start.design)}); relax `constraints`, widen `vary` or give more `candidates`"
        )
    candidates_table = pd.DataFrame([_row(problem, j) for j in judged]).drop(columns="how")
    pareto = pd.DataFrame()
    if problem.also and best.feasible:
        pareto = pareto_front(problem, judged, best, lambda sub, s: _refined(sub, settings, s, spent)[0], front)
    return Design(problem, best, start, candidates_table, pd.DataFrame(rows), spent, message, pareto, settings)
