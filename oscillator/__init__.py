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

from oscillator import presenting as _presenting
from oscillator import views as _views
from oscillator.threads import one_blas_thread as _one_blas_thread
from oscillator.version import __version__ as __version__

_one_blas_thread()  # before NumPy loads its BLAS (oscillator.threads says why)

#: ``typing.TYPE_CHECKING`` without importing ``typing``: the command starts faster, and a
#: Ctrl-C in its first milliseconds reaches code that can catch it sooner.
TYPE_CHECKING = False

#: Public name -> the module that defines it.
_EXPORTS = {
    "Case": "oscillator.io.cases",
    "ExpectedEvent": "oscillator.io.cases",
    "case_names": "oscillator.io.cases",
    "load_case": "oscillator.io.cases",
    "resolve_case": "oscillator.io.cases",
    "Event": "oscillator.model.events",
    "EventKind": "oscillator.model.events",
    "InitialState": "oscillator.model.parameters",
    "Parameters": "oscillator.model.parameters",
    "SolverOptions": "oscillator.model.parameters",
    "SweepSettings": "oscillator.model.parameters",
    "Mode": "oscillator.model.phase_space",
    "OscillatorError": "oscillator.errors",
    "InputError": "oscillator.errors",
    "SimulationFailed": "oscillator.errors",
    "Interrupted": "oscillator.errors",
    "Reason": "oscillator.errors",
    "Result": "oscillator.hybrid.result",
    "SaveAt": "oscillator.hybrid.recording",
    "Segment": "oscillator.hybrid.record",
    "Status": "oscillator.hybrid.result",
    "EnergyAudit": "oscillator.hybrid.result",
    "SolverStats": "oscillator.hybrid.result",
    "simulate": "oscillator.hybrid.simulate",
    "FrictionChain": "oscillator.model.chains",
    "ChainResult": "oscillator.hybrid.chain_run",
    "simulate_chain": "oscillator.hybrid.chain_run",
    "load_system": "oscillator.io.chains",
    "read_run": "oscillator.saved",
    "Orbit": "oscillator.orbits.shooting",
    "find_orbit": "oscillator.orbits.shooting",
    "ChainOrbit": "oscillator.orbits.chain_orbits",
    "ChainSensitivities": "oscillator.orbits.chain_sensitivity",
    "ChainNoise": "oscillator.orbits.chain_noise",
    "chain_noise": "oscillator.orbits.chain_noise",
    "frequency_sweep": "oscillator.orbits.chain_response",
    "worst_over": "oscillator.designing.chain_design",
    "Response": "oscillator.orbits.response",
    "FrequencyResponse": "oscillator.attractors.frequency",
    "frequency_response": "oscillator.attractors.frequency",
    "response": "oscillator.orbits.response",
    "Noise": "oscillator.orbits.noise",
    "noise": "oscillator.orbits.noise",
    "Sensitivities": "oscillator.orbits.sensitivity",
    "Design": "oscillator.designing.optimise",
    "design": "oscillator.designing.optimise",
    "Calibration": "oscillator.calibrating.fit",
    "calibrate": "oscillator.calibrating.fit",
    "sensitivities": "oscillator.orbits.sensitivity",
    "explore": "oscillator.exploring",
    "Explorer": "oscillator.exploring.app",
    "Branch": "oscillator.orbits.branch",
    "continue_orbit": "oscillator.orbits.continuation",
    "Attractor": "oscillator.attractors.grouping",
    "Attractors": "oscillator.attractors.finding",
    "AttractorSettings": "oscillator.attractors.mapping",
    "Axis": "oscillator.analysis.axes",
    "Basins": "oscillator.attractors.basins",
    "find_basins": "oscillator.attractors.basins",
    "Atlas": "oscillator.attractors.atlas",
    "AtlasSettings": "oscillator.attractors.atlas",
    "regime_atlas": "oscillator.attractors.atlas",
    "Curve": "oscillator.orbits.curves",
    "trace_curve": "oscillator.orbits.curves",
    "find_attractors": "oscillator.attractors.finding",
    "LyapunovSpectrum": "oscillator.attractors.lyapunov",
    "lyapunov": "oscillator.attractors.lyapunov",
    "AttractorsOver": "oscillator.attractors.following",
    "follow_attractors": "oscillator.attractors.following",
}

