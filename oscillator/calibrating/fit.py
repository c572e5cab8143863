"""Least-squares calibration of a model's parameters to measured steady responses or a measured
time series (docs/calibration.md).

The parameters ``vary`` (each within its range) minimise ``sum rho((model_i - value_i) /
sigma_i)`` over the measured rows, with ``rho`` the square (``loss = "linear"``) or a robust loss
that lets an outlier count less (SciPy's ``least_squares``: ``"soft_l1"``, ``"huber"``,
``"cauchy"``, ``"arctan"``; trust-region reflective within the ranges).  The residuals'
Jacobian is exact: each step costs one orbit and one sensitivity pass per measured frequency
(:mod:`~oscillator.calibrating.steady`), or one run and its tangent pass for a time series
(:mod:`~oscillator.calibrating.series`, a table with a ``t`` column) or for event times
(:mod:`~oscillator.calibrating.events`, a ``kind`` column), never a difference of simulations.

The problem is not convex where the motion's switching sequence changes across the ranges:
``starts > 1`` fits again from that many more points spread over the ranges (a Latin hypercube)
and keeps the best.  The estimate's covariance, intervals, correlations and what the data cannot
identify are computed at the optimum (:mod:`~oscillator.calibrating.uncertainty`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import admitted_box
from oscillator.calibrating.events import Events
from oscillator.calibrating.measured import Measured, check_events, check_measured, check_series
from oscillator.calibrating.series import Series
from oscillator.calibrating.steady import Crossing, Responses
from oscillator.calibrating.uncertainty import Uncertainty, uncertainty
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.counting import runs
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chain_rules import ChainEventKind
from oscillator.model.chains import FrictionChain
from oscillator.model.events import EventKind
from oscillator.model.parameters import Parameters, check_count, is_finite_number
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.calibrating.store import CalibrationStore

__all__ = ["LOSSES", "TOLERANCE", "Calibration", "Fit", "calibrate"]

#: SciPy's three stopping tests (step, cost, gradient), relative: far below any estimate's
#: standard error, above the measures' own accuracy (about 1e-9).
TOLERANCE = 1e-8

#: The losses of SciPy's least_squares, and the weight each gives a residual ``z = (r / f)^2``
#: at the optimum (``rho'(z)``): what a point counts for in the covariance.
LOSSES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "linear": lambda z: np.ones_like(z),
    "soft_l1": lambda z: 1 / np.sqrt(1 + z),
    "huber": lambda z: np.where(z <= 1, 1.0, 1 / np.sqrt(np.maximum(z, 1))),
    "cauchy": lambda z: 1 / (1 + z),
    "arctan": lambda z: 1 / (1 + z**2),
}


@dataclass(frozen=True)
class Calibration:
    """A calibration (:func:`calibrate`).

    Attributes
    ----------
    system : Case or FrictionChain
        The model as given (its values the first start).
    params : tuple of str
        The fitted parameters.
    table : DataFrame
        Per parameter: ``low``, ``high`` (its range), ``start``, ``estimate``, ``stderr`` and the
        interval ``ci_low``, ``ci_high`` at :attr:`level`.
    uncertainty : Uncertainty
        Covariance, correlation, intervals, the noise's ``scale`` and the warnings.
    residuals : DataFrame
        The measured rows with ``fitted`` and ``residual`` (measured minus fitted) and ``weight``
        (1, or less where a robust loss discounted the row).
    starts : DataFrame
        Each start's values, its end's ``cost``, ``evaluations``, ``runs`` (simulations) and
        ``status``.
    crossings : DataFrame
        Where the switching sequence of a measured point's orbit changed during the best fit:
        ``evaluation``, the measured parameter's value, the switches per return before and after.
    notes : tuple of str
        Points where the derivative was taken by differences, orbits settled afresh.
    cost, evaluations, runs, message, success, loss
        The best fit's ``0.5 sum rho``, its model evaluations, the simulations of the whole
        calibration (every start), SciPy's message, whether it converged, the loss.
    """

    system: Any
    over: str
    params: tuple[str, ...]
    table: pd.DataFrame
    uncertainty: Uncertainty
    residuals: pd.DataFrame
    starts: pd.DataFrame
    crossings: pd.DataFrame
    notes: tuple[str, ...]
    cost: float
    evaluations: int
    runs: int
    message: str
    success: bool
    loss: str

    @property
    def estimate(self) -> pd.Series:
        """The fitted values by name."""
        return self.table.estimate

    @property
    def covariance(self) -> pd.DataFrame:
        return self.uncertainty.covariance

    @property
    def correlation(self) -> pd.DataFrame:
        return self.uncertainty.correlation

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the data cannot identify, and strong correlations (empty: all well determined)."""
        return self.uncertainty.warnings

    @property
    def fitted(self) -> Case | FrictionChain:
        """The model with the estimate."""
        return _with(self.system, dict(self.estimate))

    def __str__(self) -> str:
        level = f"{100 * self.uncertainty.level:g} %"
        lines = [f"calibration of {', '.join(self.params)} to {len(self.residuals)} measurements: {self.message}"]
        lines += [
            f"  {name} = {row.estimate:.8g} +- {row.stderr:.3g} ({level}: {row.ci_low:.6g} to {row.ci_high:.6g})"
            for name, row in self.table.iterrows()
        ]
        lines.append(
            f"  residuals' scale {self.uncertainty.scale:.4g}, {self.evaluations} evaluations, {self.runs} runs"
        )
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])


