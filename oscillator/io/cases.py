"""Cases: parameters, start, end time, solver settings and expected events, from TOML files.

Named cases live in the top-level ``cases/`` folder of the repository, shipped inside the package
as ``oscillator/cases``.  A case file has the tables ``[parameters]``, ``[initial]`` and
``[run]``, optional ``title``/``description`` strings and an optional array of ``[[expected]]``
events (see ``docs/cases.md`` and the shipped instances).  A number may be written as a string
expression of numbers and ``pi`` (:mod:`oscillator.io.expressions`), e.g. ``P1 = "pi/8"``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from oscillator.errors import InputError, OscillatorError
from oscillator.io.expressions import parse_value
from oscillator.io.files import read_untrusted
from oscillator.model.events import EventKind
from oscillator.model.parameters import (
    InitialState,
    Parameters,
    SolverOptions,
    SweepSettings,
    as_float,
    is_finite_number,
    real_argument,
)
from oscillator.model.system import ARTICLE, System
from oscillator.text import printable, shown, unsafe_characters

__all__ = [
    "TAKES_A_SYSTEM",
    "Case",
    "ExpectedEvent",
    "case_names",
    "case_to_toml",
    "load_case",
    "not_a_case",
    "resolve_case",
    "section_times",
]

#: The largest case file read (bytes); the article's cases are about 2 kB.
MAX_CASE_BYTES = 1 << 20
#: The longest texts a case may carry, in characters.
MAX_TEXT = {"title": 300, "description": 10_000, "label": 300, "note": 2_000}


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
        The independent implementation's time, to 4 decimals (docs/model.md, Sec. 9).
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
    """A runnable case: parameters, initial state, end time, settings and expectations.

    ``modified`` lists the parameters and initial values that overrides changed from the case
    as written (``"Omega 1.6 → 1.7"``); such a case expects nothing (its
    ``expected`` events were the written case's), and :attr:`full_title` says so.
    """

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
    modified: tuple[str, ...] = ()
    #: Keep only the events at or after this time (``[run] keep_events_from``; all when None):
    #: a long run's memory and report stay bounded.  The counts still count every event.
    keep_events_from: float | None = None

    @property
    def system(self) -> System:
        """The machine this case runs: the article's two-mass oscillator (its shape, names and
        sizes: :mod:`oscillator.model.system`)."""
        return ARTICLE

    @property
    def full_title(self) -> str:
        """The title, and what overrides changed, if anything: at most ``MAX_TEXT["title"]``
        characters, a case file's limit (the changes that do not fit are counted, and a title too
        long to leave room for them is cut), so that the case written reads back."""
        if not self.modified:
            return self.title
        limit, count = MAX_TEXT["title"], len(self.modified)
        for kept in range(count, -1, -1):
            listed = [*self.modified[:kept], *([f"and {count - kept} more"] if kept < count else [])]
            changes = f"modified: {', '.join(listed)}"
            full = f"{self.title} ({changes})" if self.title else changes
            if len(full) <= limit:
                return full
        changes = f"modified: {count} values"
        return f"{self.title[: limit - len(changes) - 4]}… ({changes})"

    def __post_init__(self) -> None:
        t_end = real_argument(self.t_end, "run.t_end")
        object.__setattr__(self, "t_end", t_end)
        if self.keep_events_from is not None:
            keep = as_float(self.keep_events_from)
            if math.isnan(keep):
                raise InputError(
                    f"run.keep_events_from must be a time in s, got {shown(self.keep_events_from)}",
                    field="keep_events_from",
                )
            object.__setattr__(self, "keep_events_from", keep)
        if t_end <= self.initial.t0:
            raise InputError(
                f"run.t_end = {t_end!r} must be after initial.t0 = {self.initial.t0!r}; "
                f"give an end time later than the start",
                field="t_end",
            )


def _given(value: float | None) -> float:
    """A value with a default, which is never ``None``."""
    assert value is not None
    return value


def _cases_dir() -> Path:
    """The shipped ``cases`` folder: inside the installed package, else the source tree's."""
    packaged = resources.files("oscillator").joinpath("cases")
    if packaged.is_dir():
        return Path(str(packaged))
    # Editable installs and source checkouts: <repo>/oscillator/io/cases.py -> <repo>/cases
    return Path(__file__).resolve().parents[2] / "cases"