__all__ = [
    "Atlas",
    "AtlasSettings",
    "Attractor",
    "AttractorSettings",
    "Attractors",
    "AttractorsOver",
    "Axis",
    "Basins",
    "Branch",
    "Calibration",
    "Case",
    "ChainNoise",
    "ChainOrbit",
    "ChainResult",
    "ChainSensitivities",
    "Curve",
    "Design",
    "EnergyAudit",
    "Event",
    "EventKind",
    "ExpectedEvent",
    "Explorer",
    "FrequencyResponse",
    "FrictionChain",
    "InitialState",
    "InputError",
    "Interrupted",
    "LyapunovSpectrum",
    "Mode",
    "Noise",
    "Orbit",
    "OscillatorError",
    "Parameters",
    "Reason",
    "Response",
    "Result",
    "SaveAt",
    "Segment",
    "Sensitivities",
    "SimulationFailed",
    "SolverOptions",
    "SolverStats",
    "Status",
    "SweepSettings",
    "calibrate",
    "case_names",
    "chain_noise",
    "continue_orbit",
    "design",
    "explore",
    "find_attractors",
    "find_basins",
    "find_orbit",
    "follow_attractors",
    "frequency_response",
    "frequency_sweep",
    "load_case",
    "load_system",
    "lyapunov",
    "noise",
    "read_run",
    "regime_atlas",
    "resolve_case",
    "response",
    "sensitivities",
    "simulate",
    "simulate_chain",
    "trace_curve",
    "worst_over",
]

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.atlas import Atlas, AtlasSettings, regime_atlas
    from oscillator.attractors.basins import Basins, find_basins
    from oscillator.attractors.finding import Attractors, find_attractors
    from oscillator.attractors.following import AttractorsOver, follow_attractors
    from oscillator.attractors.frequency import FrequencyResponse, frequency_response
    from oscillator.attractors.grouping import Attractor
    from oscillator.attractors.lyapunov import LyapunovSpectrum, lyapunov
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.calibrating.fit import Calibration, calibrate
    from oscillator.designing.chain_design import worst_over
    from oscillator.designing.optimise import Design, design
    from oscillator.errors import InputError, Interrupted, OscillatorError, Reason, SimulationFailed
    from oscillator.exploring import explore
    from oscillator.exploring.app import Explorer
    from oscillator.hybrid.chain_run import ChainResult, simulate_chain
    from oscillator.hybrid.record import Segment
    from oscillator.hybrid.recording import SaveAt
    from oscillator.hybrid.result import EnergyAudit, Result, SolverStats, Status
    from oscillator.hybrid.simulate import simulate
    from oscillator.io.cases import Case, ExpectedEvent, case_names, load_case, resolve_case
    from oscillator.io.chains import load_system
    from oscillator.model.chains import FrictionChain
    from oscillator.model.events import Event, EventKind
    from oscillator.model.parameters import InitialState, Parameters, SolverOptions, SweepSettings
    from oscillator.model.phase_space import Mode
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.chain_noise import ChainNoise, chain_noise
    from oscillator.orbits.chain_orbits import ChainOrbit
    from oscillator.orbits.chain_response import frequency_sweep
    from oscillator.orbits.chain_sensitivity import ChainSensitivities
    from oscillator.orbits.continuation import continue_orbit
    from oscillator.orbits.curves import Curve, trace_curve
    from oscillator.orbits.noise import Noise, noise
    from oscillator.orbits.response import Response, response
    from oscillator.orbits.sensitivity import Sensitivities, sensitivities
    from oscillator.orbits.shooting import Orbit, find_orbit
    from oscillator.saved import read_run


# The results' plot/save/_repr_html_ go through this (the computing layers import no report).
_presenting.register(_views.Views())


def __getattr__(name: str) -> object:
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'oscillator' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
