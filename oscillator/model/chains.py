"""Friction chains: the machines users declare (issue 51, docs/systems.md).

A friction chain is ``N >= 1`` masses on a line and elements between them, each acting ``on`` a
mass and ``with`` another mass, or with the ground when ``with`` is omitted:

========== =============================== ================================================
type       fields (default)                 what it is
========== =============================== ================================================
spring     k (0), k3 (0)                    ``k u + k3 u^3`` of the stretch ``u``
damper     c (0), c3 (0)                    ``c w + c3 w^3`` of the stretch's rate ``w``
force      Q, phi (0)                       ``Q sin(Omega t + phi)`` on the mass
friction   mu_s, mu_k, N (m g), P (0), w (0) dry friction against the floor or a belt moving
                                            at ``w``; ``P`` the feedback (the article's P_i)
stop       side, at, K, C (0)               a compliant one-sided stop to the ground: "right"
                                            touches when ``x >= at``, "left" when ``x <= at``
contact    side, gap, K, C (0)              a compliant contact between two masses: "left"
                                            closes when ``x_on - x_with <= -gap``, "right"
                                            when ``x_on - x_with >= gap``
jenkins    kt, F                            a spring ``kt`` in series with a Coulomb slider of
                                            strength ``F`` (the slider's position a state)
========== =============================== ================================================

Every value is checked where it is given: a bad one raises one
:class:`~oscillator.errors.InputError` naming the element (its name, or its type and number), the
field and the fix.  The values are frozen dataclasses; :class:`FrictionChain`'s builder methods
return a new chain each.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from oscillator.errors import InputError
from oscillator.model.parameters import MAX_MAGNITUDE, InitialState, Parameters, as_float, is_finite_number
from oscillator.model.system import System
from oscillator.text import did_you_mean, printable, shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = [
    "ELEMENTS",
    "MAX_ELEMENTS",
    "MAX_MASSES",
    "UNITS",
    "Element",
    "FrictionChain",
    "Mass",
    "article_chain",
    "article_mode",
]

#: The most masses and elements a chain may have: the compiled kernels hold a chain's state (two
#: values a mass, one a Jenkins slider) and its modes in fixed-width arrays.
MAX_MASSES = 32
MAX_ELEMENTS = 256
#: The longest name of a mass or an element.
MAX_NAME = 64

_REQUIRED = object()
#: Each element type's fields and their defaults (``_REQUIRED``: no default); ``N = None``: the
#: mass's weight ``m g``.
ELEMENTS: dict[str, dict[str, Any]] = {
    "spring": {"k": 0.0, "k3": 0.0},
    "damper": {"c": 0.0, "c3": 0.0},
    "force": {"Q": _REQUIRED, "phi": 0.0},
    "friction": {"mu_s": _REQUIRED, "mu_k": _REQUIRED, "N": None, "P": 0.0, "w": 0.0},
    "stop": {"side": _REQUIRED, "at": _REQUIRED, "K": _REQUIRED, "C": 0.0},
    "contact": {"side": _REQUIRED, "gap": _REQUIRED, "K": _REQUIRED, "C": 0.0},
    "jenkins": {"kt": _REQUIRED, "F": _REQUIRED},
}
#: Whether each type acts between two masses: always (``True``), never (``False``) or either.
_WITH = {"spring": None, "damper": None, "force": False, "friction": False, "stop": False, "contact": True}
_WITH["jenkins"] = None
#: Fields that must not be negative, and those that must be positive.
_NOT_NEGATIVE = {"c", "c3", "C", "K", "gap", "F", "mu_k", "mu_s", "P"}
_POSITIVE = {"kt", "N"}
_SIDES = ("left", "right")
#: The SI unit of each number of a chain, by its field (a mass's ``m``, ``x``, ``v``; the system's
#: ``Omega``, ``g``, ``t0``; an element's fields); dimensionless ones (``mu_s``, ``mu_k``) have none.
UNITS = {
    "Omega": "rad/s",
    "g": "m/s^2",
    "t0": "s",
    "m": "kg",
    "x": "m",
    "v": "m/s",
    "k": "N/m",
    "k3": "N/m^3",
    "c": "N s/m",
    "c3": "N s^3/m^3",
    "Q": "N",
    "phi": "rad",
    "N": "N",
    "P": "N",
    "w": "m/s",
    "at": "m",
    "K": "N/m",
    "C": "N s/m",
    "gap": "m",
    "kt": "N/m",
    "F": "N",
}


def _name(value: object, what: str, field: str = "name") -> str:
    """A name: text of 1 to :data:`MAX_NAME` printable characters."""
    if not isinstance(value, str) or not value or len(value) > MAX_NAME or printable(value) != value:
        raise InputError(
            f"{what} must be a name of 1 to {MAX_NAME} printable characters, got {shown(value)}", field=field
        )
    return value


def _number(value: object, where: str, name: str) -> float:
    number = as_float(value)
    if not is_finite_number(value) or abs(number) > MAX_MAGNITUDE:
        raise InputError(f"{where}: {name} must be a finite number, got {shown(value)}", field=name)
    return number


@dataclass(frozen=True)
class Mass:
    """A mass on the line: its name, ``m`` (kg, > 0) and its initial position and velocity."""

    name: str
    m: float
    x: float = 0.0
    v: float = 0.0

    def __post_init__(self) -> None:
        _name(self.name, "a mass's name")
        where = f"mass {printable(self.name)!r}"
        for key in ("m", "x", "v"):
            object.__setattr__(self, key, _number(getattr(self, key), where, key))
        if not self.m > 0:
            raise InputError(f"{where}: m must be positive (kg), got {self.m:g}", field="m")


@dataclass(frozen=True)
class Element:
    """An element of a chain: its ``type`` (:data:`ELEMENTS`), the mass it acts ``on``, the mass
    it acts ``with`` (``None``: the ground), its fields with their defaults filled in, and a name
    (by default its type and number, given by the chain)."""

    type: str
    on: str
    with_: str | None = None
    values: Mapping[str, Any] = field(default_factory=dict)
    name: str = ""

    def __post_init__(self) -> None:
        where = self.where
        if self.type not in ELEMENTS:
            hint = did_you_mean(str(self.type), list(ELEMENTS))
            raise InputError(
                f"{where}: unknown type {shown(self.type)}{hint} (one of {', '.join(ELEMENTS)})", field="type"
            )
        fields = ELEMENTS[self.type]
        unknown = [key for key in self.values if key not in fields]
        if unknown:
            hint = did_you_mean(str(unknown[0]), list(fields))
            raise InputError(
                f"{where}: unknown field {shown(unknown[0])}{hint} (a {self.type} has {', '.join(fields)})",
                field=str(unknown[0]),
            )
        missing = [key for key, default in fields.items() if default is _REQUIRED and key not in self.values]
        if missing:
            raise InputError(f"{where}: a {self.type} needs {', '.join(missing)}; add it", field=missing[0])
        object.__setattr__(self, "values", self._checked({**fields, **self.values}))
        self._check_ends(where)

    @property
    def where(self) -> str:
        """How messages name the element."""
        return f"element {printable(self.name)!r}" if self.name else f"a {printable(str(self.type))} element"

    def _checked(self, values: dict[str, Any]) -> dict[str, Any]:
        where, checked = self.where, {}
        for key, value in values.items():
            if key == "side":
                if value not in _SIDES:
                    raise InputError(f"{where}: side must be 'left' or 'right', got {shown(value)}", field="side")
                checked[key] = value
                continue
            if value is None:  # N: the mass's weight
                checked[key] = None
                continue
            number = _number(value, where, key)
            if key in _NOT_NEGATIVE and number < 0:
                raise InputError(f"{where}: {key} must not be negative, got {number:g}", field=key)
            if key in _POSITIVE and not number > 0:
                raise InputError(f"{where}: {key} must be positive, got {number:g}", field=key)
            checked[key] = number
        if self.type == "friction" and checked["mu_s"] < checked["mu_k"]:
            raise InputError(
                f"{where}: mu_s ({checked['mu_s']:g}) must be at least mu_k ({checked['mu_k']:g}): static friction "
                "is not weaker than kinetic",
                field="mu_s",
            )
        return checked

    def _check_ends(self, where: str) -> None:
        _name(self.on, f"{where}: on", "on")
        between = _WITH[self.type]
        if self.with_ is None and between:
            raise InputError(
                f"{where}: a {self.type} acts between two masses; give with = <another mass>", field="with"
            )
        if self.with_ is not None:
            _name(self.with_, f"{where}: with", "with")
            if between is False:
                raise InputError(
                    f"{where}: a {self.type} acts on one mass against the ground; leave out with", field="with"
                )
            if self.with_ == self.on:
                raise InputError(f"{where}: with must be another mass than on ({printable(self.on)!r})", field="with")


@dataclass(frozen=True)
class FrictionChain:
    """A machine of masses and elements (module docstring), with the forcing frequency ``Omega``
    every ``force`` shares, gravity ``g``, the start time ``t0`` and a run's end ``t_end`` (``None``:
    10 forcing periods).

    Build it from a case file (:func:`oscillator.io.chains.load_system`) or by its methods, each
    returning a new chain::

        machine = (
            FrictionChain(Omega=1.0)
            .mass("blade", m=1.0, v=0.5)
            .mass("damper", m=0.1)
            .spring("blade", k=1.0)
            .jenkins("blade", "damper", kt=2.0, F=0.3)
            .force("blade", Q=0.5)
        )
    """

    masses: tuple[Mass, ...] = ()
    elements: tuple[Element, ...] = ()
    Omega: float = 1.0
    g: float = 9.8
    t0: float = 0.0
    title: str = ""
    t_end: float | None = None

    def __post_init__(self) -> None:
        for key in ("Omega", "g", "t0"):
            object.__setattr__(self, key, _number(getattr(self, key), "the system", key))
        if self.t_end is not None:
            object.__setattr__(self, "t_end", _number(self.t_end, "[run]", "t_end"))
            if not self.t_end > self.t0:
                raise InputError(f"[run]: t_end must be after t0 = {self.t0:g} s, got {self.t_end:g}", field="t_end")
        if not self.Omega > 0:
            raise InputError(f"the system: Omega must be positive (rad/s), got {self.Omega:g}", field="Omega")
        if len(self.masses) > MAX_MASSES or len(self.elements) > MAX_ELEMENTS:
            raise InputError(
                f"the system has {len(self.masses)} masses and {len(self.elements)} elements; at most {MAX_MASSES} "
                f"masses and {MAX_ELEMENTS} elements fit the compiled kernels: split the machine, or join masses",
                field="mass" if len(self.masses) > MAX_MASSES else "element",
            )
        names = [mass.name for mass in self.masses]
        twice = next((name for name in names if names.count(name) > 1), None)
        if twice is not None:
            raise InputError(f"two masses are named {printable(twice)!r}; give each its own name", field="name")
        named = [e if e.name else dataclasses.replace(e, name=f"{e.type}-{k + 1}") for k, e in enumerate(self.elements)]
        object.__setattr__(self, "elements", tuple(named))
        self._check_elements(set(names))

    def _check_elements(self, names: set[str]) -> None:
        seen: dict[str, str] = {}
        labels = [element.name for element in self.elements]
        for element in self.elements:
            if labels.count(element.name) > 1:
                raise InputError(f"two elements are named {printable(element.name)!r}; name each once", field="name")
            for end, field_name in ((element.on, "on"), (element.with_, "with")):
                if end is not None and end not in names:
                    hint = did_you_mean(end, sorted(names))
                    known = ", ".join(repr(n) for n in sorted(names)) or "none yet: declare the masses first"
                    raise InputError(
                        f"{element.where}: {field_name} = {printable(end)!r} is no mass of the system{hint} "
                        f"(masses: {known})",
                        field=field_name,
                    )
            if element.type == "friction":
                if element.on in seen:
                    raise InputError(
                        f"{element.where}: mass {printable(element.on)!r} has a friction element already "
                        f"({printable(seen[element.on])!r}); give one friction element a mass",
                        field="on",
                    )
                seen[element.on] = element.name

    def checked(self) -> FrictionChain:
        """The chain, refused unless it has a mass: what a simulation needs."""
        if not self.masses:
            raise InputError("the system has no mass; declare one with [[mass]] (name, m)", field="mass")
        return self

    # -- the builder ----------------------------------------------------------------------------

    def mass(self, name: str, m: float, x: float = 0.0, v: float = 0.0) -> FrictionChain:
        """This chain with one more mass."""
        return dataclasses.replace(self, masses=(*self.masses, Mass(name, m, x, v)))

    def element(self, type: str, on: str, with_: str | None = None, *, name: str = "", **values: Any) -> FrictionChain:
        """This chain with one more element of ``type`` (:data:`ELEMENTS`)."""
        return dataclasses.replace(self, elements=(*self.elements, Element(type, on, with_, values, name)))

    def spring(
        self, on: str, with_: str | None = None, *, name: str = "", k: float = 0.0, k3: float = 0.0
    ) -> FrictionChain:
        return self.element("spring", on, with_, name=name, k=k, k3=k3)

    def damper(
        self, on: str, with_: str | None = None, *, name: str = "", c: float = 0.0, c3: float = 0.0
    ) -> FrictionChain:
        return self.element("damper", on, with_, name=name, c=c, c3=c3)

    def force(self, on: str, *, name: str = "", Q: float, phi: float = 0.0) -> FrictionChain:
        return self.element("force", on, name=name, Q=Q, phi=phi)

    def friction(self, on: str, *, name: str = "", **values: Any) -> FrictionChain:
        """Dry friction on ``on``: ``mu_s``, ``mu_k``, and ``N``, ``P``, ``w`` (a belt's speed)."""
        return self.element("friction", on, name=name, **values)

    def stop(self, on: str, *, name: str = "", side: str, at: float, K: float, C: float = 0.0) -> FrictionChain:
        return self.element("stop", on, name=name, side=side, at=at, K=K, C=C)

    def contact(
        self, on: str, with_: str, *, name: str = "", side: str, gap: float, K: float, C: float = 0.0
    ) -> FrictionChain:
        return self.element("contact", on, with_, name=name, side=side, gap=gap, K=K, C=C)

    def jenkins(self, on: str, with_: str | None = None, *, name: str = "", kt: float, F: float) -> FrictionChain:
        return self.element("jenkins", on, with_, name=name, kt=kt, F=F)

    # -- what the chain is made of ----------------------------------------------------------------

    def parameter_names(self) -> list[str]:
        """Every number of the chain by its name: ``Omega``, ``g``, ``t0``, ``<mass>.m`` (``.x``,
        ``.v``), ``<element>.<field>`` (e.g. ``platform.F``, ``blade.m``)."""
        names = ["Omega", "g", "t0"]
        names += [f"{m.name}.{q}" for m in self.masses for q in ("m", "x", "v")]
        for e in self.elements:
            names += [f"{e.name}.{k}" for k, v in e.values.items() if k != "side"]
        return names

    def value(self, name: str) -> float | None:
        """The number ``name`` (:meth:`parameter_names`); None for a field left to its default (a
        friction element's normal load ``N``, its masses' weight).  An unknown name is refused
        with the closest one."""
        if name not in self.parameter_names():
            self.with_values({name: 0.0})  # refuses it, naming the closest
        owner, _, key = name.rpartition(".")
        if not owner:
            return float(getattr(self, name))
        mass = next((m for m in self.masses if m.name == owner and key in ("m", "x", "v")), None)
        if mass is not None:
            return float(getattr(mass, key))
        found = next(e for e in self.elements if e.name == owner).values.get(key)
        return None if found is None else float(found)

    def with_values(self, changes: Mapping[str, float]) -> FrictionChain:
        """This chain with numbers changed by name (:meth:`parameter_names`), each checked as where
        it was first given; an unknown name is refused with the closest one."""
        known = self.parameter_names()
        masses, elements, top = list(self.masses), list(self.elements), dict[str, Any]()
        for name, value in changes.items():
            if name not in known:
                hint = did_you_mean(name, known)
                raise InputError(
                    f"{printable(name)} is no number of the system{hint}: name one as <mass>.m, <element>.<field>, "
                    "Omega, g or t0",
                    field=name,
                )
            owner, _, key = name.rpartition(".")
            if not owner:
                top[name] = value
                continue
            k = next((i for i, m in enumerate(masses) if m.name == owner and key in ("m", "x", "v")), None)
            if k is not None:
                masses[k] = dataclasses.replace(masses[k], **{key: value})  # type: ignore[arg-type]
                continue
            k = next(i for i, e in enumerate(elements) if e.name == owner)
            elements[k] = dataclasses.replace(elements[k], values={**elements[k].values, key: value})
        return dataclasses.replace(self, masses=tuple(masses), elements=tuple(elements), **top)

    @property
    def system(self) -> System:
        """The chain's shape as every layer reads it (:mod:`oscillator.model.system`): its masses by
        name, the state ``x:<mass>``, ``v:<mass>`` mass after mass then ``z:<slider>``, its numbers'
        names, its stops and contacts, one mode integer per element."""
        masses = tuple(m.name for m in self.masses)
        state = [f"{q}:{m}" for m in masses for q in ("x", "v")]
        state += [f"z:{e.name}" for e in self.elements if e.type == "jenkins"]
        contacts = tuple(e.name for e in self.elements if e.type in ("stop", "contact"))
        title = self.title or "a friction chain"
        return System(title, masses, masses, tuple(state), tuple(self.parameter_names()), contacts, len(self.elements))

    @staticmethod
    def unit(name: str) -> str:
        """The SI unit of the number ``name`` (:meth:`parameter_names`): ``blade.m`` kg,
        ``platform.F`` N, ``Omega`` rad/s; ``""`` for a dimensionless one."""
        return UNITS.get(name.rpartition(".")[2], "")

    def plot(self) -> Figure:
        """The machine's schematic (a matplotlib figure): masses, springs, dampers, stops with their
        places, contacts with their gaps, friction and belts, Jenkins elements, forces."""
        from oscillator.presenting import presenter

        return presenter().plot_system(self)

    @property
    def period(self) -> float:
        """The forcing period ``2 pi / Omega`` (s)."""
        return 2.0 * math.pi / self.Omega

    def normal_force(self, element: Element) -> float:
        """A friction element's normal force: its ``N``, or its mass's weight ``m g``."""
        if element.values.get("N") is not None:
            return float(element.values["N"])
        mass = next(m for m in self.masses if m.name == element.on)
        return mass.m * self.g


def article_chain(p: Parameters, initial: InitialState) -> FrictionChain:
    """The article's two masses as a friction chain (docs/model.md): each mass's spring (K1, K2;
    K4, K5) and damper (C1, C2; C4, C5) to the ground, its forcing (Q1, phi1; Q2, phi2) and its
    friction (mu_s, mu_k, N = m g, feedback P1; P2); the contact between the masses on the left
    (gap d, K3, C3) and m1's stop on the right at d1 (K6).  Its elements, in this order, are those
    :func:`article_mode` numbers."""
    return (
        FrictionChain(Omega=p.Omega, g=p.g, t0=initial.t0, title="the article's system")
        .mass("m1", p.m1, initial.x1, initial.v1)
        .mass("m2", p.m2, initial.x2, initial.v2)
        .spring("m1", k=p.K1, k3=p.K2)
        .damper("m1", c=p.C1, c3=p.C2)
        .force("m1", Q=p.Q1, phi=p.phi1)
        .friction("m1", mu_s=p.mu_s, mu_k=p.mu_k, P=p.P1)
        .spring("m2", k=p.K4, k3=p.K5)
        .damper("m2", c=p.C4, c3=p.C5)
        .force("m2", Q=p.Q2, phi=p.phi2)
        .friction("m2", mu_s=p.mu_s, mu_k=p.mu_k, P=p.P2)
        .contact("m1", "m2", side="left", gap=p.d, K=p.K3, C=p.C3)
        .stop("m1", side="right", at=p.d1, K=p.K6)
    )


def article_mode(s1: int, s2: int, left: bool, right: bool) -> list[int]:
    """The article's mode (each mass's velocity sign, the contacts) as :func:`article_chain`'s
    mode vector: one integer per element."""
    return [0, 0, 0, s1, 0, 0, 0, s2, int(left), int(right)]
