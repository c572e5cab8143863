"""System parameters, initial state and solver settings (Sec. 3.1 and 6 of the article).

The names are the article's, in ASCII: ``m1 m2 C1..C5 K1..K6 mu_k mu_s d d1 Q1 Q2 phi1 phi2 P1
P2 Omega g``.  Every object here is a frozen dataclass validated in ``__post_init__``; a bad value
raises :class:`~oscillator.OscillatorError` naming the field and the fix.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, fields
from typing import Any, TypeGuard

from oscillator.errors import InputError
from oscillator.text import shown

__all__ = [
    "InitialState",
    "Parameters",
    "SolverOptions",
    "SweepSettings",
    "as_float",
    "is_number",
    "is_whole_number",
    "real_argument",
]


#: The largest magnitude a parameter or initial value may have.  The fields raise states to the
#: fourth power and multiply them by parameters; past this, forces leave floating point.
MAX_MAGNITUDE = 1e100
#: The smallest magnitude a nonzero parameter or initial value may have.  Forces are divided by
#: the masses, the forcing period is ``2 pi / Omega``, and a root function of subnormal size
#: cannot be located; 1e-100 of any unit is zero in any physical system.
MIN_MAGNITUDE = 1e-100
#: The most values a sweep may have, and the most forcing periods it may record per value.
MAX_SWEEP_STEPS = 100_000
MAX_SWEEP_RECORD = 100_000


def is_number(value: Any) -> bool:
    """A real number (Python's or NumPy's), not a boolean."""
    if type(value) is float:  # the common case, without the abstract classes' checks (every case resolved)
        return True
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def is_finite_number(value: Any) -> TypeGuard[float]:
    """A finite real number (Python's or NumPy's), not a boolean: the one test every argument
    and file field that must be a number goes through (:func:`real_argument` raises on it)."""
    return is_number(value) and math.isfinite(value)


def is_whole_number(value: Any) -> bool:
    """An integer (Python's or NumPy's), not a boolean."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def as_float(value: Any) -> float:
    """A real number as a float (``inf`` past floating point); ``nan`` for anything else."""
    if not is_number(value):
        return math.nan
    try:
        return float(value)
    except OverflowError:
        return math.inf


def real_argument(value: Any, name: str, *, positive: bool = False) -> float:
    """A function's argument that must be a finite real number (``positive``: ``> 0``), as a float.

    Text, booleans, ``nan`` and infinities are refused with :class:`InputError` naming ``name``.
    """
    number = as_float(value)
    if not is_finite_number(number) or (positive and not number > 0):
        kind = "a positive finite number" if positive else "a finite number"
        raise InputError(f"{name} must be {kind}, got {shown(value)}", field=name)
    return number


def _require_finite(owner: str, name: str, value: Any) -> float:
    if not is_number(value):
        raise InputError(
            f"{owner}.{name} must be a number, got {shown(value)} ({type(value).__name__}); "
            f"write it as a plain number such as 1.0",
            field=name,
        )
    number = as_float(value)
    if not is_finite_number(number):
        raise InputError(f"{owner}.{name} must be finite, got {number!r}; give a finite number", field=name)
    return number


#: The SI unit of each parameter ("" for the friction coefficients), for labels.
UNITS = {
    "m1": "kg",
    "m2": "kg",
    "C1": "N s/m",
    "C2": "N s^3/m^3",
    "C3": "N s/m",
    "C4": "N s/m",
    "C5": "N s^3/m^3",
    "K1": "N/m",
    "K2": "N/m^3",
    "K3": "N/m",
    "K4": "N/m",
    "K5": "N/m^3",
    "K6": "N/m",
    "mu_k": "",
    "mu_s": "",
    "d": "m",
    "d1": "m",
    "Q1": "N",
    "Q2": "N",
    "Omega": "rad/s",
    "phi1": "rad",
    "phi2": "rad",
    "P1": "N",
    "P2": "N",
    "g": "m/s^2",
}


def labelled(name: str) -> str:
    """``"Omega (rad/s)"``: a parameter's name with its unit, for an axis."""
    unit = UNITS.get(name, "")
    return f"{name} ({unit or 'dimensionless'})"


#: Messages name a value as the case file does: by its section and name (``parameters.m1``).
_SECTIONS = {"Parameters": "parameters", "InitialState": "initial", "SolverOptions": "run", "SweepSettings": "sweep"}


