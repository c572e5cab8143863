"""oscillator: event-driven simulation of a 2-DOF frictional oscillator with elastic stops.

The model, domains, G-functions and switching theorems are those of the article *On the
discontinuous dynamics of a class of 2-DOF frictional vibration systems with asymmetric elastic
constraints*; ``docs/model.md`` states the model and maps the article to the code.

The names below are imported on first use (PEP 562), so that ``import oscillator`` and the
command's start, its ``--help`` and its refusals of bad input do not wait for the numerical
libraries.
"""

from __future__ import annotations

import importlib

#: ``typing.TYPE_CHECKING`` without importing ``typing``: the command starts faster, and a
#: Ctrl-C in its first milliseconds reaches code that can catch it sooner.
TYPE_CHECKING = False

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_EXPORTS = {
    "Case": "oscillator.cases",
    "ExpectedEvent": "oscillator.cases",
    "case_names": "oscillator.cases",
    "load_case": "oscillator.cases",
    "resolve_case": "oscillator.cases",
    "Event": "oscillator.events",
    "EventKind": "oscillator.events",
    "InitialState": "oscillator.parameters",
    "Parameters": "oscillator.parameters",
    "SolverOptions": "oscillator.parameters",
    "SweepSettings": "oscillator.parameters",
    "Mode": "oscillator.phase_space",
    "OscillatorError": "oscillator._errors",
    "Result": "oscillator.result",
    "simulate": "oscillator.simulation",
}

__all__ = [
    "Case",
    "Event",
    "EventKind",
    "ExpectedEvent",
    "InitialState",
    "Mode",
    "OscillatorError",
    "Parameters",
    "Result",
    "SolverOptions",
    "SweepSettings",
    "case_names",
    "load_case",
    "resolve_case",
    "simulate",
]

if TYPE_CHECKING:  # pragma: no cover
    from oscillator._errors import OscillatorError
    from oscillator.cases import Case, ExpectedEvent, case_names, load_case, resolve_case
    from oscillator.events import Event, EventKind
    from oscillator.parameters import InitialState, Parameters, SolverOptions, SweepSettings
    from oscillator.phase_space import Mode
    from oscillator.result import Result
    from oscillator.simulation import simulate


def __getattr__(name: str) -> object:
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'oscillator' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
