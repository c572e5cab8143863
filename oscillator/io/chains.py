"""System files: a friction chain declared in TOML (docs/systems.md), read as untrusted text and
written back.

::

    title = "Blade with a friction damper"
    [system]
    Omega = 1.0          # g = 9.8, t0 = 0.0 by default
    [run]
    t_end = 20.0         # by default 10 forcing periods
    [[mass]]
    name = "blade"
    m = 1.0
    x = 0.0              # x, v: 0 by default
    v = 0.5
    [[element]]
    type = "jenkins"
    on = "blade"
    with = "damper"      # left out: the ground
    kt = 2.0
    F = 0.3

Numbers may be written as short expressions (``"pi/8"``).  Every key is checked: an unknown one
is refused naming the mass or element and the keys it may have, with the closest one.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from oscillator.errors import InputError, OscillatorError
from oscillator.io.expressions import parse_value
from oscillator.io.files import read_untrusted
from oscillator.model.chains import ELEMENTS, MAX_ELEMENTS, MAX_MASSES, Element, FrictionChain, Mass
from oscillator.model.parameters import is_finite_number
from oscillator.text import did_you_mean, printable, shown

__all__ = [
    "MAX_SYSTEM_BYTES",
    "Expected",
    "chain_from_dict",
    "chain_to_toml",
    "expected_events",
    "is_system",
    "load_system",
    "system_path",
]

#: The largest system file read.
MAX_SYSTEM_BYTES = 1 << 20
_TOP = ("title", "system", "mass", "element", "run", "expected")
_EXPECTED = ("label", "element", "kind", "t", "tolerance")
_RUN = ("t_end",)
_SYSTEM = ("Omega", "g", "t0")
_MASS = ("name", "m", "x", "v")
_ENDS = ("type", "on", "with", "name")


def is_system(data: dict[str, Any]) -> bool:
    """Whether parsed TOML declares a friction chain (it has ``[[mass]]`` or ``[system]``)."""
    return "mass" in data or "system" in data


@dataclass(frozen=True)
class Expected:
    """An event a system file expects (``[[expected]]``): the element, the kind of event, the time
    (s) and how far from it the run's may be (s, 1e-3 by default); what ``oscillator check`` compares."""

    label: str
    element: str
    kind: str
    t: float
    tolerance: float = 1e-3


def expected_events(path: str | Path) -> tuple[FrictionChain, tuple[Expected, ...]]:
    """A system file's chain and its ``[[expected]]`` events, each naming an element of the chain
    and an event kind."""
    from oscillator.model.chain_rules import ChainEventKind

    path = Path(path)
    chain, data = _load(path)
    source, names = printable(str(path)), [e.name for e in chain.elements]
    found = []
    for number, table in enumerate(_list(data, "expected", MAX_ELEMENTS, source), start=1):
        where = f"{source}: expected event {number}"
        for key in table:
            if key not in _EXPECTED:
                raise _unknown(key, _EXPECTED, where)
        if table.get("element") not in names:
            hint = did_you_mean(str(table.get("element")), names)
            raise InputError(f"{where}: element must name an element of the system{hint}", field="element")
        if table.get("kind") not in set(ChainEventKind):
            hint = did_you_mean(str(table.get("kind")), [str(k) for k in ChainEventKind])
            raise InputError(f"{where}: kind must be one of {', '.join(ChainEventKind)}{hint}", field="kind")
        t, tolerance = (_value(table.get(k, d), k, where) for k, d in (("t", None), ("tolerance", 1e-3)))
        if not (is_finite_number(t) and is_finite_number(tolerance) and float(tolerance) > 0):
            raise InputError(f"{where}: t must be a time and tolerance a positive number of s", field="t")
        label = table.get("label", f"{table['element']} {table['kind']}")
        found.append(Expected(printable(str(label))[:200], table["element"], table["kind"], float(t), float(tolerance)))
    return chain, tuple(found)


def system_path(argument: str) -> Path | None:
    """The path ``argument`` names when it is a system file (a ``.toml`` file declaring masses or
    ``[system]``), else ``None`` (a named case or a case file: the article's system)."""
    path = Path(argument)
    if path.suffix.lower() != ".toml" or not path.is_file():
        return None
    try:
        text = read_untrusted(path, what="system file", field="case", limit=MAX_SYSTEM_BYTES)
        data = tomllib.loads(text.removeprefix("\ufeff"))
    except (OscillatorError, tomllib.TOMLDecodeError, ValueError, RecursionError, MemoryError):
        return None  # the case reader says what is wrong with it
    return path if is_system(data) else None


def _unknown(key: object, known: tuple[str, ...] | list[str], where: str) -> InputError:
    hint = did_you_mean(str(key), list(known))
    return InputError(f"{where}: unknown key {shown(key)}{hint} (known: {', '.join(known)})", field=str(key))


def _list(data: dict[str, Any], key: str, most: int, source: str) -> list[dict[str, Any]]:
    items = data.get(key, [])
    if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
        raise InputError(f"{source}: {key} must be written as [[{key}]] tables", field=key)
    if len(items) > most:
        what = "masses" if key == "mass" else "elements"
        raise InputError(
            f"{source}: {len(items)} [[{key}]] tables; at most {most} {what} fit the compiled kernels: split the "
            "machine, or join masses",
            field=key,
        )
    return items


