"""The settings of the periodic orbits' computations, checked before anything is computed:
:func:`~oscillator.orbits.shooting.find_orbit`'s period, tolerance, Newton steps and guess, and
:func:`~oscillator.orbits.continuation.continue_orbit`'s range and steps, and the frequency
response's span and counts (:func:`check_frequency`).

Nothing here integrates: the command line checks its options with these before it loads the
numerical libraries, so that a refusal is quick (``oscillator orbit ... --period 1000000``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from oscillator.errors import InputError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.parameters import Parameters, check_count, real_argument
from oscillator.text import shown

__all__ = [
    "DEFAULT_STEP",
    "MAX_ITERATIONS",
    "MAX_PERIOD",
    "MAX_POINTS",
    "MAX_TRANSIENT",
    "MIN_STEP",
    "TOL",
    "ContinuationSettings",
    "check_frequency",
    "check_guess",
    "check_orbit_settings",
    "check_settings",
]

#: The longest return looked for, in forcing periods: a longer one is a motion to simulate.
MAX_PERIOD = 1000
#: The most Newton steps allowed, and the longest transient (forcing periods).
MAX_ITERATIONS = 200
MAX_TRANSIENT = 1_000_000
#: Newton's tolerance on the return's residual unless the caller sets it.
TOL = 1e-9

#: The default largest step, the smallest allowed and the most points (``continue_orbit``).
DEFAULT_STEP = 1 / 40
MIN_STEP = 1e-6
MAX_POINTS = 100_000


def check_orbit_settings(period: object, tol: object = TOL, max_iterations: object = 20) -> tuple[int, float, int]:
    """``period``, ``tol`` and ``max_iterations`` checked (:func:`~oscillator.orbits.shooting.find_orbit`)."""
    return (
        check_count(period, "period", 1, MAX_PERIOD),
        real_argument(tol, "tol", positive=True),
        check_count(max_iterations, "max_iterations", 1, MAX_ITERATIONS),
    )


def check_guess(guess: object) -> np.ndarray:
    """``guess`` as four finite floats ``(x1, v1, x2, v2)``."""
    try:
        values = [real_argument(v, "guess") for v in guess]  # type: ignore[attr-defined]
    except (TypeError, InputError):
        values = []
    if len(values) != 4:
        raise InputError(f"guess must be four finite numbers (x1, v1, x2, v2), got {shown(guess)}", field="guess")
    return np.array(values)


def _check_range(
    case: Case | str, param: str, start: object, stop: object, overrides: dict[str, Any], locate_tol: float
) -> tuple[float, float]:
    """``start`` and ``stop`` as valid values of ``param``, far enough apart to continue."""
    Parameters.check_name(param)
    if param in overrides:
        raise InputError(f"{param} is the continued parameter; give its range with start and stop", field=param)
    values = real_argument(start, "start"), real_argument(stop, "stop")
    for name, value in zip(("start", "stop"), values, strict=True):
        try:
            resolve_case(case, **{**overrides, param: value})
        except InputError as error:
            raise InputError(f"{name} = {value!r} is not a valid {param}: {error}", field=name) from None
    width = abs(values[1] - values[0])
    if width < 10 * locate_tol or width < 1e-12 * max(abs(values[0]), abs(values[1])):
        least = max(10 * locate_tol, 1e-12 * abs(values[0]))
        raise InputError(
            f"`stop` must be at least {least:.3g} away from `start` (10 times the location "
            f"tolerance), got {values[1]!r} and {values[0]!r}",
            field="stop",
        )
    return values


@dataclass(frozen=True)
class ContinuationSettings:
    """:func:`~oscillator.orbits.continuation.continue_orbit`'s numeric settings, checked (:func:`check_settings`)."""

    start: float
    stop: float
    period: int
    tol: float
    locate_tol: float
    max_points: int
    step: float  #: the largest step, as a fraction of ``|stop - start|``


def check_settings(
    case: Case | str,
    *,
    param: str,
    start: object,
    stop: object,
    period: object = 1,
    section: object = None,
    guess: object = None,
    transient: object = None,
    step: object = None,
    max_points: object = 400,
    tol: object = 1e-9,
    locate_tol: object = 1e-9,
    progress: object = None,
    **overrides: object,
) -> ContinuationSettings:
    """Check :func:`~oscillator.orbits.continuation.continue_orbit`'s arguments without computing
    anything (the command line does so before it creates its folder).

    Raises
    ------
    InputError
        The first argument that is refused, named.
    """
    period_, tol_, _ = check_orbit_settings(period, tol, 1)
    locate_tol_ = real_argument(locate_tol, "locate_tol", positive=True)
    start_, stop_ = _check_range(case, param, start, stop, overrides, locate_tol_)
    max_points_ = check_count(max_points, "max_points", 2, MAX_POINTS)
    step_ = DEFAULT_STEP if step is None else real_argument(step, "step", positive=True)
    if not MIN_STEP <= step_ <= 1:
        raise InputError(
            f"step must be from {MIN_STEP:g} to 1 (a fraction of |stop - start|), got {shown(step)}", field="step"
        )
    if progress is not None and not callable(progress):
        raise InputError(f"progress must be a function of the fraction done, got {shown(progress)}", field="progress")
    if guess is not None:
        check_guess(guess)
    if transient is not None:
        check_count(transient, "transient", 0, MAX_TRANSIENT)
    if section is not None:
        real_argument(section, "section")
    return ContinuationSettings(start_, stop_, period_, tol_, locate_tol_, max_points_, step_)


def check_frequency(
    case: Case, param: str, span: object, *, period: int = 1, seeds: int = 5, sweep: int = 41, max_points: int = 3000
) -> tuple[float, float]:
    """:func:`~oscillator.attractors.frequency.frequency_response`'s arguments checked before any
    work (the command line does so before it creates its folder): the span, as ``(low, high)``;
    else the first refused, named."""
    Parameters.check_name(param, "param")
    check_count(max_points, "max_points", 2, 100_000)
    check_count(period, "period", 1, 1000)
    check_count(seeds, "seeds", 2, 1000)
    check_count(sweep, "sweep", 2, 100_000)
    try:
        low, high = (float(value) for value in span)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(f"span must be two numbers (low, high), got {span!r}", field="span") from None
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise InputError(
            f"span must be two finite numbers, low < high, got {span!r}; give the lower value first", field="span"
        )
    for value in (low, high):
        resolve_case(case, **{param: value})  # each end must be a valid value, or it is refused by name
    return low, high
