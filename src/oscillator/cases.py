"""Cases: parameters, start, end time, solver settings and expected events, from TOML files.

Named cases live in the top-level ``cases/`` folder of the repository, shipped inside the package
as ``oscillator/cases``.  A case file has the tables ``[parameters]``, ``[initial]`` and
``[run]``, optional ``title``/``description`` strings and an optional array of ``[[expected]]``
events (see ``docs/model.md`` and the shipped instances).  A number may be written as a string
expression of numbers and ``pi`` with ``+ - * / **`` and parentheses, e.g. ``P1 = "pi/8"``.
"""

from __future__ import annotations

import ast
import dataclasses
import difflib
import math
import operator
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from oscillator._errors import OscillatorError
from oscillator.events import EventKind
from oscillator.parameters import InitialState, Parameters, SolverOptions, SweepSettings

__all__ = ["Case", "ExpectedEvent", "case_names", "case_to_toml", "load_case", "parse_value"]

_OPERATORS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}


def parse_value(value: Any, *, field: str) -> Any:
    """A number from a case file: a TOML number, or a string such as ``"pi/8"``.

    Only numbers, ``pi``, ``+ - * / **`` and parentheses are allowed in strings.
    """
    if not isinstance(value, str):
        return value

    def evaluate(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return evaluate(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
            return _OPERATORS[type(node.op)](evaluate(node.left), evaluate(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPERATORS:
            return _OPERATORS[type(node.op)](evaluate(node.operand))
        raise ValueError(node)

    try:
        result = evaluate(ast.parse(value.strip(), mode="eval"))
    except (SyntaxError, ValueError, TypeError, ZeroDivisionError, OverflowError, RecursionError) as exc:
        raise OscillatorError(
            f'{field} = {value!r} is not a number; write a number or an expression of numbers and pi such as "pi/8"',
            field=field,
        ) from exc
    return result


@dataclass(frozen=True, slots=True)
class ExpectedEvent:
    """A switching time the article reports, with the independent implementation's time.

    Attributes
    ----------
    t : float or None
        The article's time (s), or ``None`` where the article gives none.
    mass : int
    kind : EventKind
    to_domain : int or None
        The domain entered, when the article names it.
    reference : float or None
        The independent implementation's time, to 4 decimals (MODEL.md Sec. 6).
    tolerance : float
        Allowed distance from the article's time (s); 1e-3 unless the case explains otherwise.
    reference_tolerance : float
        Allowed distance from ``reference`` (s); 5e-5, i.e. equal to the 4 decimals given,
        unless the case explains otherwise.
    label : str
        What the article says, in words.
    note : str
        Why a tolerance differs, or anything else a reader must know.
    """

    t: float | None
    mass: int
    kind: EventKind
    to_domain: int | None = None
    reference: float | None = None
    tolerance: float = 1e-3
    reference_tolerance: float = 5e-5
    label: str = ""
    note: str = ""


@dataclass(frozen=True)
class Case:
    """A runnable case: parameters, initial state, end time, settings and expectations."""

    name: str
    parameters: Parameters
    initial: InitialState
    t_end: float
    options: SolverOptions = field(default_factory=SolverOptions)
    title: str = ""
    description: str = ""
    expected: tuple[ExpectedEvent, ...] = ()
    sweep: SweepSettings | None = None
    source: Path | None = None

    def __post_init__(self) -> None:
        t_end = _finite("run.t_end", self.t_end)
        object.__setattr__(self, "t_end", t_end)
        if t_end <= self.initial.t0:
            raise OscillatorError(
                f"run.t_end = {t_end!r} must be after initial.t0 = {self.initial.t0!r}; "
                f"give an end time later than the start",
                field="t_end",
            )


def _finite(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise OscillatorError(f"{name} must be a finite number, got {value!r}", field=name)
    return float(value)


def _cases_dir() -> Path:
    """The shipped ``cases`` folder: inside the installed package, else the source tree's."""
    packaged = resources.files("oscillator").joinpath("cases")
    if packaged.is_dir():
        return Path(str(packaged))
    # Editable installs and source checkouts: <repo>/src/oscillator/cases.py -> <repo>/cases
    return Path(__file__).resolve().parents[2] / "cases"


def case_names() -> list[str]:
    """Names of the shipped cases, sorted."""
    return sorted(path.stem for path in _cases_dir().glob("*.toml"))


def _suggest(word: str, choices: list[str] | tuple[str, ...]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=3, cutoff=0.5)
    return f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""


def _table(data: dict, name: str, source: str) -> dict:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise OscillatorError(f"{source}: [{name}] must be a table", field=name)
    return value


def _build(cls: type, table: dict, section: str, source: str, defaults: dict | None = None) -> Any:
    names = cls.names()
    values = dict(defaults or {})
    for key, raw in table.items():
        if key not in names:
            raise OscillatorError(
                f"{source}: unknown {section} {key!r}{_suggest(key, names)} (known: {', '.join(names)})",
                field=key,
            )
        values[key] = parse_value(raw, field=f"{section}.{key}")
    try:
        return cls(**values)
    except TypeError as exc:
        missing = [n for n in names if n not in values and n in _required(cls)]
        raise OscillatorError(
            f"{source}: [{section}] is missing {', '.join(missing)}; add "
            + ", ".join(f"{n} = <number>" for n in missing),
            field=missing[0] if missing else section,
        ) from exc
    except OscillatorError as exc:
        raise OscillatorError(f"{source}: {exc}", field=exc.field) from exc


def _required(cls: type) -> set[str]:
    return {
        f.name
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }


_RUN_KEYS = ("t_end", *SolverOptions.names())


def case_from_dict(data: dict, *, name: str, source: str = "<case>", path: Path | None = None) -> Case:
    """Build a :class:`Case` from the parsed contents of a case file."""
    known = {"title", "description", "parameters", "initial", "run", "expected", "sweep"}
    for key in data:
        if key not in known:
            raise OscillatorError(f"{source}: unknown top-level key {key!r}{_suggest(key, sorted(known))}", field=key)
    params = _build(Parameters, _table(data, "parameters", source), "parameters", source)
    initial = _build(InitialState, _table(data, "initial", source), "initial", source)
    run = dict(_table(data, "run", source))
    for key in run:
        if key not in _RUN_KEYS:
            raise OscillatorError(f"{source}: unknown run setting {key!r}{_suggest(key, _RUN_KEYS)}", field=key)
    if "t_end" not in run:
        raise OscillatorError(f"{source}: [run] needs t_end = <end time in s>", field="t_end")
    t_end = parse_value(run.pop("t_end"), field="run.t_end")
    option_values = {k: parse_value(v, field=f"run.{k}") for k, v in run.items()}
    try:
        options = SolverOptions(**option_values)
    except OscillatorError as exc:
        raise OscillatorError(f"{source}: {exc}", field=exc.field) from exc
    expected = _expected_list(data, source)
    sweep = _sweep(_table(data, "sweep", source), source) if "sweep" in data else None
    try:
        return Case(
            name=name,
            parameters=params,
            initial=initial,
            t_end=t_end,
            options=options,
            title=str(data.get("title", "")),
            description=str(data.get("description", "")),
            expected=expected,
            sweep=sweep,
            source=path,
        )
    except OscillatorError as exc:
        raise OscillatorError(f"{source}: {exc}", field=exc.field) from exc


#: Case-file keys of ``[sweep]`` and the SweepSettings fields they fill.
_SWEEP_KEYS = {"from": "start", "to": "stop"} | {n: n for n in SweepSettings.names() if n not in ("start", "stop")}


def _sweep(table: dict, source: str) -> SweepSettings:
    values = {}
    for key, raw in table.items():
        if key not in _SWEEP_KEYS:
            raise OscillatorError(
                f"{source}: unknown sweep setting {key!r}{_suggest(key, list(_SWEEP_KEYS))}", field=key
            )
        values[_SWEEP_KEYS[key]] = raw if key in ("param",) else parse_value(raw, field=f"sweep.{key}")
    for name in ("steps", "transient", "record", "mass", "max_period"):
        if name in values and isinstance(values[name], float) and values[name].is_integer():
            values[name] = int(values[name])
    missing = [k for k in ("param", "from", "to") if _SWEEP_KEYS[k] not in values]
    if missing:
        raise OscillatorError(f"{source}: [sweep] needs {', '.join(missing)}", field="sweep")
    try:
        return SweepSettings(**values)
    except OscillatorError as exc:
        raise OscillatorError(f"{source}: {exc}", field=exc.field) from exc


_EXPECTED_KEYS = ("label", "t", "reference", "mass", "kind", "to_domain", "tolerance", "reference_tolerance", "note")


def _expected_list(data: dict, source: str) -> tuple[ExpectedEvent, ...]:
    items = data.get("expected", [])
    if not isinstance(items, list):
        raise OscillatorError(
            f"{source}: expected events are [[expected]] tables (an array of tables), got {items!r}",
            field="expected",
        )
    return tuple(_expected(item, source) for item in items)


def _expected(item: Any, source: str) -> ExpectedEvent:
    """One ``[[expected]]`` table, every field checked."""

    def refuse(what: str) -> OscillatorError:
        return OscillatorError(f"{source}: [[expected]] {what}", field="expected")

    if not isinstance(item, dict):
        raise refuse(f"entries must be tables, got {item!r}")
    for key in item:
        if key not in _EXPECTED_KEYS:
            raise refuse(f"unknown key {key!r}{_suggest(key, _EXPECTED_KEYS)} (known: {', '.join(_EXPECTED_KEYS)})")
    for key in ("mass", "kind"):
        if key not in item:
            raise refuse(f"entry lacks {key!r}; give mass and kind")
    kinds = [k.value for k in EventKind]
    if item["kind"] not in kinds:
        raise refuse(f"kind must be one of {', '.join(kinds)}, got {item['kind']!r}")
    if item["mass"] not in (1, 2) or isinstance(item["mass"], bool):
        raise refuse(f"mass must be 1 or 2, got {item['mass']!r}")
    to_domain = item.get("to_domain")
    if to_domain is not None and (isinstance(to_domain, bool) or to_domain not in range(9)):
        raise refuse(f"to_domain must be a domain number 0-8, got {to_domain!r}")

    def number(key: str, default: float | None, positive: bool = False) -> float | None:
        if key not in item:
            return default
        value = _finite(f"expected.{key}", parse_value(item[key], field=f"expected.{key}"))
        if positive and value <= 0:
            raise refuse(f"{key} must be > 0, got {value!r}")
        return value

    for key in ("label", "note"):
        if not isinstance(item.get(key, ""), str):
            raise refuse(f"{key} must be text, got {item[key]!r}")
    return ExpectedEvent(
        t=number("t", None),
        mass=int(item["mass"]),
        kind=EventKind(item["kind"]),
        to_domain=None if to_domain is None else int(to_domain),
        reference=number("reference", None),
        tolerance=number("tolerance", 1e-3, positive=True),
        reference_tolerance=number("reference_tolerance", 5e-5, positive=True),
        label=item.get("label", ""),
        note=item.get("note", ""),
    )


def load_case(name_or_path: str | Path) -> Case:
    """Load a shipped case by name (``"instance-3"``) or a case file by path.

    Raises
    ------
    OscillatorError
        Unknown name (with the closest names), unreadable or malformed file (with line and
        column), unknown or invalid fields (naming the field and the fix).
    """
    text_name = str(name_or_path)
    path = Path(text_name)
    if not (path.suffix == ".toml" or path.exists()):
        path = _cases_dir() / f"{text_name}.toml"
        if not path.is_file():
            names = case_names()
            raise OscillatorError(
                f"unknown case {text_name!r}{_suggest(text_name, names)} "
                f"(named cases: {', '.join(names)}; or give the path of a .toml file)",
                field="case",
            )
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise OscillatorError(f"cannot read case file {path}: {exc.strerror}", field="case") from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise OscillatorError(f"{path}: malformed TOML: {exc}", field="case") from exc
    return case_from_dict(data, name=path.stem, source=str(path), path=path)


def case_to_toml(case: Case) -> str:
    """The case as a TOML file that :func:`load_case` reads back to an equal case.

    Every parameter and setting is written out, defaults included, so that a run can be
    repeated exactly.
    """
    import tomli_w

    data: dict[str, Any] = {"title": case.title}
    if case.description:
        data["description"] = case.description
    data["parameters"] = dataclasses.asdict(case.parameters)
    data["initial"] = dataclasses.asdict(case.initial)
    data["run"] = {"t_end": case.t_end, **dataclasses.asdict(case.options)}
    expected = []
    for item in case.expected:
        entry = {k: v for k, v in dataclasses.asdict(item).items() if v is not None and v != ""}
        entry["kind"] = str(item.kind)
        expected.append(entry)
    if expected:
        data["expected"] = expected
    if case.sweep is not None:
        settings = dataclasses.asdict(case.sweep)
        data["sweep"] = {key: settings[name] for key, name in _SWEEP_KEYS.items()}
    return tomli_w.dumps(data, multiline_strings=True)