def _value(raw: object, key: str, where: str) -> Any:
    if key in ("name", "on", "with", "type", "side"):
        return raw  # text, checked by the model
    try:
        return parse_value(raw, field=key)
    except InputError as error:
        raise InputError(f"{where}: {error}", field=key) from None


def _mass(table: dict[str, Any], number: int, source: str) -> Mass:
    where = f"{source}: mass {number}"
    for key in table:
        if key not in _MASS:
            raise _unknown(key, _MASS, where)
    if "name" not in table or "m" not in table:
        missing = "name" if "name" not in table else "m"
        raise InputError(f"{where}: a mass needs {missing}; add it", field=missing)
    return Mass(**{key: _value(raw, key, where) for key, raw in table.items()})


def _element(table: dict[str, Any], number: int, source: str) -> Element:
    """An ``[[element]]`` table: its type, ends and name, and its fields (each checked by
    :class:`~oscillator.model.chains.Element`, which names an unknown one)."""
    kind = table.get("type")
    if not isinstance(kind, str):
        raise InputError(
            f"{source}: element {number}: give type = one of {', '.join(ELEMENTS)}, got {shown(kind)}", field="type"
        )
    name = table.get("name") or f"{kind}-{number}"
    if "on" not in table:
        raise InputError(f"{source}: element {shown(name)}: give on = <the mass it acts on>", field="on")
    where = f"element {shown(name)}"
    values = {key: _value(raw, key, where) for key, raw in table.items() if key not in _ENDS}
    return Element(kind, table["on"], table.get("with"), values, name)


def _table(data: dict[str, Any], key: str, known: tuple[str, ...], source: str) -> dict[str, Any]:
    """The table ``[key]`` (empty if absent), each of its keys one of ``known``."""
    table = data.get(key, {})
    if not isinstance(table, dict):
        raise InputError(f"{source}: [{key}] must be a table", field=key)
    for name in table:
        if name not in known:
            raise _unknown(name, known, f"{source}: [{key}]")
    return table


def chain_from_dict(data: dict[str, Any], *, source: str = "<system>") -> FrictionChain:
    """The friction chain parsed TOML declares (module docstring); refused naming the table and
    key of the first bad value."""
    for key in data:
        if key not in _TOP:
            raise _unknown(key, _TOP, source)
    system, run = _table(data, "system", _SYSTEM, source), _table(data, "run", _RUN, source)
    title = data.get("title", "")
    if not isinstance(title, str) or len(title) > 300:
        raise InputError(f"{source}: title must be text of at most 300 characters", field="title")
    try:
        masses = tuple(_mass(t, k + 1, source) for k, t in enumerate(_list(data, "mass", MAX_MASSES, source)))
        elements = tuple(_element(t, k + 1, source) for k, t in enumerate(_list(data, "element", MAX_ELEMENTS, source)))
        settings = {key: _value(raw, key, "[system]") for key, raw in system.items()}
        settings |= {key: _value(raw, key, "[run]") for key, raw in run.items()}
        return FrictionChain(masses, elements, title=title, **settings).checked()
    except OscillatorError as error:
        message = str(error)
        text = message if message.startswith(source) else f"{source}: {message}"
        raise InputError(text, field=error.field) from None


def _load(path: Path) -> tuple[FrictionChain, dict[str, Any]]:
    source = printable(str(path))
    text = read_untrusted(path, what="system file", field="case", limit=MAX_SYSTEM_BYTES).removeprefix("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{source}: malformed TOML: {error}", field="case") from None
    except (ValueError, RecursionError, MemoryError):
        raise InputError(f"{source}: malformed TOML: a value too long or nested too deeply", field="case") from None
    return chain_from_dict(data, source=source), data


def load_system(path: str | Path) -> FrictionChain:
    """The friction chain a system file declares, read as untrusted text (at most
    :data:`MAX_SYSTEM_BYTES`, UTF-8, a regular file)."""
    return _load(Path(path))[0]


def chain_to_toml(chain: FrictionChain) -> str:
    """The chain as a system file that :func:`load_system` reads back to an equal chain (every
    field written, defaults included)."""
    import tomli_w

    data: dict[str, Any] = {"title": chain.title} if chain.title else {}
    data["system"] = {"Omega": chain.Omega, "g": chain.g, "t0": chain.t0}
    if chain.t_end is not None:
        data["run"] = {"t_end": chain.t_end}
    data["mass"] = [{"name": m.name, "m": m.m, "x": m.x, "v": m.v} for m in chain.masses]
    elements = []
    for element in chain.elements:
        table: dict[str, Any] = {"type": element.type, "name": element.name, "on": element.on}
        if element.with_ is not None:
            table["with"] = element.with_
        table |= {key: value for key, value in element.values.items() if value is not None}
        elements.append(table)
    data["element"] = elements
    return tomli_w.dumps(data)
