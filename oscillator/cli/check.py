"""``oscillator check``: a case's switching times against the article's."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer
from rich import box
from rich.table import Table
from rich.text import Text

from oscillator.cli.commands import command
from oscillator.cli.console import err, fail, load, message, out, say
from oscillator.cli.inputs import case_from, check_engine
from oscillator.cli.options import EngineOption
from oscillator.errors import InputError, OscillatorError, SimulationFailed
from oscillator.io.cases import Case, is_shipped
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = ["check"]


@command(40, "Compare a case's switching times with the article's.")
def check(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A case or a system file with [[expected]] events.")],
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", metavar="NAME=VALUE", help="A solver option (rtol, atol, ...) for this check."),
    ] = None,
    engine: EngineOption = None,
) -> None:
    """Compare a case's switching times with the article's, or a system file's events with its
    [[expected]] ones; exit 1 if one is out of tolerance.

    \b
    Examples:
      oscillator check instance-5
      oscillator check instance-3 --set rtol=1e-12 --set atol=1e-12
      oscillator check docs/systems/belt-chain.toml
    """
    from oscillator.io.chains import system_path

    system = system_path(case)
    if system is not None:
        if set_ or engine:
            raise fail("--set and --engine apply to the article's cases; a system file is checked as written")
        from oscillator.cli.system import check_system

        return check_system(system)
    try:
        check_engine(engine)
        resolved = case_from(case, None, set_)
        if resolved.modified:
            raise InputError(
                f"--set changes the case ({', '.join(resolved.modified)}); its expected times are for the case as "
                f"written, so check takes solver options only (rtol, atol, ...); write a case file to check another "
                f"case",
                field="--set",
            )
        if not resolved.expected:
            raise InputError(f"case {shown(resolved.name)} has no [[expected]] events to check against", field="case")
        load("oscillator.analysis.reproduction", "oscillator.hybrid.simulate", notice=True)
        from oscillator.analysis.reproduction import compare
        from oscillator.hybrid.recording import SaveAt
        from oscillator.hybrid.simulate import simulate

        table = compare(resolved, simulate(resolved, save=SaveAt(steps=False), engine=engine).events)
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    except KeyboardInterrupt:
        raise fail("interrupted", code=130) from None
    out.print(_times_table(resolved, table))
    for row in table.itertuples(index=False):
        if row.note:
            out.print(Text(f"{printable(row.label)}: {printable(row.note)}", style="dim"))
    failed = int((~(table.within_article & table.within_reference)).sum())
    if failed:
        err.print(Text(f"{failed} expected time(s) out of tolerance", style="bold red"))
        raise typer.Exit(1)
    say(f"all {len(table)} expected times within tolerance")


def _times_table(case: Case, table: pd.DataFrame) -> Table:
    """The comparison as a table: each expected event's times, ours minus them, and a verdict."""
    view = Table(
        title=f"{printable(case.name)}: expected switching times (s)",
        title_justify="left",
        header_style="bold",
        box=box.SIMPLE_HEAD,
        pad_edge=False,
    )
    source = "article" if case.source is None or is_shipped(case.source) else "expected"
    view.add_column("event", ratio=1, min_width=16)
    for column in (source, "ref.", "ours", f"− {source}", "− ref.", "ok"):  # the differences: ours minus that
        view.add_column(column, no_wrap=True, justify="right")
    view.caption = f"ref.: the independent implementation; − {source}, − ref.: ours minus that time"
    view.caption_justify = "left"
    for row in table.itertuples(index=False):
        ok = row.within_article and row.within_reference
        view.add_row(
            printable(row.label),
            _time(row.article),
            _time(row.reference),
            _time(row.ours, 6),
            _delta(row.ours_minus_article),
            _delta(row.ours_minus_reference),
            Text("✓") if ok else Text("✗", "red"),
        )
    return view


def _time(value: float, digits: int = 4) -> str:
    return "—" if value != value else f"{value:.{digits}f}"


def _delta(value: float) -> str:
    return "—" if value != value else f"{value:+.1e}"