def _with(system: Case | FrictionChain, values: Mapping[str, float]) -> Case | FrictionChain:
    if isinstance(system, FrictionChain):
        return system.with_values(values)
    return resolve_case(system, **values)


def _system(system: object) -> Case | FrictionChain:
    if isinstance(system, FrictionChain):
        return system.checked()
    if isinstance(system, Case | str):
        return resolve_case(system)
    raise InputError(
        f"system must be a case (or a shipped case's name) or a FrictionChain, got {shown(system)}", field="system"
    )


def _value(system: Case | FrictionChain, name: str) -> float | None:
    if isinstance(system, FrictionChain):
        return system.value(name)
    return float(getattr(system.parameters, Parameters.check_name(name, "vary")))


def _ranges(system: Case | FrictionChain, vary: object, over: str) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """The fitted parameters' names and ranges, each end admitted by the model."""
    if not isinstance(vary, Mapping) or not vary:
        raise InputError("vary must map parameters to ranges, e.g. {'mu_k': (0.05, 0.2)}", field="vary")
    names, low, high = [], [], []
    for name, bounds in vary.items():
        _value(system, str(name))  # a name the model has (refused with the closest one)
        ends = list(bounds) if isinstance(bounds, Sequence) and not isinstance(bounds, str) else []
        if len(ends) != 2 or not all(is_finite_number(e) for e in ends) or not float(ends[0]) < float(ends[1]):
            raise InputError(
                f"vary: {printable(str(name))}'s range must be two numbers low < high, got {shown(bounds)}",
                field="vary",
            )
        if name == over:
            raise InputError(f"vary: {over} is the measured parameter; it is not fitted", field="vary")
        names.append(str(name))
        low.append(float(ends[0]))
        high.append(float(ends[1]))
    box = dict(zip(names, zip(low, high, strict=True), strict=True))
    admitted_box(system, box, dict.fromkeys(names, "vary"), "give ranges whose every combination it admits")
    return tuple(names), np.array(low), np.array(high)


def _check_points(system: Case | FrictionChain, measured: Measured) -> None:
    """Every measured value of the parameter admitted by the model (a frequency that cannot be)."""
    column = measured.table[measured.over].to_numpy()
    for at in measured.values:
        try:
            _with(system, {measured.over: float(at)})
        except InputError as error:
            row = int(np.flatnonzero(column == at)[0]) + 1
            raise InputError(
                f"data row {row}: the model refuses {measured.over} = {at:g} ({error}); give values it admits",
                field=measured.over,
            ) from None


