"""The one entry point, :func:`simulate`, and the checks a case passes before it runs."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np

from oscillator.engines import Engine, EngineChoice, build_engine
from oscillator.errors import InputError, Interrupted, Reason, SimulationFailed
from oscillator.hybrid.counting import counted
from oscillator.hybrid.guards import start_problem
from oscillator.hybrid.record import RunRecord
from oscillator.hybrid.recording import SaveAt, recording
from oscillator.hybrid.result import Result, Status
from oscillator.hybrid.supervisor import CallbackRaised, Supervisor
from oscillator.io.cases import Case, resolve_case
from oscillator.io.chains import load_system, system_path
from oscillator.io.signals import interrupts_heard
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SolverOptions, as_float
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.hybrid.chain_run import ChainResult

__all__ = ["admit", "resolve_case", "simulate"]


def _time(value: object, name: str) -> float:
    number = as_float(value)
    if math.isnan(number):
        raise InputError(f"{name} must be a time in s (a number), got {shown(value)}", field=name)
    return number


def _grid(t_eval: object, case: Case) -> np.ndarray:
    """``t_eval`` as a 1-D array of finite, increasing times within ``[t0, t_end]``."""
    try:
        grid = np.asarray(t_eval, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"t_eval must be a sequence of times in s, got {shown(t_eval)}", field="t_eval") from exc
    if grid.ndim != 1 or not np.isfinite(grid).all() or np.any(np.diff(grid) <= 0):
        raise InputError(
            "t_eval must be a one-dimensional sequence of finite, strictly increasing times in s", field="t_eval"
        )
    t0, t_end = case.initial.t0, case.t_end
    if grid.size and (grid[0] < t0 or grid[-1] > t_end):
        outside = float(grid[0] if grid[0] < t0 else grid[-1])
        raise InputError(
            f"t_eval holds t = {outside!r} s, outside the run [t0, t_end] = [{t0!r}, {t_end!r}] s; "
            f"give times within the run",
            field="t_eval",
        )
    return grid


def admit(case: Case) -> None:
    """Refuse a case that cannot start: too long a run, or a start beyond floating point.

    Run by :func:`simulate` before anything is integrated (and by the command line before it
    creates an output folder), so that the rule is simple: a refused input raises before the
    run, a failure after it has started carries the partial result.

    Raises
    ------
    InputError
        More than ``max_periods`` forcing periods between ``t0`` and ``t_end``; or the fields,
        root functions, powers or energy at the start are not finite numbers.
    """
    p, start = case.parameters, case.initial
    periods = (case.t_end - start.t0) / p.period
    if periods > case.options.max_periods:
        raise InputError(
            f"t_end - t0 = {case.t_end - start.t0:.6g} s is {periods:.3g} forcing periods, more than max_periods = "
            f"{case.options.max_periods}; shorten t_end (or check Omega), or raise max_periods",
            field="max_periods",
        )
    problem = start_problem(start.t0, start.y, p)
    if problem is not None:
        state = ", ".join(f"{name} = {value:g}" for name, value in zip(case.system.state, start.y, strict=True))
        raise InputError(
            f"at the start (t0 = {start.t0:g} s, {state}) {problem}; give parameters and a start of physical size",
            field="initial",
        )


def _chain_of(case: object) -> FrictionChain | None:
    """The friction chain ``case`` is or names (a system file's path), else ``None``."""
    if isinstance(case, FrictionChain):
        return case
    if isinstance(case, (str, Path)) and (path := system_path(str(case))) is not None:
        return load_system(path)
    return None


def _simulate_chain(chain: FrictionChain, t_end: float | None, unused: list[str], overrides: dict[str, float]) -> Any:
    """:func:`simulate` of a friction chain: :func:`~oscillator.hybrid.chain_run.simulate_chain`,
    overrides the chain's numbers by name (``Omega``; ``platform.F`` as ``**{"platform.F": 0.5}``) or
    solver options; the article's own settings refused by name."""
    from oscillator.hybrid.chain_run import simulate_chain

    if unused:
        raise InputError(f"{unused[0]} applies to the article's cases, not to a friction chain", field=unused[0])
    options = SolverOptions.names()
    chain = chain.with_values({name: value for name, value in overrides.items() if name not in options})
    settings: dict[str, Any] = {name: value for name, value in overrides.items() if name in options}
    return simulate_chain(chain, t_end, options=SolverOptions(**settings))


@overload
def simulate(
    case: FrictionChain,
    /,
    *,
    t_end: float | None = None,
    t_eval: Sequence[float] | np.ndarray | None = None,
    record_trajectory: bool = True,
    progress: Callable[[float], None] | None = None,
    keep_events_from: float | None = None,
    engine: EngineChoice = None,
    save: SaveAt | None = None,
    **overrides: float,
) -> ChainResult: ...


@overload
def simulate(
    case: Case | str | Path,
    /,
    *,
    t_end: float | None = None,
    t_eval: Sequence[float] | np.ndarray | None = None,
    record_trajectory: bool = True,
    progress: Callable[[float], None] | None = None,
    keep_events_from: float | None = None,
    engine: EngineChoice = None,
    save: SaveAt | None = None,
    **overrides: float,
) -> Result: ...


def simulate(
    case: Case | str | Path | FrictionChain,
    /,
    *,
    t_end: float | None = None,
    t_eval: Sequence[float] | np.ndarray | None = None,
    record_trajectory: bool = True,
    progress: Callable[[float], None] | None = None,
    keep_events_from: float | None = None,
    engine: EngineChoice = None,
    save: SaveAt | None = None,
    **overrides: float,
) -> Any:
    """Simulate a case from its start to ``t_end``.

    Parameters
    ----------
    case : Case, str, Path or FrictionChain
        A :class:`Case`, a shipped case's name (``"instance-1"``) or a case file's path; or a
        friction chain (:class:`~oscillator.FrictionChain`, or a system file's path: docs/systems.md),
        whose run is :func:`~oscillator.simulate_chain`'s :class:`~oscillator.ChainResult` (the
        chain's numbers by name and solver options as overrides; ``t_eval``, ``save``, ``engine``
        and ``keep_events_from`` are the article's).
    t_end : float, optional
        End time (s); the case's by default.
    t_eval : array_like, optional
        Record the trajectory on this grid (times within ``[t0, t_end]``) instead of at the
        solver's steps.
    record_trajectory : bool
        Keep trajectory rows (events and the energy audit are always kept).
    progress : callable, optional
        Called with the current time after every return of the engine: at every root, and with
        the trajectory at every step, after at most 256 steps (the steps between are taken in
        compiled code).  An exception it raises stops the run and reaches the caller unchanged.
    keep_events_from : float, optional
        Keep only the events at or after this time in ``Result.events`` (``stats.events``
        counts them all); the case's own (``[run] keep_events_from``) by default. With the
        trajectory off or on a grid too, memory stays flat in the run's length.
    engine : str or callable, optional
        The integrator (:mod:`oscillator.engines`): ``"cvode"`` (CVODE through its C API, the
        default where SUNDIALS' libraries load), ``"sksundae"`` (CVODE through scikit-sundae's
        Python API, the fallback) or ``"scipy"``; or a callable ``engine(params, options)`` that
        returns an :class:`~oscillator.engines.Engine`.
    save : SaveAt, optional
        What the run keeps, said at once (:class:`~oscillator.SaveAt`: the trajectory at the
        steps, on a grid or none; the events from a time on; the segments; the derivative of
        the flow), in place of ``t_eval``, ``record_trajectory`` and ``keep_events_from``.
    **overrides
        Any parameter (``Omega=1.7``), initial value (``x1=3.1``) or solver option
        (``rtol=1e-12``, ``grazing_velocity_tolerance=0.05``).

    Returns
    -------
    Result
        Events, trajectory, energy audit and solver statistics.

    Raises
    ------
    InputError
        Bad input, before anything runs (see :func:`admit`).
    SimulationFailed
        A solver failure or a guard (with the time, domains and state); ``error.result`` holds
        the partial :class:`Result` up to the last point reached (``Status.FAILED``).
    Interrupted
        Ctrl-C during the run (a ``KeyboardInterrupt``); ``error.result`` holds the partial
        result (``Status.INTERRUPTED``).

    Examples
    --------
    >>> from oscillator import simulate
    >>> result = simulate("instance-1")
    >>> result.events[["t", "mass", "kind", "to_domain"]].round(4).values.tolist()
    [[1.1746, 2, 'sliding_vanish', 1], [1.289, 1, 'sliding_vanish', 2]]
    """
    chain = _chain_of(case)
    if chain is not None:  # a friction chain (docs/systems.md)
        unused = {"t_eval": t_eval, "keep_events_from": keep_events_from, "engine": engine, "save": save}
        return _simulate_chain(chain, t_end, [k for k, v in unused.items() if v is not None], overrides)
    assert not isinstance(case, FrictionChain)  # for the type checker: a chain returned above
    if keep_events_from is not None:
        _time(keep_events_from, "keep_events_from")
    if save is not None and (t_eval is not None or record_trajectory is not True or keep_events_from is not None):
        raise InputError(
            "give what the run keeps either as save=SaveAt(...) or as t_eval, record_trajectory and "
            "keep_events_from, not both",
            field="save",
        )
    case = resolve_case(case, t_end=t_end, keep_events_from=keep_events_from, **overrides)
    if not isinstance(record_trajectory, (bool, np.bool_)):
        raise InputError(
            f"record_trajectory must be True or False, got {shown(record_trajectory)}", field="record_trajectory"
        )
    if progress is not None and not callable(progress):
        raise InputError(f"progress must be a function of the time (or None), got {shown(progress)}", field="progress")
    keep_from = -math.inf if case.keep_events_from is None else case.keep_events_from
    if save is None:
        save = SaveAt(
            steps=bool(record_trajectory), ts=None if t_eval is None else _grid(t_eval, case), events_from=keep_from
        )
    else:  # the keywords' SaveAt is checked as it is built
        save = _checked(save, case, keep_from)
    admit(case)
    integrator = build_engine(engine, case.parameters, case.options, variational=save.derivative)
    return _run(case, integrator, save, progress)


def _checked(save: object, case: Case, keep_from: float) -> SaveAt:
    """``save`` with its grid checked against the case (and the case's ``keep_events_from`` where
    it says nothing)."""
    if not isinstance(save, SaveAt):
        raise InputError(f"save must be an oscillator.SaveAt, got {shown(save)}", field="save")
    for name in ("steps", "segments", "derivative"):
        if not isinstance(getattr(save, name), (bool, np.bool_)):
            raise InputError(f"save.{name} must be True or False, got {shown(getattr(save, name))}", field=name)
    events_from = _time(save.events_from, "events_from")
    grid = None if save.ts is None else _grid(save.ts, case)
    return dataclasses.replace(save, ts=grid, events_from=keep_from if events_from == -math.inf else events_from)


def _run(case: Case, integrator: Engine, save: SaveAt, progress: Callable[[float], None] | None) -> Result:
    """Run the supervisor; the result, or the failure with its partial result."""
    p, options = case.parameters, case.options
    counted()
    policy = recording(save, max_rows=options.max_trajectory_rows, period=p.period)
    record = RunRecord()
    try:
        with interrupts_heard() as heard:
            supervisor = Supervisor(
                p,
                options,
                integrator,
                policy,
                progress=progress,
                segments=save.segments,
                derivative=save.derivative,
                interrupted=heard,
            )
            supervisor.run(case.initial.t0, case.initial.y, case.t_end, record)
    except CallbackRaised as raised:
        raise raised.error from None
    except SimulationFailed as error:
        if record.started:
            policy.stopped(record)
            error.result = Result.from_record(
                case, record, engine=integrator.name, status=Status.FAILED, message=str(error), reason=error.reason
            )
        raise
    except KeyboardInterrupt:
        if not record.started:
            raise
        policy.stopped(record)
        partial = Result.from_record(
            case,
            record,
            engine=integrator.name,
            status=Status.INTERRUPTED,
            message="interrupted by the user",
            reason=Reason.INTERRUPTED,
        )
        raise Interrupted(partial) from None
    finally:
        integrator.close()
    return Result.from_record(case, record, engine=integrator.name)
