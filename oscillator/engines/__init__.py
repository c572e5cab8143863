"""Integrators behind one interface: the supervisor drives an :class:`Engine`, never a solver.

An engine integrates the smooth field of one mode and watches its root functions
(:mod:`oscillator.model.roots`).  The supervisor (:mod:`oscillator.hybrid.supervisor`) calls

* ``reset(mode, t, y)`` at the start and after every switch: integrate ``mode``'s field from
  ``(t, y)`` (``y`` is the 8-vector of the state and the four work quadratures);
* ``advance(target, t_stop=..., one_step=...)`` to go on: the engine returns a :class:`Step` at the
  first root, at ``target``, or - with ``one_step`` - after one internal step; never past
  ``t_stop``.

* ``close()`` at the end, to free what the integrator holds.

The engines:

* ``"cvode"`` - :class:`~oscillator.engines.cvode_c.CCvodeEngine`, SUNDIALS CVODE (Adams) with
  its rootfinding, called through its C API with compiled callbacks: the default;
* ``"sksundae"`` - :class:`~oscillator.engines.sksundae.SksundaeEngine`, the same through
  scikit-sundae's Python API: the fallback where SUNDIALS' libraries cannot be loaded;
* ``"dop853"`` - :class:`~oscillator.engines.dop853_engine.Dop853Engine`, the explicit Runge-Kutta pair
  DOP853 with CVODE's root search on its dense output, compiled whole: the engine of the
  many-start analyses (:mod:`oscillator.hybrid.batch`), checked against CVODE's events;
* ``"scipy"`` - :class:`~oscillator.engines.scipy.ScipyEngine`, SciPy's ``solve_ivp`` (DOP853)
  with its events: the baseline of the benchmarks.
"""

from __future__ import annotations

import enum
import importlib
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from oscillator.errors import InputError
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.model.parameters import Parameters, SolverOptions
    from oscillator.model.phase_space import Mode

__all__ = [
    "ENGINES",
    "Engine",
    "EngineChoice",
    "EngineFailure",
    "EngineInfo",
    "Step",
    "StepKind",
    "build_engine",
    "check_engine",
    "default_engine",
    "describe",
    "engine_factory",
]


class StepKind(enum.Enum):
    """Why an engine returned."""

    ROOT = "root"  #: a root function vanished (``Step.roots`` says which)
    TARGET = "target"  #: the requested target (or ``t_stop``) was reached
    STEP = "step"  #: one internal step was taken (``one_step=True``)


@dataclass(frozen=True, slots=True)
class Step:
    """One return of an engine: the time, the state (8 values, a fresh array) and why."""

    t: float
    y: np.ndarray
    kind: StepKind
    roots: tuple[int, ...] = ()

    @property
    def fired(self) -> int:
        """The roots as the bits ``1 << root`` (what the switching rules take)."""
        bits = 0
        for root in self.roots:
            bits |= 1 << root
        return bits


class EngineFailure(Exception):
    """The integrator failed; ``flag`` is its code and the message says what it reported."""

    def __init__(self, message: str, flag: int | str) -> None:
        super().__init__(message)
        self.flag = flag


class Engine(Protocol):
    """What the supervisor needs of an integrator."""

    #: The engine's name, recorded in ``Result.stats.engine``.
    name: str
    #: The state's length: 8 (``x1, v1, x2, v2`` and the four works), or 24 with the derivative
    #: of the flow carried along (the compiled CVODE engine, ``variational=True``); an engine
    #: without it is taken to integrate 8.
    size: int

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        """Integrate ``mode``'s field from ``(t, y)`` from now on."""
        ...

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        """Go on to the first root, to ``target`` or, with ``one_step``, one internal step.

        Raises :class:`EngineFailure` when the integrator fails.
        """
        ...

    @property
    def rhs_evaluations(self) -> int:
        """Evaluations of the field so far."""
        ...

    @property
    def restarts(self) -> int:
        """(Re-)initialisations so far."""
        ...

    def close(self) -> None:
        """Free what the integrator holds; the engine is not used afterwards."""
        ...


@dataclass(frozen=True)
class EngineInfo:
    """What an engine says of itself: its ``name`` (``simulate(engine=...)``, ``--engine``), where
    its class is (``module:Class``, imported only when the engine is chosen), its ``method`` as a
    run's ``run.json`` records it, and the ``solver`` its failures name."""

    name: str
    entry: str
    method: str
    solver: str


