"""The library's exceptions.

Every refusal of bad input and every failure of a run is an :class:`OscillatorError` whose message
names the argument, the value and the fix, so that callers (the command line, a sweep) can report
it in one line instead of a traceback.  Two kinds are told apart by type:

* :class:`InputError` - the input was refused before anything ran;
* :class:`SimulationFailed` - a run started and stopped (a solver failure or a guard); it carries
  the partial :class:`~oscillator.hybrid.result.Result` up to the last point reached.

A Ctrl-C during a run or a continuation raises :class:`Interrupted`, a ``KeyboardInterrupt`` that
carries the partial result the same way (a ``Result``, or the ``Branch`` traced so far).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.hybrid.result import Result
    from oscillator.orbits.continuation import Branch

__all__ = ["InputError", "Interrupted", "OscillatorError", "SimulationFailed"]


class OscillatorError(ValueError):
    """Bad input or a failed run, with a message that names the argument and the fix.

    Parameters
    ----------
    message : str
        The complete, human-readable explanation.
    field : str or None
        The library's name of the parameter, case-file key or argument concerned (``"Omega"``,
        ``"folder"``, ``"t_eval"``), when there is one; the command line maps it to its flag.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field


class InputError(OscillatorError):
    """The input was refused before anything ran: nothing was computed or written."""


class SimulationFailed(OscillatorError):
    """A run started and could not finish: the solver failed or a guard stopped it.

    Attributes
    ----------
    result : Result or None
        The partial result up to the last point reached (``result.status`` is
        ``Status.FAILED``); ``None`` only while the supervisor raises it, before
        :func:`oscillator.simulate` attaches the result.
    """

    def __init__(self, message: str, *, field: str | None = None, result: Result | None = None) -> None:
        super().__init__(message, field=field)
        self.result = result


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a run or a continuation; ``result`` is what was computed so far: the partial
    ``Result`` of :func:`~oscillator.simulate` (``Status.INTERRUPTED``), or the ``Branch`` of
    :func:`~oscillator.continue_orbit` traced so far (``complete`` False)."""

    def __init__(self, result: Result | Branch) -> None:
        super().__init__("interrupted by the user")
        self.result = result
