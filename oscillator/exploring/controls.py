"""The explorer's controls: one slider with a box for every parameter and every start value.

Each slider spans a range around the case's value that keeps the parameter physical (masses,
``Omega`` and ``g`` above zero; springs, dampers and friction not negative; a phase over one
turn); its box takes any value, beyond the slider's ends too.  A value the model refuses
(``mu_s < mu_k``, a negative stiffness typed in the box) is reported by the page and not run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from oscillator.analysis.axes import STATE
from oscillator.io.cases import Case
from oscillator.model.parameters import Parameters

__all__ = ["START", "Control", "controls_of"]

#: The start values the page has a control for.
START = STATE
_POSITIVE = ("m1", "m2", "Omega", "g")
_SIGNED = ("phi1", "phi2", "d", "d1")
#: Steps per slider.
_STEPS = 200


@dataclass(frozen=True)
class Control:
    """One slider: the name (a parameter or a start value), its group, value, ends and step."""

    name: str
    group: str
    value: float
    start: float
    end: float
    step: float


def _range(name: str, value: float) -> tuple[float, float]:
    if name in ("phi1", "phi2"):
        return -math.pi, math.pi
    scale = abs(value) if value != 0 else 1.0
    if name in START or name in _SIGNED:
        return value - 2 * scale, value + 2 * scale
    if name in _POSITIVE:
        return value / 10, 3 * value
    return 0.0, 2 * scale if value != 0 else 1.0


def controls_of(case: Case) -> list[Control]:
    """The controls of ``case``: its 25 parameters, then its start ``(x1, v1, x2, v2)``."""
    found = []
    for group, names, holder in (("parameters", Parameters.names(), case.parameters), ("start", START, case.initial)):
        for name in names:
            value = float(getattr(holder, name))
            start, end = _range(name, value)
            step = float(f"{(end - start) / _STEPS:.1g}")
            found.append(Control(name, group, value, start, end, step))
    return found
