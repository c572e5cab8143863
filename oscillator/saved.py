"""Reading back what a command or a ``save`` wrote: :func:`read_run`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from oscillator.io.files import as_folder

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.hybrid.result import Result
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.shooting import Orbit

__all__ = ["read_run"]


def read_run(folder: str | Path) -> Result | Orbit | Branch:
    """What a folder holds, as the object that was saved.

    A folder of ``oscillator run`` or :meth:`Result.save` gives a :class:`~oscillator.Result`
    (its case, tables, status, energy audit and counts); one of :meth:`Orbit.save` an
    :class:`~oscillator.Orbit`; one of ``oscillator continue`` or :meth:`Branch.save` a
    :class:`~oscillator.Branch` (with its case).  Every file read is checked.

    Raises
    ------
    InputError
        Not such a folder, or a file in it missing or damaged (named in the message).
    """
    from oscillator.report.runs import folder_kind, read_run_folder, result_of

    folder = as_folder(folder)
    if folder_kind(folder) == "branch":
        from oscillator.report.orbit_folders import read_branch

        return read_branch(folder).branch
    run = read_run_folder(folder)
    if run.run.get("kind") == "orbit":
        from oscillator.report.orbit_folders import orbit_of_folder

        return orbit_of_folder(folder, run.case, run.events, run.run)
    return result_of(run)