def is_shipped(path: Path) -> bool:
    """Whether ``path`` is one of the shipped case files."""
    try:
        return Path(path).resolve().parent == _cases_dir().resolve()
    except OSError:
        return False


def case_names() -> list[str]:
    """Names of the shipped cases, sorted."""
    return sorted(path.stem for path in _cases_dir().glob("*.toml"))


def _suggest(word: str, choices: list[str] | tuple[str, ...]) -> str:
    if not isinstance(word, str) or len(word) > 64:
        return ""
    close = difflib.get_close_matches(word, list(choices), n=3, cutoff=0.5)
    return f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""


def _table(data: dict[str, Any], name: str, source: str) -> dict[str, Any]:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise InputError(f"{source}: [{name}] must be a table", field=name)
    return value


def _build(cls: Any, table: dict[str, Any], section: str, source: str, defaults: dict[str, Any] | None = None) -> Any:
    names = cls.names()
    values = dict(defaults or {})
    for key, raw in table.items():
        if key not in names:
            raise InputError(
                f"{source}: unknown {section} {shown(key)}{_suggest(key, names)} (known: {', '.join(names)})",
                field=key,
            )
        values[key] = parse_value(raw, field=f"{section}.{key}")
    try:
        return cls(**values)
    except TypeError as exc:
        missing = [n for n in names if n not in values and n in _required(cls)]
        raise InputError(
            f"{source}: [{section}] is missing {', '.join(missing)}; add "
            + ", ".join(f"{n} = <number>" for n in missing),
            field=missing[0] if missing else section,
        ) from exc
    except OscillatorError as exc:
        raise InputError(f"{source}: {exc}", field=exc.field) from exc


def _required(cls: type) -> set[str]:
    return {
        f.name
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }


_RUN_KEYS = ("t_end", "keep_events_from", *SolverOptions.names())


def case_from_dict(data: dict[str, Any], *, name: str, source: str = "<case>", path: Path | None = None) -> Case:
    """Build a :class:`Case` from the parsed contents of a case file."""
    known = {"title", "description", "parameters", "initial", "run", "expected", "sweep"}
    for key in data:
        if key not in known:
            hint = _suggest(key, sorted(known))
            raise InputError(f"{source}: unknown top-level key {shown(key)}{hint}", field=str(key))
    params = _build(Parameters, _table(data, "parameters", source), "parameters", source)
    initial = _build(InitialState, _table(data, "initial", source), "initial", source)
    run = dict(_table(data, "run", source))
    for key in run:
        if key not in _RUN_KEYS:
            raise InputError(f"{source}: unknown run setting {shown(key)}{_suggest(key, _RUN_KEYS)}", field=key)
    if "t_end" not in run:
        raise InputError(f"{source}: [run] needs t_end = <end time in s>", field="t_end")
    t_end = parse_value(run.pop("t_end"), field="run.t_end")
    keep = parse_value(run.pop("keep_events_from"), field="run.keep_events_from") if "keep_events_from" in run else None
    option_values = {k: parse_value(v, field=f"run.{k}") for k, v in run.items()}
    try:
        options = SolverOptions(**option_values)
    except OscillatorError as exc:
        raise InputError(f"{source}: {exc}", field=exc.field) from exc
    expected = _expected_list(data, source)
    _check_expected_times(expected, initial.t0, t_end, source)
    sweep = _sweep(_table(data, "sweep", source), source) if "sweep" in data else None
    title, description = _text(data, "title", source), _text(data, "description", source)
    try:
        return Case(
            name=name,
            parameters=params,
            initial=initial,
            t_end=t_end,
            keep_events_from=keep,
            options=options,
            title=title,
            description=description,
            expected=expected,
            sweep=sweep,
            source=path,
        )
    except OscillatorError as exc:
        raise InputError(f"{source}: {exc}", field=exc.field) from exc


