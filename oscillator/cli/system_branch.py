"""``oscillator continue FILE``: a declared machine's period-1 orbit followed in one of its numbers
through folds (:func:`~oscillator.orbits.chain_branch.continue_chain_orbit`, docs/systems.md)."""

from __future__ import annotations

import functools
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from rich.text import Text

from oscillator.cli.console import fail, load, message, out
from oscillator.cli.resumable import with_progress
from oscillator.cli.system import changed, finished, guessed
from oscillator.errors import InputError, OscillatorError
from oscillator.io.files import check_new
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.chain_branch import ChainBranch

__all__ = ["continue_system"]


def continue_system(
    target: str,
    assignments: list[str] | None,
    span: tuple[str, float, float],
    settings: tuple[float | None, int, str | None, int | None],
    out_dir: Path | None,
    article: tuple[object, ...],
    quiet: bool,
) -> bool:
    """``oscillator continue FILE`` if ``target`` is a system file: the branch from ``--from`` to
    ``--to`` in ``--param`` (``settings``: ``--step``, ``--max-points``, ``--guess``,
    ``--transient``), its folder written, its folds and how it ended said (exit 1 if it ended before
    ``--to``: the branch so far kept); ``article``: ``--period``, ``--section``, ``--coordinate``
    and ``--over`` as given, refused unless left out; whether it was one."""
    from oscillator.io.chains import load_system, system_path

    path = system_path(target)
    if path is None:
        return False
    (param, start, stop), (step, max_points, guess, transient) = span, settings
    flags = ("--period", "--section", "--coordinate", "--over")
    case_only = [flag for flag, value, left in zip(flags, article, (1, None, None, None), strict=True) if value != left]
    try:
        if case_only:
            raise InputError(f"{case_only[0]} applies to the article's cases", field=case_only[0])
        if out_dir is not None:
            check_new(out_dir, option="--out")
        load("oscillator.orbits.chain_branch", notice=not quiet)
        from oscillator.orbits.chain_branch import continue_chain_orbit
        from oscillator.report.runs import claim_output

        chain = changed(load_system(path), assignments or [])
        chain.with_values({param: start}).with_values({param: stop})  # both ends checked, the field named
        given = guessed(guess, chain.system.state)
        run = functools.partial(
            continue_chain_orbit,
            chain,
            param=param,
            start=start,
            stop=stop,
            guess=None if given is None else np.asarray(given),
            step=0.1 if step is None else step,
            max_points=max_points,
            transient=100 if transient is None else transient,
        )
        run(max_points=2)  # the start's orbit found and every setting checked before a folder is made
        claim = claim_output(out_dir, f"{path.stem}-continue")
    except OscillatorError as error:
        raise fail(message(error), code=2 if isinstance(error, InputError) else 1) from None
    try:
        branch = with_progress(
            run, f"{printable(chain.title or path.stem)}: branch in {printable(param)}", "points", quiet
        )
    except BaseException:
        claim.abandon()
        raise
    return _written(branch, claim, stop, quiet)


def _written(branch: ChainBranch, claim: object, stop: float, quiet: bool) -> bool:
    from oscillator.report.chain_frequency import branch_figure, write_chain_branch
    from oscillator.report.figures import save_figure

    folder = write_chain_branch(branch, claim, command=["oscillator", *sys.argv[1:]])  # type: ignore[arg-type]
    if not quiet:
        for _, row in branch.bifurcations.iterrows():
            out.print(Text(f"  {printable(str(row.kind))} at {branch.param} = {row[branch.param]:.8g}"))
        out.print(Text(f"  {len(branch.points)} points; ended: {printable(branch.ended)}"))

    def draw() -> None:
        figures = folder / "figures"
        figures.mkdir(exist_ok=True)
        save_figure(branch_figure(branch), figures, "branch")

    finished(folder, draw)
    if branch.ended != "the end of the span":
        raise fail(f"the branch ended before {branch.param} = {stop:g}: {branch.ended}; it is kept in {folder}", 1)
    return True