#: The engines, by name: a new engine is its module and one entry here.
ENGINES = {
    info.name: info
    for info in (
        EngineInfo(
            "cvode",
            "oscillator.engines.cvode_c:CCvodeEngine",
            "CVODE (SUNDIALS, C API with compiled callbacks), Adams, root finding",
            "CVODE",
        ),
        EngineInfo(
            "sksundae",
            "oscillator.engines.sksundae:SksundaeEngine",
            "CVODE (SUNDIALS, through scikit-sundae's Python API), Adams, root finding",
            "CVODE",
        ),
        EngineInfo(
            "dop853",
            "oscillator.engines.dop853_engine:Dop853Engine",
            "DOP853 (SciPy's coefficients) with CVODE's root search on its dense output, compiled",
            "DOP853",
        ),
        EngineInfo(
            "scipy", "oscillator.engines.scipy:ScipyEngine", "SciPy solve_ivp (DOP853), events", "SciPy solve_ivp"
        ),
    )
}


def describe(name: str) -> EngineInfo:
    """What the engine called ``name`` says of itself; an engine built by a user's callable
    (not registered) is described by its name alone."""
    return ENGINES.get(name, EngineInfo(name, "", name, f"the engine {name!r}"))


def check_engine(name: object, *, among: Sequence[str] | None = None, field: str = "engine") -> str:
    """``name`` if it names an engine of :data:`ENGINES` (of ``among`` where given: a command's
    choices), else refused naming ``field`` and the engines it may name."""
    names = tuple(ENGINES) if among is None else tuple(among)
    if not isinstance(name, str) or name not in names:
        raise InputError(f"{field} must be one of {', '.join(names)}, got {shown(name)}", field=field)
    return name


def engine_factory(name: str) -> type:
    """The engine class called ``name`` (see :data:`ENGINES`); its constructor takes
    ``(params: Parameters, options: SolverOptions)``."""
    module, _, cls = ENGINES[check_engine(name)].entry.partition(":")
    engine: type = getattr(importlib.import_module(module), cls)
    return engine


#: What ``simulate(engine=...)`` takes: ``None`` (the default engine), an engine's name, or a
#: callable that builds an engine.
EngineChoice = str | Callable[["Parameters", "SolverOptions"], Engine] | None


def default_engine() -> str:
    """``"cvode"`` where SUNDIALS' C libraries load, else ``"sksundae"`` with a one-line warning."""
    from oscillator.engines.sundials import SundialsUnavailable, load

    try:
        load()
    except SundialsUnavailable as reason:
        warnings.warn(
            f"the compiled CVODE engine is not available ({reason}); using scikit-sundae's Python API, "
            f"several times slower",
            RuntimeWarning,
            stacklevel=3,
        )
        return "sksundae"
    return "cvode"


def build_engine(
    choice: EngineChoice, params: Parameters, options: SolverOptions, *, variational: bool = False
) -> Engine:
    """An engine ready for :meth:`Engine.reset`: the default one (``None``), the one called
    ``choice``, or ``choice(params, options)``.  With ``variational``, an engine integrating the
    derivative of the flow with the state: the compiled CVODE one (the default) or the compiled
    DOP853 one (only they can)."""
    if variational:
        return _variational_engine(choice, params, options)
    if choice is None:
        choice = default_engine()
    factory = choice if callable(choice) else engine_factory(choice)
    try:
        engine: Engine = factory(params, options)
    except _unavailable() as reason:
        raise InputError(f"engine {choice!r} is not available here: {reason}", field="engine") from reason
    return engine


def _variational_engine(choice: EngineChoice, params: Parameters, options: SolverOptions) -> Engine:
    if choice == "dop853":
        from oscillator.engines.dop853_engine import Dop853Engine

        return Dop853Engine(params, options, variational=True)
    if choice not in (None, "cvode"):
        raise InputError(
            "the derivative of the flow (periodic orbits) needs the compiled CVODE engine or the "
            f"compiled DOP853 one, not {shown(choice)}",
            field="engine",
        )
    from oscillator.engines.cvode_c import CCvodeEngine

    try:
        return CCvodeEngine(params, options, variational=True)
    except _unavailable() as reason:
        raise InputError(f"the compiled CVODE engine is not available here: {reason}", field="engine") from reason


def _unavailable() -> type[Exception]:
    from oscillator.engines.sundials import SundialsUnavailable

    return SundialsUnavailable
