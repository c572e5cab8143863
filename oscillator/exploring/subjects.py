"""What the explorer explores, as one value the page takes: the article's system (a case) or a
friction chain (docs/systems.md).

A :class:`Subject` says everything the page needs of its system and nothing the page assumes:
its controls (:mod:`oscillator.exploring.controls`), how the values on screen become a system
(checked, every refusal naming its field), the motion of a system (a
:class:`~oscillator.exploring.scene.Scene`), what of it is drawn (its
:class:`~oscillator.exploring.scene.Outline`), its file, its title and description, and which of
the page's tools apply (the orbit and its multipliers, a check by CVODE of a compiled drawing:
the article's system only, for now).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from oscillator.exploring.controls import Control, chain_controls, controls_of
from oscillator.exploring.scene import (
    ARTICLE,
    Explored,
    Outline,
    Scene,
    chain_scene_of,
    outline_of,
    scene_of,
    with_changes,
)
from oscillator.io.cases import Case, case_to_toml, resolve_case
from oscillator.model.chains import FrictionChain

__all__ = ["CaseSubject", "ChainSubject", "Subject", "subject_of"]


class Subject(Protocol):
    """A system as the explorer takes it (module docstring)."""

    #: The system explored, as given.
    system: Explored
    #: What the page draws of its motion.
    outline: Outline
    #: Whether the page finds its periodic orbit and multipliers.
    orbits: bool
    #: The engines that may draw a change (the first is the reference).
    engines: tuple[str, ...]

    @property
    def name(self) -> str:
        """A short name (the downloads' file names start with it)."""

    @property
    def title(self) -> str:
        """The page's title (text from a file: escaped where it is shown)."""

    @property
    def description(self) -> str:
        """What the file says of the system, or ``""``."""

    def controls(self) -> list[Control]:
        """A control for every number the page may change, each with its group."""

    def changed(self, values: dict[str, float]) -> Explored:
        """The system with ``values`` (names of :meth:`controls`), checked: an
        :class:`~oscillator.errors.InputError` naming the field otherwise."""

    def scene(self, system: Explored, periods: int, *, engine: str, stop: Callable[[], bool] | None = None) -> Scene:
        """The motion of ``system`` (one :meth:`changed` gave) over ``periods`` forcing periods."""

    def toml(self, system: Explored) -> str:
        """``system`` as a file that ``oscillator run`` reads."""


@dataclass(frozen=True)
class CaseSubject:
    """The article's system: a case, its 25 parameters and its start (docs/explore.md)."""

    system: Case
    outline: Outline = field(default=ARTICLE, init=False)
    orbits: bool = field(default=True, init=False)
    engines: tuple[str, ...] = field(default=("cvode", "dop853", "scipy"), init=False)

    @property
    def name(self) -> str:
        return self.system.name

    @property
    def title(self) -> str:
        return self.system.full_title

    @property
    def description(self) -> str:
        # a case changed by overrides (said in its title) is another system: the description of the one it came
        # from is not its own
        case = self.system
        return "" if case.modified or "(modified:" in case.title else case.description

    def controls(self) -> list[Control]:
        return controls_of(self.system)

    def changed(self, values: dict[str, float]) -> Case:
        return with_changes(self.system, values)

    def scene(self, system: Explored, periods: int, *, engine: str, stop: Callable[[], bool] | None = None) -> Scene:
        assert isinstance(system, Case)
        return scene_of(system, periods, engine=engine, stop=stop)

    def toml(self, system: Explored) -> str:
        assert isinstance(system, Case)
        return case_to_toml(system)


@dataclass(frozen=True)
class ChainSubject:
    """A friction chain: its every number by name (``Omega``, ``blade.m``, ``platform.F``),
    drawn by CVODE (the chains' one engine) through
    :func:`~oscillator.exploring.scene.chain_scene_of`."""

    system: FrictionChain
    label: str = "system"
    outline: Outline = field(init=False)
    orbits: bool = field(default=False, init=False)
    engines: tuple[str, ...] = field(default=("cvode",), init=False)

    #: Each control's value as the file gives it (a change is what differs from these).
    given: dict[str, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "outline", outline_of(self.system.checked()))
        object.__setattr__(self, "given", {control.name: control.value for control in self.controls()})

    @property
    def name(self) -> str:
        return self.label

    @property
    def title(self) -> str:
        return self.system.title or self.label

    @property
    def description(self) -> str:
        return ""

    def controls(self) -> list[Control]:
        return chain_controls(self.system)

    def changed(self, values: dict[str, float]) -> FrictionChain:
        changes = {name: value for name, value in values.items() if self.given.get(name) != value}
        return self.system.with_values(changes).checked() if changes else self.system

    def scene(self, system: Explored, periods: int, *, engine: str, stop: Callable[[], bool] | None = None) -> Scene:
        assert isinstance(system, FrictionChain)
        return chain_scene_of(system, periods, stop=stop)

    def toml(self, system: Explored) -> str:
        from oscillator.io.chains import chain_to_toml

        assert isinstance(system, FrictionChain)
        return chain_to_toml(system)


def subject_of(target: Any, **overrides: float) -> CaseSubject | ChainSubject:
    """What ``target`` explores: a friction chain or a system file's path (its numbers changed by
    name by ``overrides``), else a case (a name, a case file or a :class:`~oscillator.Case`)."""
    from oscillator.io.chains import load_system, system_path

    if isinstance(target, CaseSubject | ChainSubject):
        return target
    if isinstance(target, FrictionChain):
        chain, label = target, "system"
    elif isinstance(target, str | Path) and (path := system_path(str(target))) is not None:
        chain, label = load_system(path), path.stem
    else:
        return CaseSubject(resolve_case(target, **overrides))
    return ChainSubject(chain.with_values(overrides) if overrides else chain, label)
