"""The one entry point: :func:`simulate`."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from oscillator._errors import OscillatorError
from oscillator.cases import Case, _suggest, load_case
from oscillator.parameters import InitialState, Parameters, SolverOptions
from oscillator.result import Result
from oscillator.supervisor import ARITHMETIC_ERRORS, Supervisor, strict_arithmetic

__all__ = ["resolve_case", "simulate"]


def resolve_case(case: Case | str | Path, *, t_end: float | None = None, **overrides: float) -> Case:
    """The case with overrides applied: parameter, initial-state and solver-option names."""
    if not isinstance(case, Case):
        case = load_case(case)
    groups: dict[str, dict] = {"parameters": {}, "initial": {}, "options": {}}
    owners = (
        ("parameters", Parameters.names()),
        ("initial", InitialState.names()),
        ("options", SolverOptions.names()),
    )
    known = [name for _, names in owners for name in names]
    for key, value in overrides.items():
        for group, names in owners:
            if key in names:
                groups[group][key] = value
                break
        else:
            raise OscillatorError(
                f"unknown setting {key!r}{_suggest(key, known)} (parameters, initial state "
                f"t0 x1 v1 x2 v2, or solver options {', '.join(SolverOptions.names())})",
                field=key,
            )
    return dataclasses.replace(
        case,
        parameters=dataclasses.replace(case.parameters, **groups["parameters"]),
        initial=dataclasses.replace(case.initial, **groups["initial"]),
        options=dataclasses.replace(case.options, **groups["options"]),
        t_end=case.t_end if t_end is None else t_end,
    )


def _time(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or math.isnan(value):
        raise OscillatorError(f"{name} must be a time in s (a number), got {value!r}", field=name)
    return float(value)


def _grid(t_eval: object) -> np.ndarray:
    """``t_eval`` as a 1-D array of finite, increasing times."""
    try:
        grid = np.asarray(t_eval, dtype=float)
    except (TypeError, ValueError) as exc:
        raise OscillatorError(f"t_eval must be a sequence of times in s, got {t_eval!r}", field="t_eval") from exc
    if grid.ndim != 1 or not np.isfinite(grid).all() or np.any(np.diff(grid) <= 0):
        raise OscillatorError(
            "t_eval must be a one-dimensional sequence of finite, strictly increasing times in s", field="t_eval"
        )
    return grid


def simulate(
    case: Case | str | Path,
    *,
    t_end: float | None = None,
    t_eval: Sequence[float] | np.ndarray | None = None,
    record_trajectory: bool = True,
    progress: Callable[[float], None] | None = None,
    keep_events_from: float | None = None,
    **overrides: float,
) -> Result:
    """Simulate a case from its start to ``t_end``.

    Parameters
    ----------
    case : Case, str or Path
        A :class:`Case`, a shipped case's name (``"instance-1"``) or a case file's path.
    t_end : float, optional
        End time (s); the case's by default.
    t_eval : array_like, optional
        Record the trajectory on this grid instead of at CVODE's steps.
    record_trajectory : bool
        Keep trajectory rows (events and the energy audit are always kept).
    progress : callable, optional
        Called with the current time after every solver step (keep it cheap).
    keep_events_from : float, optional
        Keep only the events at or after this time in ``Result.events`` (``stats["events"]``
        counts them all). With the trajectory off too, memory stays flat in the run's length.
    **overrides
        Any parameter (``Omega=1.7``), initial value (``x1=3.1``) or solver option
        (``rtol=1e-12``, ``grazing_velocity_tolerance=0.05``).

    Returns
    -------
    Result
        Events, trajectory, energy audit and solver statistics.

    Raises
    ------
    OscillatorError
        Bad input, or a solver failure or guard (with the time, domains and state).  When the
        run had started, ``error.result`` holds the partial :class:`Result` up to the last point
        reached, with ``status == "failed"``; a ``KeyboardInterrupt`` carries one the same way,
        with ``status == "interrupted"``.

    Examples
    --------
    >>> from oscillator import simulate
    >>> result = simulate("instance-1")
    >>> result.events[["t", "mass", "kind", "to_domain"]].round(4).values.tolist()
    [[1.1746, 2, 'sliding_vanish', 1], [1.289, 1, 'sliding_vanish', 2]]
    """
    case = resolve_case(case, t_end=t_end, **overrides)
    supervisor = Supervisor(
        case.parameters,
        case.options,
        t_eval=None if t_eval is None else _grid(t_eval),
        record_trajectory=bool(record_trajectory),
        progress=progress,
        keep_events_from=-math.inf if keep_events_from is None else _time(keep_events_from, "keep_events_from"),
    )
    try:
        record = supervisor.run(case.initial.t0, case.initial.y, case.t_end)
    except (OscillatorError, KeyboardInterrupt) as error:
        partial = getattr(error, "partial", None)
        if partial is not None and partial.mode_initial is not None and partial.y_final is not None:
            status = "interrupted" if isinstance(error, KeyboardInterrupt) else "failed"
            failure = str(error) or "interrupted by the user"
            with contextlib.suppress(*ARITHMETIC_ERRORS), strict_arithmetic():
                error.result = Result.from_record(case, partial, status=status, failure=failure)  # type: ignore[attr-defined]
        raise
    try:
        with strict_arithmetic():
            return Result.from_record(case, record)
    except ARITHMETIC_ERRORS as exc:
        raise OscillatorError(
            f"the energy audit left floating point ({exc}); give parameters and a start of physical size",
            field="parameters",
        ) from exc
