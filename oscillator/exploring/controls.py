"""The explorer's controls: one slider for every parameter and every start value, in groups.

Each slider spans a range around the case's value that keeps the parameter physical (masses,
``Omega`` and ``g`` above zero; springs, dampers and friction not negative; a phase over one
turn), in steps counted from the case's value: the arrow keys take a slider away from it and back
to it exactly (steps counted from the range's lower end could not reach it again: ``g`` went 9.8,
9.88, 9.78).  Any value, beyond a slider's ends too, goes in the page's box.  A value the model
refuses (``mu_s < mu_k``, a negative stiffness typed in the box) is reported by the page and not
run.  Each control is titled with its unit and belongs to a group: for the article's system the
forcing, each mass's springs, dampers and feedback, the stops, friction, the start
(:func:`controls_of`); for a friction chain the system (``Omega``, ``g``), each mass (``m``, its
start ``x``, ``v``) and each element's fields, named as ``--set`` names them (``blade.m``,
``platform.F``: :func:`chain_controls`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from oscillator.analysis.axes import STATE
from oscillator.io.cases import Case
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import UNITS, Parameters

__all__ = ["GROUPS", "START", "Control", "chain_controls", "controls_of", "groups_of"]

#: What values a control's range keeps: a phase over one turn, any sign, above zero, not below zero.
Span = Literal["phase", "signed", "positive", "not_negative"]

#: The start values the page has a control for.
START = STATE
_POSITIVE = ("m1", "m2", "Omega", "g")
_SIGNED = ("phi1", "phi2", "d", "d1")
#: Steps per slider (about: the step is rounded to one significant figure).
_STEPS = 200
#: The groups of controls, in the page's order, each with its members in order.
GROUPS = {
    "Forcing": ("Omega", "Q1", "Q2", "phi1", "phi2"),
    "Mass m1": ("m1", "K1", "K2", "C1", "C2", "P1"),
    "Mass m2": ("m2", "K4", "K5", "C4", "C5", "P2"),
    "Stops": ("d", "K3", "C3", "d1", "K6"),
    "Friction": ("mu_k", "mu_s", "g"),
    "Start": START,
}
_STATE_UNITS = {name: "m" if k % 2 == 0 else "m/s" for k, name in enumerate(START)}


@dataclass(frozen=True)
class Control:
    """One slider: the name (a parameter or a start value), its group, value, ends and step; the
    ends lie a whole number of steps from the value."""

    name: str
    group: str
    value: float
    start: float
    end: float
    step: float
    unit: str = ""

    @property
    def title(self) -> str:
        """The name with its unit: ``K1 (N/m)``; ``mu_k`` alone (dimensionless)."""
        return f"{self.name} ({self.unit})" if self.unit else self.name


def _span(name: str) -> Span:
    """What values the article's ``name`` (a parameter or a start value) may take."""
    if name in ("phi1", "phi2"):
        return "phase"
    if name in START or name in _SIGNED:
        return "signed"
    return "positive" if name in _POSITIVE else "not_negative"


def _range(span: Span, value: float) -> tuple[float, float]:
    if span == "phase":
        return -math.pi, math.pi
    scale = abs(value) if value != 0 else 1.0
    if span == "signed":
        return value - 2 * scale, value + 2 * scale
    if span == "positive":
        return value / 10, 3 * value
    return 0.0, 2 * scale if value != 0 else 1.0


def _anchored(value: float, low: float, high: float) -> tuple[float, float, float]:
    """The step (one significant figure of the range's 200th) and the ends, a whole number of
    steps from ``value`` inside ``[low, high]``: ``(start, end, step)``."""
    step = float(f"{(high - low) / _STEPS:.1g}")
    below, above = math.floor((value - low) / step + 1e-9), math.floor((high - value) / step + 1e-9)
    return value - below * step, value + above * step, step


def _control(name: str, group: str, value: float, span: Span, unit: str) -> Control:
    start, end, step = _anchored(value, *_range(span, value))
    return Control(name, group, value, start, end, step, unit)


def controls_of(case: Case) -> list[Control]:
    """The controls of ``case``: its parameters, then its start ``(x1, v1, x2, v2)``, each with
    its group (:data:`GROUPS`)."""
    group_of = {name: group for group, names in GROUPS.items() for name in names}
    found = []
    for names, holder in ((Parameters.names(), case.parameters), (START, case.initial)):
        for name in names:
            unit = UNITS.get(name, _STATE_UNITS.get(name, ""))
            found.append(_control(name, group_of[name], float(getattr(holder, name)), _span(name), unit))
    return found


#: A friction chain's fields by what values they take (the others may not be negative).
_CHAIN_SPANS: dict[str, Span] = {
    "phi": "phase",
    "x": "signed",
    "v": "signed",
    "at": "signed",
    "w": "signed",
    "Q": "signed",
    "k": "signed",
    "k3": "signed",
    "m": "positive",
    "kt": "positive",
    "N": "positive",
    "Omega": "positive",
    "g": "positive",
}


def chain_controls(chain: FrictionChain) -> list[Control]:
    """The controls of a friction chain: ``Omega`` and ``g``, each mass's ``m``, ``x``, ``v`` and
    each element's fields (a friction element's ``N`` when given; its default is the mass's
    weight), named as :meth:`~oscillator.model.chains.FrictionChain.with_values` names them, in
    groups: the system, each mass, each element (``platform (jenkins)``)."""
    found = [
        _control(name, "System", float(getattr(chain, name)), "positive", chain.unit(name)) for name in ("Omega", "g")
    ]
    for mass in chain.masses:
        for key in ("m", "x", "v"):
            name = f"{mass.name}.{key}"
            found.append(_control(name, mass.name, float(getattr(mass, key)), _CHAIN_SPANS[key], chain.unit(name)))
    for element in chain.elements:
        for key, value in element.values.items():
            if key == "side" or value is None:
                continue
            name, span = f"{element.name}.{key}", _CHAIN_SPANS.get(key, "not_negative")
            found.append(_control(name, f"{element.name} ({element.type})", float(value), span, chain.unit(name)))
    return found


def groups_of(controls: list[Control]) -> dict[str, tuple[str, ...]]:
    """The groups of ``controls`` in their order, each with its members' names in order."""
    groups: dict[str, list[str]] = {}
    for control in controls:
        groups.setdefault(control.group, []).append(control.name)
    return {group: tuple(names) for group, names in groups.items()}
