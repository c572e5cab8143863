"""The library's exceptions.

Every refusal of bad input and every failure of a run is an :class:`OscillatorError` whose message
names the argument, the value and the fix, so that callers (the command line, a sweep) can report
it in one line instead of a traceback.  Two kinds are told apart by type:

* :class:`InputError` - the input was refused before anything ran;
* :class:`SimulationFailed` - a run started and stopped (a solver failure or a guard); it carries
  the partial :class:`~oscillator.hybrid.result.Result` up to the last point reached.

A Ctrl-C during a run or a continuation raises :class:`Interrupted`, a ``KeyboardInterrupt`` that
carries the partial result the same way (a ``Result``, or the ``Branch`` or ``Curve`` traced so far).
"""

from __future__ import annotations

import enum
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.hybrid.result import Result
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.curves import Curve

__all__ = ["InputError", "Interrupted", "OscillatorError", "Reason", "SimulationFailed"]


class Reason(enum.StrEnum):
    """Why a run, an orbit or a point of a branch did not succeed: what a program reads (the
    message says it to a person)."""

    SOLVER_FAILURE = "solver_failure"
    """The integrator returned an error flag (CVODE's, or SciPy's)."""
    STEP_LIMIT = "step_limit"
    """More than ``max_num_steps`` steps without a switch."""
    UNSEEN_CROSSING = "unseen_crossing"
    """A guard: the state crossed a boundary between two steps, unseen by the root finding."""
    STALL = "stall"
    """A guard: the solver keeps stopping at roots at one instant without a switch."""
    STORM = "storm"
    """A guard: more than ``storm_events`` events within ``storm_window``, or endless switching
    at one instant."""
    MAX_EVENTS = "max_events"
    """More than ``max_events`` events in all."""
    MAX_ROWS = "max_rows"
    """The trajectory passed ``max_trajectory_rows`` rows."""
    ARITHMETIC = "arithmetic"
    """The forces left floating point (an overflow or an invalid operation)."""
    INTERRUPTED = "interrupted"
    """Ctrl-C."""
    NO_CONVERGENCE = "no_convergence"
    """Newton's method (an orbit, a corrector step) did not converge."""
    SINGULAR = "singular"
    """Newton's system is singular (a multiplier 1: a fold, or a family of orbits)."""
    NO_MONODROMY = "no_monodromy"
    """No monodromy matrix: the orbit grazes a boundary (the saltation matrix is undefined)."""
    NOT_DIFFERENTIABLE = "not_differentiable"
    """No derivative in the parameters: the orbit sits on a grazing, sliding or rest-threshold point."""
    NO_ORBIT = "no_orbit"
    """No orbit where one was sought (a located bifurcation's side, the end of a range)."""
    MAX_POINTS = "max_points"
    """A continuation computed ``max_points`` points before it reached its end."""
    REFUSED = "refused"
    """The input was refused before anything ran (:class:`InputError`: a sweep's value the model
    does not admit)."""

    @property
    def guard(self) -> bool:
        """Stopped by one of the run's guards, not by the integrator."""
        return self in (
            Reason.UNSEEN_CROSSING,
            Reason.STALL,
            Reason.STORM,
            Reason.MAX_EVENTS,
            Reason.MAX_ROWS,
            Reason.STEP_LIMIT,
        )


class OscillatorError(ValueError):
    """Bad input or a failed run, with a message that names the argument and the fix.

    Parameters
    ----------
    message : str
        The complete, human-readable explanation.  It names the library's arguments as
        :meth:`said_as` reads them: it begins with ``field`` where it is about that argument,
        and quotes any other argument in backticks (```guess```).
    field : str or None
        The library's name of the parameter, case-file key or argument concerned (``"Omega"``,
        ``"folder"``, ``"t_eval"``), when there is one; the command line maps it to its flag.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field

    def said_as(self, names: Mapping[str, str]) -> str:
        """The message with the arguments it names said as ``names`` calls them (the command
        line's flags: ``{"start": "--from"}``): the field it begins with, and every argument it
        quotes in backticks; a name ``names`` lacks stays as the library says it."""
        text = str(self)
        field = self.field or ""
        if field in names and text.startswith(field):
            text = names[field] + text[len(field) :]
        return re.sub(r"`(\w+)`", lambda m: names.get(m.group(1), m.group(1)), text)


class InputError(OscillatorError):
    """The input was refused before anything ran: nothing was computed or written."""


class SimulationFailed(OscillatorError):
    """A run started and could not finish: the solver failed or a guard stopped it.

    Attributes
    ----------
    reason : Reason
        Why, for a program to read.
    result : Result or None
        The partial result up to the last point reached (``result.status`` is
        ``Status.FAILED``, ``result.reason`` this reason); ``None`` only while the supervisor
        raises it, before :func:`oscillator.simulate` attaches the result, and for the orbit
        code's failures.
    """

    def __init__(self, message: str, *, reason: Reason, field: str | None = None, result: Result | None = None) -> None:
        super().__init__(message, field=field)
        self.reason = reason
        self.result = result


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a run or a continuation; ``result`` is what was computed so far: the partial
    ``Result`` of :func:`~oscillator.simulate` (``Status.INTERRUPTED``), the ``Branch`` of
    :func:`~oscillator.continue_orbit` traced so far (``complete`` False), or the ``Curve`` of
    :func:`~oscillator.orbits.curves.trace_curve` traced so far (an unfinished end ``"interrupted"``)."""

    def __init__(self, result: Result | Branch | Curve) -> None:
        super().__init__("interrupted by the user")
        self.result = result