def _check_expected_times(expected: tuple[ExpectedEvent, ...], t0: float, t_end: object, source: str) -> None:
    """Refuse an expected event whose time lies outside the run: it could never be checked
    (``check`` would report every event within tolerance without looking at it)."""
    if not is_finite_number(t_end):
        return  # Case refuses the end time itself, naming it
    for item in expected:
        time = _expected_time(item)
        if time is not None and not t0 <= time <= t_end:
            what = f"{item.label!r}" if item.label else f"m{item.mass} {item.kind}"
            raise InputError(
                f"{source}: [[expected]] {printable(what)} at t = {time:g} s lies outside the run "
                f"[t0, t_end] = [{t0:g}, {t_end:g}] s and could never be checked; raise run.t_end or "
                "remove the entry",
                field="expected",
            )


def _text(table: dict[str, Any], key: str, source: str, *, where: str = "") -> str:
    """A text of the case (title, description, label, note): a string of bounded length,
    without control characters (descriptions and notes may hold line breaks and tabs)."""
    value = table.get(key, "")
    name = f"{where}{key}"
    if not isinstance(value, str):
        raise InputError(f"{source}: {name} must be text in quotes, got {printable(repr(value))[:80]}", field=name)
    if len(value) > MAX_TEXT[key]:
        raise InputError(
            f"{source}: {name} is {len(value):,} characters long; at most {MAX_TEXT[key]:,} are allowed", field=name
        )
    bad = unsafe_characters(value, allow="\n\t\r" if key in ("description", "note") else "")
    if bad:
        raise InputError(f"{source}: {name} holds the control character {printable(bad[0])!s}; remove it", field=name)
    return value


#: Case-file keys of ``[sweep]`` and the SweepSettings fields they fill.
_SWEEP_KEYS = {"from": "start", "to": "stop"} | {n: n for n in SweepSettings.names() if n not in ("start", "stop")}


def _sweep(table: dict[str, Any], source: str) -> SweepSettings:
    values = {}
    for key, raw in table.items():
        if key not in _SWEEP_KEYS:
            raise InputError(
                f"{source}: unknown sweep setting {shown(key)}{_suggest(key, list(_SWEEP_KEYS))}", field=key
            )
        values[_SWEEP_KEYS[key]] = raw if key in ("param",) else parse_value(raw, field=f"sweep.{key}")
    for name in ("steps", "transient", "record", "mass", "max_period"):
        if name in values and isinstance(values[name], float) and values[name].is_integer():
            values[name] = int(values[name])
    missing = [k for k in ("param", "from", "to") if _SWEEP_KEYS[k] not in values]
    if missing:
        raise InputError(f"{source}: [sweep] needs {', '.join(missing)}", field="sweep")
    try:
        return SweepSettings(**values)
    except OscillatorError as exc:
        raise InputError(f"{source}: {exc}", field=exc.field) from exc


_EXPECTED_KEYS = ("label", "t", "reference", "mass", "kind", "to_domain", "tolerance", "reference_tolerance", "note")


def _expected_list(data: dict[str, Any], source: str) -> tuple[ExpectedEvent, ...]:
    items = data.get("expected", [])
    if not isinstance(items, list):
        raise InputError(
            f"{source}: expected events are [[expected]] tables (an array of tables), got {shown(items)}",
            field="expected",
        )
    return tuple(_expected(item, source) for item in items)


def _expected(item: Any, source: str) -> ExpectedEvent:
    """One ``[[expected]]`` table, every field checked."""

    def refuse(what: str) -> InputError:
        return InputError(f"{source}: [[expected]] {what}", field="expected")

    if not isinstance(item, dict):
        raise refuse(f"entries must be tables, got {shown(item)}")
    for key in item:
        if key not in _EXPECTED_KEYS:
            hint = _suggest(key, _EXPECTED_KEYS)
            raise refuse(f"unknown key {shown(key)}{hint} (known: {', '.join(_EXPECTED_KEYS)})")
    for key in ("mass", "kind"):
        if key not in item:
            raise refuse(f"entry lacks {key!r}; give mass and kind")
    kinds = [k.value for k in EventKind]
    if item["kind"] not in kinds:
        raise refuse(f"kind must be one of {', '.join(kinds)}, got {shown(item['kind'])}")
    if item["mass"] not in (1, 2) or isinstance(item["mass"], bool):
        raise refuse(f"mass must be 1 or 2, got {shown(item['mass'])}")
    to_domain = item.get("to_domain")
    if to_domain is not None and (isinstance(to_domain, bool) or to_domain not in range(9)):
        raise refuse(f"to_domain must be a domain number 0-8, got {shown(to_domain)}")

    def number(key: str, default: float | None, positive: bool = False) -> float | None:
        if key not in item:
            return default
        value = real_argument(parse_value(item[key], field=f"expected.{key}"), f"expected.{key}")
        if positive and value <= 0:
            raise refuse(f"{key} must be > 0, got {value!r}")
        return value

    label, note = (_text(item, key, source, where="[[expected]] ") for key in ("label", "note"))
    return ExpectedEvent(
        t=number("t", None),
        mass=int(item["mass"]),
        kind=EventKind(item["kind"]),
        to_domain=None if to_domain is None else int(to_domain),
        reference=number("reference", None),
        tolerance=_given(number("tolerance", 1e-3, positive=True)),
        reference_tolerance=_given(number("reference_tolerance", 5e-5, positive=True)),
        label=label,
        note=note,
    )