def _first(system: Case | FrictionChain, names: tuple[str, ...], low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The model's own values, where inside their ranges (else each range's middle), scaled to [0, 1]."""
    given = [_value(system, name) for name in names]
    values = np.array([(lo + hi) / 2 if v is None else v for v, lo, hi in zip(given, low, high, strict=True)])
    inside = (values >= low) & (values <= high)
    return np.where(inside, (values - low) / (high - low), 0.5)


@dataclass(frozen=True)
class Fit:
    """One start's end: the scaled point, the weighted residuals and Jacobian there, SciPy's
    verdict, the simulations it took, and where its points' switching sequences changed
    (:class:`~oscillator.calibrating.steady.Crossing`) and what was noted on the way."""

    u: np.ndarray
    cost: float
    residuals: np.ndarray
    jacobian: np.ndarray
    fitted: np.ndarray
    evaluations: int
    message: str
    success: bool
    runs: int = 0
    crossings: tuple[Crossing, ...] = ()
    notes: tuple[str, ...] = ()


def _fit(
    responses: Responses | Series | Events, low: np.ndarray, high: np.ndarray, u0: np.ndarray, options: dict[str, Any]
) -> Fit:
    """Least squares from ``u0`` (scaled to the ranges) with the exact Jacobian."""
    from scipy.optimize import least_squares

    table = responses.measured.table
    value, sigma, width = table.value.to_numpy(), table.sigma.to_numpy(), high - low
    seen: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def at(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        key = np.asarray(u, dtype=float).tobytes()
        if key not in seen:
            try:
                fitted, jacobian = responses(low + np.clip(u, 0, 1) * width)
            except SimulationFailed as error:
                if not seen:  # the start itself
                    raise
                # no orbit at a trial point: non-finite residuals make SciPy refuse the step and
                # shrink its trust region
                responses.notes.append(f"step {responses.evaluations}: {error}; the step refused")
                fitted, jacobian = np.full(len(value), np.nan), np.full((len(value), len(width)), np.nan)
            seen.clear()  # SciPy asks for the Jacobian where it last asked for the residuals
            seen[key] = ((fitted - value) / sigma, jacobian / sigma[:, None] * width, fitted)
        return seen[key]

    solved = least_squares(
        lambda u: at(u)[0],
        u0,
        jac=lambda u: at(u)[1],
        bounds=(0, 1),
        method="trf",
        x_scale="jac",
        loss=options["loss"],
        f_scale=options["f_scale"],
        max_nfev=options["max_evaluations"],
        xtol=TOLERANCE,
        ftol=TOLERANCE,
        gtol=TOLERANCE,
    )
    r, jacobian, fitted = at(solved.x)
    verdict = {"message": solved.message, "success": bool(solved.success)}
    return Fit(solved.x, float(solved.cost), r, jacobian / width, fitted, responses.evaluations, **verdict)


def _starts(first: np.ndarray, count: int, seed: int) -> np.ndarray:
    """``first`` and ``count - 1`` more points spread over the unit box (a Latin hypercube)."""
    if count == 1:
        return first[None, :]
    from scipy.stats import qmc

    return np.vstack([first, qmc.LatinHypercube(d=len(first), seed=seed).random(count - 1)])


def _options(loss: object, f_scale: object, level: object, starts: object, max_evaluations: object) -> dict[str, Any]:
    if loss not in LOSSES:
        raise InputError(f"loss must be one of {', '.join(LOSSES)}, got {shown(loss)}", field="loss")
    if not is_finite_number(f_scale) or not float(f_scale) > 0:
        raise InputError(
            f"f_scale must be a positive number (residuals in sigma), got {shown(f_scale)}", field="f_scale"
        )
    if not is_finite_number(level) or not 0 < float(level) < 1:
        raise InputError(f"level must be a probability between 0 and 1 (0.95), got {shown(level)}", field="level")
    check_count(starts, "starts", 1, 1000)
    most = check_count(max_evaluations, "max_evaluations", 1, 100_000)
    return {"loss": loss, "f_scale": float(f_scale), "max_evaluations": most}


def calibrate(
    system: Case | FrictionChain | str,
    data: pd.DataFrame,
    vary: Mapping[str, Sequence[float]],
    *,
    over: str = "Omega",
    starts: int = 1,
    loss: str = "linear",
    f_scale: float = 1.0,
    level: float = 0.95,
    transient: int = 100,
    seed: int = 0,
    max_evaluations: int = 100,
    store: CalibrationStore | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Calibration:
    """Fit the parameters ``vary`` of ``system`` to the measured steady responses ``data``
    (module docstring; docs/calibration.md).

    Parameters
    ----------
    system : Case, FrictionChain or str
        The model; its own values of ``vary`` are the first start (each range's middle where
        outside it).
    data : DataFrame
        Steady responses: columns ``over``, ``measure``, ``value`` and optionally ``sigma``; a
        time series: ``t``, ``variable`` (a state's name: ``x1``, ``v2``, ``x:part``), ``value``
        and optionally ``sigma``; the article's system's event times: ``kind``, ``t`` and
        optionally ``mass`` and ``sigma`` (:mod:`~oscillator.calibrating.measured`).
    vary : mapping
        Each fitted parameter's range, ``{"mu_k": (0.05, 0.2), "K6": (0.5, 5)}``.
    over : str
        The parameter the rows were measured at (``"Omega"``).
    starts : int
        Fits from the model's values and ``starts - 1`` points spread over the ranges; the best
        is kept.
    loss, f_scale : str, float
        SciPy's loss (``"linear"``: least squares; a robust one for outliers) and the residual
        (in ``sigma``) beyond which a robust loss discounts a row.
    level : float
        The confidence intervals' level.
    transient : int
        Forcing periods simulated from the model's start to settle on each point's orbit.
    seed, max_evaluations : int
        The spread starts' seed; model evaluations per start at most.
    store : CalibrationStore, optional
        A resumable folder (:func:`~oscillator.calibrating.store.calibration_store`): each start's
        fit is kept in it as it ends, and a start it holds is read back instead of fitted again.
        It is checked (a folder of another calibration is refused) and created once the data and
        the ranges are admitted.
    progress : callable, optional
        ``progress(done, total)`` after each start.

    Raises
    ------
    InputError
        Bad data (by row and column), an unknown parameter, a range the model refuses.
    SimulationFailed
        No orbit at a measured point from any start.
    """
    model = _system(system)
    series = isinstance(data, pd.DataFrame) and ("t" in data.columns or "kind" in data.columns)
    names, low, high = _ranges(model, vary, "t" if series else over)
    options = _options(loss, f_scale, level, starts, max_evaluations)
    check_count(transient, "transient", 0, 100_000)
    check_count(seed, "seed", 0)
    if progress is not None and not callable(progress):
        raise InputError(f"progress must be a function of (done, total), got {shown(progress)}", field="progress")
    measured, make = _model_of(model, data, names, series, over, int(transient))
    points = _starts(_first(model, names, low, high), int(starts), seed)
    if store is not None:  # the data and the ranges admitted: the folder is made (or resumed)
        fitted = {"over": over, "starts": starts, "loss": loss, "f_scale": f_scale, "transient": transient}
        _check_store(store, model, data, vary, fitted | {"seed": seed, "max_evaluations": max_evaluations})
        store.check()
        store.open()
    ends, rows = [], []
    for k, u0 in enumerate(points):
        end = _start(make, (low, high), u0, options, (store, k, len(measured.table)))
        ends.append(end)
        status = "converged" if end.success else end.message
        rows.append(
            dict(zip(names, low + u0 * (high - low), strict=True))
            | {"cost": end.cost, "evaluations": end.evaluations, "runs": end.runs, "status": status}
        )
        if progress is not None:
            progress(k + 1, len(points))
    fits = [end for end in ends if math.isfinite(end.cost)]
    if not fits:
        raise SimulationFailed(f"no start reached a fit: {rows[0]['status']}", reason=Reason.NO_ORBIT)
    best = min(fits, key=lambda f: f.cost)
    spent = sum(end.runs for end in ends)
    return _result(model, measured, (names, low, high), best, pd.DataFrame(rows), spent, options, level)


def _check_store(store: CalibrationStore, model: object, data: object, vary: object, settings: dict[str, Any]) -> None:
    """Refuse a store made for another calibration than this call's."""
    from oscillator.calibrating.store import calibration_store

    expected = calibration_store(store.folder, model, data, vary, **settings)  # type: ignore[arg-type]
    if store.identity != expected.identity:
        raise InputError(
            "store: it was made for another calibration (another model, data, ranges or settings); make it with "
            "calibration_store and this call's arguments",
            field="store",
        )


def _start(
    make: Callable[[], Responses | Series | Events],
    ranges: tuple[np.ndarray, np.ndarray],
    u0: np.ndarray,
    options: dict[str, Any],
    kept: tuple[CalibrationStore | None, int, int],
) -> Fit:
    """The fit from ``u0``: read back from the store where it holds it (start ``k`` of a
    resumed calibration of ``rows`` measurements), else computed and kept there. A start from
    which no orbit is found ends with a NaN cost and the failure as its message."""
    store, k, rows = kept
    if store is not None and (found := store.read_fit(k, u0, rows)) is not None:
        return found
    before, responses = runs(), make()
    try:
        end = _fit(responses, *ranges, u0, options)
    except SimulationFailed as error:
        nothing = np.empty((0, len(u0)))
        end = Fit(u0, math.nan, nothing[:, 0], nothing, nothing[:, 0], responses.evaluations, str(error), False)
    end = replace(end, runs=runs() - before, crossings=tuple(responses.crossings), notes=tuple(responses.notes))
    if store is not None:
        store.write_fit(k, u0, end)
    return end


def _model_of(
    model: Case | FrictionChain, data: object, names: tuple[str, ...], series: bool, over: str, transient: int
) -> tuple[Measured, Callable[[], Responses | Series | Events]]:
    """The data checked, and what makes the model's side of a fit: a time series' trajectory
    (:class:`~oscillator.calibrating.series.Series`) or steady responses (:class:`Responses`)."""
    if not series:
        measured = check_measured(data, over, len(names), _known_measures(model))
        _check_points(model, measured)
        return measured, lambda: Responses(model, measured, names, transient=transient)
    if isinstance(model, FrictionChain):
        chain = model
        if "kind" in data.columns:  # type: ignore[attr-defined]
            kinds = tuple(kind.value for kind in ChainEventKind if kind is not ChainEventKind.GRAZING)
            elements = tuple(element.name for element in chain.elements)
            events = check_events(data, len(names), chain.t0, kinds, elements, by="element")
            return events, lambda: Events(chain, events, names)
        measured = check_series(data, len(names), chain.t0, tuple(map(str, chain.system.state)))
        return measured, lambda: Series(chain, measured, names)
    if "kind" in data.columns:  # type: ignore[attr-defined]
        kinds = tuple(kind.value for kind in EventKind if kind.switches)
        timed = check_events(data, len(names), model.initial.t0, kinds, model.system.masses)
        return timed, lambda: Events(model, timed, names)
    checked = check_series(data, len(names), model.initial.t0, model.system.state)
    return checked, lambda: Series(model, checked, names)


def _known_measures(model: Case | FrictionChain) -> tuple[str, ...] | None:
    if isinstance(model, FrictionChain):
        return None  # known from the first orbit
    from oscillator.orbits.response import COLUMNS

    return tuple(COLUMNS)


def _result(
    model: Case | FrictionChain,
    measured: Measured,
    ranges: tuple[tuple[str, ...], np.ndarray, np.ndarray],
    best: Fit,
    starts: pd.DataFrame,
    spent: int,
    options: dict[str, Any],
    level: float,
) -> Calibration:
    names, low, high = ranges
    estimate = pd.Series(low + best.u * (high - low), index=list(names), name="estimate")
    weight = LOSSES[options["loss"]]((best.residuals / options["f_scale"]) ** 2)
    root = np.sqrt(weight)
    found = uncertainty(
        best.jacobian * root[:, None], best.residuals * root, estimate, known_sigma=measured.known_sigma, level=level
    )
    first = starts.iloc[0]
    table = pd.DataFrame({"low": low, "high": high, "start": [first[n] for n in names]}, index=list(names))
    table["estimate"] = estimate
    table["stderr"] = found.stderr
    table["ci_low"], table["ci_high"] = found.intervals.low, found.intervals.high
    residuals = measured.table.assign(fitted=best.fitted, residual=measured.table.value - best.fitted, weight=weight)
    crossings = pd.DataFrame(
        [(c.evaluation, c.at, c.before, c.after) for c in best.crossings],
        columns=["evaluation", measured.over, "switches_before", "switches_after"],
    )
    return Calibration(
        system=model,
        over=measured.over,
        params=names,
        table=table,
        uncertainty=found,
        residuals=residuals,
        starts=starts,
        crossings=crossings,
        notes=best.notes,
        cost=best.cost,
        evaluations=best.evaluations,
        runs=spent,
        message=best.message,
        success=best.success,
        loss=options["loss"],
    )
