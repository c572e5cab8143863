"""oscillator: event-driven simulation of a 2-DOF frictional oscillator with elastic stops.

The model, domains, G-functions and switching theorems are those of the article in
``shared/paper`` (see ``docs/model.md`` for the map from the article to the code).
"""

from oscillator._errors import OscillatorError
from oscillator.cases import Case, ExpectedEvent, case_names, load_case
from oscillator.events import Event, EventKind
from oscillator.parameters import InitialState, Parameters, SolverOptions, SweepSettings
from oscillator.phase_space import Mode
from oscillator.result import Result
from oscillator.simulation import resolve_case, simulate

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

__version__ = "0.1.0"