#: What takes a declared system (a :class:`~oscillator.model.chains.FrictionChain`) where a case goes.
TAKES_A_SYSTEM = (
    "simulate, find_orbit, continue_orbit, sensitivities, frequency_sweep, worst_over, design, "
    "frequency_response, find_attractors, find_basins, follow_attractors, regime_atlas, lyapunov, explore"
)


def not_a_case(value: object) -> str:
    """Why ``value`` is no case: a declared system where the analysis takes the article's cases
    only (and what takes one), or another object."""
    from oscillator.model.chains import FrictionChain

    if isinstance(value, FrictionChain):
        return (
            f"this analysis takes the article's cases (a name, a case file or a Case), not a declared system; the "
            f"ones that take a system: {TAKES_A_SYSTEM} (docs/systems.md)"
        )
    return f"case must be a case's name, a case file's path or a Case, got {shown(value)}"


def load_case(name_or_path: str | Path) -> Case:
    """Load a shipped case by name (``"instance-3"``) or a case file by path.

    A case file is read as untrusted text: it must be a regular UTF-8 file of at most
    :data:`MAX_CASE_BYTES` (a FIFO, device or folder is refused without being read).

    Raises
    ------
    OscillatorError
        Unknown name (with the closest names), unreadable or malformed file (with line and
        column), unknown or invalid fields (naming the field and the fix).
    """
    if not isinstance(name_or_path, str | Path):
        raise InputError(not_a_case(name_or_path), field="case")
    text_name = str(name_or_path)
    path = Path(text_name)
    if not (path.suffix == ".toml" or os.path.lexists(path)):
        path = _cases_dir() / f"{text_name}.toml"
        if not path.is_file():
            names = case_names()
            raise InputError(
                f"unknown case {printable(repr(text_name))}{_suggest(text_name, names)} "
                f"(named cases: {', '.join(names)}; or give the path of a .toml file)",
                field="case",
            )
    shown = printable(str(path))
    try:
        text_name.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(f"case file {shown}: its name is not UTF-8 text; rename the file", field="case") from None
    text = read_untrusted(path, what="case file", field="case", limit=MAX_CASE_BYTES)
    text = text.removeprefix("\ufeff")  # a byte-order mark, as some Windows editors save UTF-8
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{shown}: malformed TOML: {exc}", field="case") from exc
    except ValueError as exc:  # an integer of more than 4300 digits
        raise InputError(f"{shown}: malformed TOML: an integer has more than 4300 digits", field="case") from exc
    except (RecursionError, MemoryError) as exc:
        raise InputError(f"{shown}: malformed TOML: arrays or tables nested too deeply", field="case") from exc
    return case_from_dict(data, name=path.stem, source=shown, path=path)


#: The names an override may set, by the part of the case they belong to.
_OVERRIDABLE = (
    ("parameters", Parameters.names()),
    ("initial", InitialState.names()),
    ("options", SolverOptions.names()),
)


def check_setting(name: str) -> None:
    """Refuse a name that is neither a parameter, an initial value nor a solver option."""
    known = [n for _, names in _OVERRIDABLE for n in names]
    if name not in known:
        raise InputError(
            f"unknown setting {shown(name)}{_suggest(name, known)} (parameters, initial state "
            f"t0 x1 v1 x2 v2, or solver options {', '.join(SolverOptions.names())})",
            field=str(name),
        )


