"""``oscillator design FILE``: a declared machine's design, one number over one band
(:func:`~oscillator.designing.chain_design.chain_design`, docs/damper-design.md)."""

from __future__ import annotations

import functools
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rich.text import Text

from oscillator.cli.console import fail, load, message, out
from oscillator.cli.resumable import with_progress
from oscillator.cli.system import changed, finished
from oscillator.errors import InputError, OscillatorError
from oscillator.io.files import check_new
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.io.files import FolderClaim
    from oscillator.model.chains import FrictionChain

__all__ = ["design_system"]


def design_system(
    target: str,
    assignments: list[str] | None,
    ranges: dict[str, tuple[float, float]],
    band: tuple[tuple[str, float, float], int],
    objectives: list[str],
    out_dir: Path | None,
    case_only: list[str],
    plots: bool,
    quiet: bool,
) -> bool:
    """``oscillator design FILE`` if ``target`` is a system file: the value of ``--vary``'s one
    number that makes the worst ``--objective`` over the ``--over`` band (swept over ``--band``
    values) smallest; its folder (history.parquet/.csv, system.toml at the best value, run.json,
    figures/design.png) written; whether it was one."""
    from oscillator.io.chains import system_path

    path = system_path(target)
    if path is None:
        return False
    (name, low, high), values = band
    chain, claim = _checked(path, assignments, ranges, band[0], objectives, out_dir, case_only, quiet)
    from oscillator.designing.chain_design import chain_design

    try:
        found = with_progress(
            lambda progress=None: chain_design(
                chain, ranges, {name: (low, high)}, objectives[0], sweep=values, progress=progress
            ),
            f"{printable(chain.title or path.stem)}: design of {', '.join(printable(n) for n in ranges)}",
            "values judged",
            quiet,
        )
    except OscillatorError as error:
        claim.abandon()
        raise fail(message(error), code=1) from None
    except BaseException:
        claim.abandon()
        raise
    from oscillator.report.chain_frequency import write_chain_design

    folder = write_chain_design(found, claim, band=(name, low, high), command=["oscillator", *sys.argv[1:]])
    if not quiet:
        out.print(Text(f"  {found.summary}"))
        out.print(Text(f"  {len(found.history)} values of {found.vary} judged (history.parquet)"))
    finished(folder, functools.partial(_figure, folder, found) if plots else None)
    return True


def _checked(
    path: Path,
    assignments: list[str] | None,
    ranges: dict[str, tuple[float, float]],
    over: tuple[str, float, float],
    objectives: list[str],
    out_dir: Path | None,
    case_only: list[str],
    quiet: bool,
) -> tuple[FrictionChain, FolderClaim]:
    """The machine and the claimed folder, every input checked first (one message naming the
    field and exit 2 on a refusal, nothing written)."""
    from oscillator.io.chains import load_system

    name, low, high = over
    try:
        if case_only:
            raise InputError(
                f"{case_only[0]} applies to the article's cases; a system's design varies one number over one band "
                "(--vary NAME=LOW,HIGH once, --over, --objective once) for now",
                field=case_only[0],
            )
        if len(objectives) != 1:
            raise InputError("a system's design takes one --objective for now", field="objective")
        if out_dir is not None:
            check_new(out_dir, option="--out")
        load("oscillator.designing.chain_design", notice=not quiet)
        from oscillator.report.runs import claim_output

        chain = changed(load_system(path), assignments or [])
        if len(ranges) != 1:
            raise InputError("a system's design varies one number (--vary NAME=LOW,HIGH once) for now", field="vary")
        for number, (lowest, highest) in {**ranges, name: (low, high)}.items():  # each end checked, named
            chain.with_values({number: lowest}).with_values({number: highest})
        return chain, claim_output(out_dir, f"{path.stem}-design")
    except OscillatorError as error:
        raise fail(message(error)) from None


def _figure(folder: Path, found: object) -> None:
    from oscillator.report.chain_frequency import design_figure
    from oscillator.report.figures import save_figure

    figures = folder / "figures"
    figures.mkdir(exist_ok=True)
    save_figure(design_figure(found), figures, "design")  # type: ignore[arg-type]
