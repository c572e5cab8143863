"""The library's own exception type.

Every refusal of bad input or failure of the solver is an :class:`OscillatorError` whose message
names the field, the value and the fix, so that callers (the CLI, a sweep) can report it in one
line instead of a traceback.
"""

from __future__ import annotations

__all__ = ["OscillatorError"]


class OscillatorError(ValueError):
    """Bad input or a failed simulation, with a message that names the field and the fix.

    Parameters
    ----------
    message : str
        The complete, human-readable explanation.
    field : str or None
        The parameter, case-file key or option concerned, when there is one.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field
