"""``oscillator basins FILE`` and ``oscillator lyapunov FILE``: a declared machine's basins over
two of its state coordinates (resumable, local or on Dask) and its Lyapunov spectrum
(:mod:`oscillator.attractors.chain_attractors`, docs/systems.md)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Any

from oscillator.analysis.execution import check_workers
from oscillator.cli.console import load
from oscillator.cli.options import NO_CUTOFF
from oscillator.cli.resumable import computing, locked, new_folder, refusing, with_progress
from oscillator.cli.system import changed
from oscillator.errors import InputError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.model.chains import FrictionChain

__all__ = ["basins_system", "chain_at", "spectrum_target"]


def chain_at(target: str, assignments: list[str] | None) -> tuple[FrictionChain, str] | None:
    """The chain a system file declares, with ``--set`` applied, and the file's stem (the default
    folder's name); None where ``target`` is no system file (a case)."""
    from oscillator.io.chains import load_system, system_path

    path = system_path(target)
    if path is None:
        return None
    return changed(load_system(path), assignments or []), path.stem


def basins_system(
    target: str,
    axes: tuple[Axis, Axis],
    settings: AttractorSettings,
    run: tuple[int | None, str | None, Path | None],
    assignments: list[str] | None,
    no_plots: bool,
    quiet: bool,
) -> bool:
    """``oscillator basins FILE`` if ``target`` is a system file: the basins over the two axes
    (two of its state's names), computed into a resumable folder (``run``: ``--workers``,
    ``--scheduler``, ``--out``), its attractors printed; whether it was one."""
    workers, scheduler, out_dir = run
    with refusing():
        found = chain_at(target, assignments)
        if found is None:
            return False
        chain, stem = found
        x, y = axes
        count = check_workers(workers, starts=x.count * y.count)
        load("oscillator.attractors.chain_attractors", notice=not quiet)
        from oscillator.attractors.basins import basin_store
        from oscillator.attractors.chain_attractors import chain_grid, find_chain_basins

        if settings.engine != "dop853":
            raise InputError("--engine applies to the article's cases: a system runs on CVODE", field="--engine")
        if settings.cutoff:
            raise InputError(NO_CUTOFF, field="--cutoff")
        chain_grid(chain, x, y)
        folder = out_dir if out_dir is not None else new_folder(stem, "basins")
        store = basin_store(folder, chain, x, y, settings)
        store.check()
        lock, client = locked(folder, scheduler)
    with computing(store, "starts", lock, client):
        compute = functools.partial(find_chain_basins, chain, x, y, store, settings=settings, workers=count)
        title = printable(chain.title or stem)
        basins = with_progress(functools.partial(compute, client=client), f"{title}: basins", "starts", quiet)
    from oscillator.cli.attractors import finish_basins

    finish_basins(basins, store, no_plots, quiet)
    return True


def spectrum_target(target: str, assignments: list[str] | None) -> tuple[Any, str]:
    """``oscillator lyapunov``'s subject: a system file's chain and its title, or the case."""
    from oscillator.cli.inputs import case_from

    found = chain_at(target, assignments)
    if found is not None:
        return found[0], found[0].title or found[1]
    case = case_from(target, None, assignments)
    return case, case.name