def resolve_case(
    case: Case | str | Path,
    /,
    *,
    t_end: float | None = None,
    keep_events_from: float | None = None,
    **overrides: float,
) -> Case:
    """The case with overrides applied: parameter, initial-state and solver-option names.

    A change of a parameter or of the start makes another case: its ``expected`` events (the
    article's times for the case as written) are dropped, and ``modified`` lists the changes.
    Solver options change no physics and keep them; an earlier ``t_end`` drops the expected
    events after it.  A new start ``t0`` without a ``t_end`` keeps the run's length: the end
    moves with the start (``resolve_case("instance-1", t0=2.0)`` runs from 2.0 to 2.9 s).
    ``keep_events_from`` replaces the case's own (``[run] keep_events_from``).
    """
    if not isinstance(case, Case):
        case = load_case(case)
    if not overrides and t_end is None and keep_events_from is None:
        return case  # nothing to apply (a Case's expected events lie within its run already)
    groups: dict[str, dict[str, Any]] = {group: {} for group, _ in _OVERRIDABLE}
    for key, value in overrides.items():
        check_setting(key)
        group = next(group for group, names in _OVERRIDABLE if key in names)
        groups[group][key] = value
    # each group rebuilt (and checked) only where it changes: the hot paths change one parameter
    parameters = (
        dataclasses.replace(case.parameters, **groups["parameters"]) if groups["parameters"] else case.parameters
    )
    initial = dataclasses.replace(case.initial, **groups["initial"]) if groups["initial"] else case.initial
    options = dataclasses.replace(case.options, **groups["options"]) if groups["options"] else case.options
    parts = {"parameters": parameters, "initial": initial}
    changes = tuple(
        f"{name} {getattr(case_part, name):.10g} → {getattr(parts[group], name):.10g}"
        for group, case_part in (("parameters", case.parameters), ("initial", case.initial))
        for name in case_part.names()
        if name in groups[group] and getattr(parts[group], name) != getattr(case_part, name)
    )
    if t_end is None:  # a new start without an end keeps the run's length
        t_end = case.t_end + (initial.t0 - case.initial.t0 if "t0" in groups["initial"] else 0.0)
    t_end = real_argument(t_end, "run.t_end")  # checked before the expected events are compared with it
    expected: tuple[ExpectedEvent, ...] = ()
    if changes:
        modified = (*case.modified, *changes)
    else:
        expected = tuple(e for e in case.expected if (t := _expected_time(e)) is None or t <= t_end)
        modified = case.modified
    return dataclasses.replace(
        case,
        parameters=parameters,
        initial=initial,
        options=options,
        t_end=t_end,
        keep_events_from=case.keep_events_from if keep_events_from is None else keep_events_from,
        expected=expected,
        modified=modified,
    )


def _expected_time(expected: ExpectedEvent) -> float | None:
    return expected.t if expected.t is not None else expected.reference


def case_to_toml(case: Case) -> str:
    """The case as a TOML file that :func:`load_case` reads back to an equal case.

    Every parameter and setting is written out, defaults included, so that a run can be
    repeated exactly.
    """
    import tomli_w

    data: dict[str, Any] = {"title": case.full_title}
    if case.description:
        data["description"] = case.description
    data["parameters"] = dataclasses.asdict(case.parameters)
    data["initial"] = dataclasses.asdict(case.initial)
    data["run"] = {"t_end": case.t_end, **dataclasses.asdict(case.options)}
    if case.keep_events_from is not None:
        data["run"]["keep_events_from"] = case.keep_events_from
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


def section_times(case: Case, first: int, last: int) -> np.ndarray:
    """The stroboscopic section's times ``t0 + k T`` for ``k = first .. last``, refused (naming
    Omega) where the forcing period is lost beside ``t0`` in floating point: the times would not
    increase, and every run from them would fail on a time it cannot reach."""
    t0, period = case.initial.t0, case.parameters.period
    marks: np.ndarray = t0 + period * np.arange(first, last + 1)
    if not (np.isfinite(marks).all() and np.all(np.diff(marks) > 0) and marks[0] >= t0 and marks[-1] > t0):
        raise InputError(
            f"Omega = {case.parameters.Omega!r}: its forcing period, {period:.3g} s, is lost beside t0 = {t0:g} s in "
            "floating point; give an Omega of physical size",
            field="Omega",
        )
    return marks