def _coerce_all(obj: Any) -> None:
    """Check every field is a finite number and store it as ``float``."""
    owner = _SECTIONS[type(obj).__name__]
    for f in fields(obj):
        value = _require_finite(owner, f.name, getattr(obj, f.name))
        if abs(value) > MAX_MAGNITUDE:
            raise InputError(
                f"{owner}.{f.name} = {value!r} is beyond any physical scale (|{f.name}| <= {MAX_MAGNITUDE:g}); "
                f"check its units",
                field=f.name,
            )
        if 0 < abs(value) < MIN_MAGNITUDE:
            raise InputError(
                f"{owner}.{f.name} = {value!r} is below any physical scale (a nonzero {f.name} has "
                f"|{f.name}| >= {MIN_MAGNITUDE:g}); check its units",
                field=f.name,
            )
        object.__setattr__(obj, f.name, value)


@dataclass(frozen=True, slots=True)
class Parameters:
    """Physical parameters of the two-mass oscillator (article Sec. 3.1, Table 1).

    Units are SI.  ``phi1 = phi2 = 0``, ``P1 = P2 = 0`` (no feedback) and ``g = 9.8`` are the only
    defaults; every other parameter must be given.

    Parameters
    ----------
    m1, m2 : float
        Masses (kg), ``> 0``.
    C1, C2 : float
        m1's linear (N s/m) and cubic (N s^3/m^3) damper to its wall, ``>= 0``.
    C3 : float
        Damper of the elastic stop on m2 that m1 touches (left contact), ``>= 0``.
    C4, C5 : float
        m2's linear and cubic damper to its wall, ``>= 0``.
    K1, K2 : float
        m1's linear (N/m) and cubic (N/m^3) spring, ``>= 0``.
    K3 : float
        Spring of the left stop, ``>= 0``.
    K4, K5 : float
        m2's linear and cubic spring, ``>= 0``.
    K6 : float
        Right stop spring at ``x1 = d1`` (no damper), ``>= 0``.
    mu_k, mu_s : float
        Kinetic and static friction coefficients, ``0 <= mu_k <= mu_s``.
    d : float
        Gap of the left contact: contact iff ``x1 - x2 <= -d``.
    d1 : float
        Position of the right stop: contact iff ``x1 >= d1``.
    Q1, Q2, phi1, phi2, Omega : float
        Forcing ``Q_i sin(Omega t + phi_i)``; ``Omega > 0`` (rad/s).
    P1, P2 : float
        Feedback ``B_i = -P_i sign(v_i)`` (3.1), ``>= 0``.
    g : float
        Gravity (m/s^2), ``> 0``; the normal force is ``m_i g``.
    """

    m1: float
    m2: float
    C1: float
    C2: float
    C3: float
    C4: float
    C5: float
    K1: float
    K2: float
    K3: float
    K4: float
    K5: float
    K6: float
    mu_k: float
    mu_s: float
    d: float
    d1: float
    Q1: float
    Q2: float
    Omega: float
    phi1: float = 0.0
    phi2: float = 0.0
    P1: float = 0.0
    P2: float = 0.0
    g: float = 9.8

    def __post_init__(self) -> None:
        _coerce_all(self)
        for name in ("m1", "m2", "Omega", "g"):
            if getattr(self, name) <= 0:
                raise InputError(
                    f"parameters.{name} must be > 0, got {getattr(self, name)!r}; give a positive value",
                    field=name,
                )
        nonnegative = ("C1", "C2", "C3", "C4", "C5", "K1", "K2", "K3", "K4", "K5", "K6")
        for name in (*nonnegative, "mu_k", "P1", "P2"):
            if getattr(self, name) < 0:
                raise InputError(
                    f"parameters.{name} must be >= 0, got {getattr(self, name)!r}; "
                    f"springs, dampers, friction and feedback cannot be negative",
                    field=name,
                )
        if self.mu_s < self.mu_k:
            raise InputError(
                f"parameters.mu_s must be >= mu_k (static friction is at least kinetic), "
                f"got mu_s={self.mu_s!r} < mu_k={self.mu_k!r}; raise mu_s or lower mu_k",
                field="mu_s",
            )

    @property
    def period(self) -> float:
        """Forcing period ``2 pi / Omega`` (s)."""
        return 2.0 * math.pi / self.Omega

    def mass(self, i: int) -> float:
        """Mass ``m_i``."""
        return self.m1 if i == 1 else self.m2

    def replace(self, **changes: float) -> Parameters:
        """A copy with some parameters changed (validated again)."""
        return dataclasses.replace(self, **changes)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Every parameter name, in declaration order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def check_name(cls, name: object, field: str = "param", *, label: str | None = None) -> str:
        """``name`` if it names a parameter; else one :class:`~oscillator.errors.InputError`
        for ``field`` (its message begins with ``label``, by default the field), with the closest
        parameter name and every one: the only place that asks "is this a parameter?"."""
        if isinstance(name, str) and name in cls.names():
            return name
        import difflib

        close = difflib.get_close_matches(str(name), cls.names(), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise InputError(
            f"{label or field} {shown(name)} is not a parameter{hint} (one of {', '.join(cls.names())})", field=field
        )


@dataclass(frozen=True, slots=True)
class InitialState:
    """Start of a run: time ``t0`` and ``(x1, v1, x2, v2)``.

    A mass given ``v_i = 0`` starts at rest on its velocity boundary (docs/model.md, rule 8).
    """

    t0: float
    x1: float
    v1: float
    x2: float
    v2: float

    def __post_init__(self) -> None:
        _coerce_all(self)

    @property
    def y(self) -> tuple[float, float, float, float]:
        """The state vector ``(x1, v1, x2, v2)``."""
        return (self.x1, self.v1, self.x2, self.v2)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


@dataclass(frozen=True, slots=True)
class SolverOptions:
    """Integration and event-reporting settings.

    Parameters
    ----------
    rtol, atol : float
        CVODE's relative and absolute tolerances, both ``> 0``; ``rtol`` in ``[1e-15, 1e-3]``.
        The defaults are the loosest that keep switching times within 1e-8 s of a 1e-13 run,
        over the article's instances and 20 forcing periods of Instance 1
        (``tests/test_convergence.py``, ``docs/performance.md``).
    max_step_fraction : float
        Largest step as a fraction of the forcing period, from 1e-6 to 0.25.  A resting mass's force
        turns twice per period; a step shorter than half a period cannot hide both turns, so
        the watched extrema always reveal two crossings hidden in one step.
    grazing_velocity_tolerance : float
        A velocity extremum (root of ``G^(0)``) with ``|v_i|`` at most this is reported as
        grazing of the velocity boundary (Thm 5.5), with the distance ``|v_i|`` (m/s); ``>= 0``.
    grazing_displacement_tolerance : float
        A zero of ``v1`` within this distance of ``x1 = d1``, or of ``zdot1`` within this distance
        of ``z1 = -d``, is reported as grazing of that displacement boundary (m); ``>= 0``.
    max_events : int
        Stop with an error after this many switching events in one run (10^9 by default: a
        100,000-period run of Instance 1 has 10^6; chattering at one instant has its own guards).
    storm_events, storm_window : int, float
        An event storm: more than ``storm_events`` events (1000 by default) within
        ``storm_window`` seconds (1e-3 by default, ``> 0``) stops the run with an error
        (``Reason.STORM``) naming the mass, kind and boundary that chatter.
    max_periods : int
        Refuse a run longer than this many forcing periods (10^8 by default: days of computing;
        a run of Instance 1 makes about 100 periods per second).
    max_trajectory_rows : int
        Stop with an error when the recorded trajectory passes this many rows (5 x 10^6 by
        default, about 1 GB): record it on a grid (``t_eval``) or not at all for long runs.
    max_num_steps : int
        CVODE's step limit between two outputs (or between two switches when the trajectory is
        recorded at every step).

    Every count (``max_events``, ``storm_events``, ``max_periods``, ``max_trajectory_rows``,
    ``max_num_steps``) is a whole number from 1 to 10^12; a value out of range is refused with
    :class:`~oscillator.errors.InputError` naming the field.
    """

    rtol: float = 1e-10
    atol: float = 1e-10
    max_step_fraction: float = 0.02
    grazing_velocity_tolerance: float = 1e-3
    grazing_displacement_tolerance: float = 1e-3
    max_events: int = 1_000_000_000
    storm_events: int = 1_000
    storm_window: float = 1e-3
    max_periods: int = 100_000_000
    max_trajectory_rows: int = 5_000_000
    max_num_steps: int = 100_000

    def __post_init__(self) -> None:
        owner = "run"
        for name in ("rtol", "atol", "max_step_fraction", "storm_window"):
            value = _require_finite(owner, name, getattr(self, name))
            if value <= 0:
                raise InputError(
                    f"{owner}.{name} must be > 0, got {value!r}; give a small positive number",
                    field=name,
                )
            object.__setattr__(self, name, value)
        if not 1e-15 <= self.rtol <= 1e-3:
            raise InputError(f"{owner}.rtol must lie in [1e-15, 1e-3], got {self.rtol!r}", field="rtol")
        if self.max_step_fraction > 0.25:
            raise InputError(
                f"{owner}.max_step_fraction must be <= 0.25 (a fraction of the forcing period: a "
                f"longer step can hide the turns of the forcing), got {self.max_step_fraction!r}",
                field="max_step_fraction",
            )
        if self.max_step_fraction < 1e-6:
            raise InputError(
                f"{owner}.max_step_fraction must be >= 1e-6 (a million steps per forcing period at "
                f"most), got {self.max_step_fraction!r}",
                field="max_step_fraction",
            )
        for name in ("grazing_velocity_tolerance", "grazing_displacement_tolerance"):
            value = _require_finite(owner, name, getattr(self, name))
            if value < 0:
                raise InputError(f"{owner}.{name} must be >= 0, got {value!r}", field=name)
            object.__setattr__(self, name, value)
        for name in ("max_events", "storm_events", "max_periods", "max_trajectory_rows", "max_num_steps"):
            value = getattr(self, name)
            if not is_whole_number(value) or not 1 <= value <= 10**12:
                raise InputError(
                    f"{owner}.{name} must be a whole number from 1 to 10^12, got {shown(value)}", field=name
                )
            object.__setattr__(self, name, int(value))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


@dataclass(frozen=True, slots=True)
class SweepSettings:
    """A one-parameter sweep (Sec. 7): the values, the transient and the recorded window.

    Parameters
    ----------
    param : str
        The swept parameter, one of :meth:`Parameters.names`.
    start, stop : float
        The first and last value (``from`` and ``to`` in case files).
    steps : int
        Number of values, evenly spaced from ``start`` to ``stop`` (111 by default).
    transient, record : int
        Forcing periods run before recording (100) and recorded (50).
    mass : int
        The mass whose switching points are collected (2: m2's sliding on ∂Ω12(2)).
    period_tolerance : float
        Poincaré points closer than this (relative) count as the same point (period-n).
    max_period : int
        The largest period n looked for.
    both_ways : bool
        Sweep from ``start`` to ``stop`` and back, each value starting from the state the
        previous value ended in (the first from the case's start): where two attractors
        coexist, the way up and the way down end on different ones (hysteresis).  The points
        then run one after another, in one process.
    """

    param: str
    start: float
    stop: float
    steps: int = 111
    transient: int = 100
    record: int = 50
    mass: int = 2
    period_tolerance: float = 1e-6
    max_period: int = 16
    both_ways: bool = False

    def __post_init__(self) -> None:
        owner = "sweep"
        if not isinstance(self.both_ways, bool):
            raise InputError(f"{owner}.both_ways must be true or false, got {shown(self.both_ways)}", field="both_ways")
        self.check_param()
        for name in ("start", "stop", "period_tolerance"):
            object.__setattr__(self, name, _require_finite(owner, name, getattr(self, name)))
        if self.period_tolerance <= 0:
            raise InputError(f"{owner}.period_tolerance must be > 0", field="period_tolerance")
        limits = (
            ("steps", 1, MAX_SWEEP_STEPS),
            ("transient", 0, 10**8),
            ("record", 1, MAX_SWEEP_RECORD),
            ("max_period", 1, 10**6),
        )
        for name, low, high in limits:
            value = getattr(self, name)
            if not is_whole_number(value) or not low <= value <= high:
                raise InputError(
                    f"{owner}.{name} must be a whole number from {low} to {high:,}, got {shown(value)}", field=name
                )
            object.__setattr__(self, name, int(value))
        if not is_whole_number(self.mass) or self.mass not in (1, 2):
            raise InputError(f"{owner}.mass must be 1 or 2, got {shown(self.mass)}", field="mass")
        object.__setattr__(self, "mass", int(self.mass))

    @property
    def values(self) -> tuple[float, ...]:
        """The swept values, evenly spaced and including both ends."""
        if self.steps == 1:
            return (self.start,)
        step = (self.stop - self.start) / (self.steps - 1)
        return (*(self.start + i * step for i in range(self.steps - 1)), self.stop)

    def check_param(self) -> None:
        """The swept parameter is one of the article's (a declared system's sweep checks its own
        names: :class:`~oscillator.analysis.chain_sweeps.ChainSweepSettings`)."""
        Parameters.check_name(self.param, "param", label="sweep.param:")

    @property
    def points(self) -> tuple[tuple[str, float], ...]:
        """``(direction, value)`` of every point, in the order they run: the values (``"up"``
        if ``stop >= start``, else ``"down"``), then, with ``both_ways``, the values back (the
        other direction)."""
        forward, back = ("up", "down") if self.stop >= self.start else ("down", "up")
        there = tuple((forward, v) for v in self.values)
        return there + tuple((back, v) for v in reversed(self.values)) if self.both_ways else there

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


def check_count(value: object, name: str, least: int, most: int | None = None) -> int:
    """A whole number ``>= least`` (and ``<= most``); a bool is not one."""
    number = int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else None
    if number is None or number < least or (most is not None and number > most):
        bounds = f">= {least}" if most is None else f"from {least} to {most}"
        raise InputError(f"{name} must be a whole number {bounds}, got {shown(value)}", field=name)
    return number
