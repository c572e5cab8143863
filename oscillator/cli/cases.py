"""``oscillator list`` and ``oscillator show``."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from oscillator.cli.commands import command
from oscillator.cli.console import fail, message, out, say
from oscillator.cli.options import CaseArgument
from oscillator.errors import OscillatorError
from oscillator.io.cases import MAX_CASE_BYTES, Case, case_names, load_case
from oscillator.io.files import read_untrusted
from oscillator.model.parameters import UNITS
from oscillator.text import printable

__all__ = ["list_cases", "show"]


@command(10, "List the named cases.", name="list")
def list_cases() -> None:
    """List the named cases with their titles.

    \b
    Example:
      oscillator list
    """
    table = Table(header_style="bold")
    table.add_column("case")
    table.add_column("title")
    for name in case_names():
        table.add_row(name, load_case(name).title)
    out.print(table)


def _written(case: Case) -> dict[str, str]:
    """The parameters the case file writes as expressions (``P1 = "pi/8"``), as written, with
    their values: ``{"P1": "pi/8 = 0.3926990817"}``."""
    if case.source is None:
        return {}
    try:
        data = tomllib.loads(read_untrusted(case.source, what="case file", field="case", limit=MAX_CASE_BYTES))
    except (OSError, OscillatorError, tomllib.TOMLDecodeError):
        return {}
    table = data.get("parameters")
    if not isinstance(table, dict):
        return {}
    return {
        name: f"{printable(text)} = {getattr(case.parameters, name):.10g}"
        for name, text in table.items()
        if isinstance(text, str) and name in case.parameters.names()
    }


@command(20, "Show a case: parameters, start, settings, expected events.")
def show(
    case: CaseArgument,
    figure: Annotated[
        Path | None,
        typer.Option(
            "--figure",
            metavar="FILE",
            help="A system file's schematic (.png, .svg or .pdf; default: NAME-schematic.png).",
        ),
    ] = None,
) -> None:
    """Show a case: its parameters, start, run settings and expected events; or a system file:
    its masses and elements, and its schematic drawn.

    \b
    Examples:
      oscillator show instance-2
      oscillator show docs/systems/blade-damper.toml --figure blade.png
    """
    from oscillator.io.chains import system_path

    system = system_path(case)
    if system is not None:
        from oscillator.cli.system import show_system

        return show_system(system, figure)
    if figure is not None:
        raise fail("--figure draws a system file's schematic; a case has none (oscillator run draws its figures)")
    try:
        c = load_case(case)
    except OscillatorError as error:
        raise fail(message(error)) from None
    say((c.name, "bold"), f": {c.title}")
    if c.description:
        say(" ".join(c.description.split()))
    params = Table(title="parameters", title_justify="left", header_style="bold")
    for column in ("name", "value", "unit", "name ", "value ", "unit "):
        params.add_column(column, justify="right" if "value" in column else "left")
    written = _written(c)
    items = [
        (name, written.get(name, f"{getattr(c.parameters, name):.10g}"), UNITS.get(name) or "-")
        for name in c.parameters.names()
    ]
    half = (len(items) + 1) // 2
    for left, right in zip(items[:half], [*items[half:], ("", "", "")], strict=False):
        params.add_row(*left, *right)
    out.print(params)
    initial = c.initial
    say(
        f"start: t0 = {initial.t0} s, x1 = {initial.x1} m, v1 = {initial.v1} m/s, x2 = {initial.x2} m, "
        f"v2 = {initial.v2} m/s; the run ends at t_end = {c.t_end} s"
    )
    say("solver: " + ", ".join(f"{name} = {getattr(c.options, name)}" for name in c.options.names()))
    if c.expected:
        table = Table(title="expected events", title_justify="left", header_style="bold")
        for column in ("event", "mass", "kind", "domain", "article (s)", "reference (s)", "tolerance (s)"):
            table.add_column(column)
        for e in c.expected:
            table.add_row(
                printable(e.label),
                str(e.mass),
                str(e.kind),
                "" if e.to_domain is None else str(e.to_domain),
                "—" if e.t is None else f"{e.t}",
                "—" if e.reference is None else f"{e.reference}",
                f"{e.tolerance:g}",
            )
        out.print(table)
