"""Reading back what a command or a ``save`` wrote: :func:`read_run`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from oscillator.io.files import as_folder

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.attractors.atlas import Atlas
    from oscillator.attractors.basins import Basins
    from oscillator.attractors.following import AttractorsOver
    from oscillator.attractors.frequency import FrequencyResponse
    from oscillator.attractors.lyapunov import LyapunovSpectrum
    from oscillator.designing.optimise import Design
    from oscillator.hybrid.chain_run import ChainResult
    from oscillator.hybrid.result import Result
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.curves import Curve
    from oscillator.orbits.shooting import Orbit

__all__ = ["read_run"]


def read_run(
    folder: str | Path,
) -> (
    Result
    | ChainResult
    | Orbit
    | Branch
    | Basins
    | AttractorsOver
    | Atlas
    | Curve
    | LyapunovSpectrum
    | FrequencyResponse
    | Design
):
    """What a folder holds, as the object that was saved.

    A folder of ``oscillator run`` on a system file or of :meth:`ChainResult.save` gives a
    :class:`~oscillator.ChainResult`; one of ``oscillator run`` or :meth:`Result.save` a :class:`~oscillator.Result`
    (its case, tables, status, energy audit and counts); one of :meth:`Orbit.save` an
    :class:`~oscillator.Orbit`; one of ``oscillator continue`` or :meth:`Branch.save` a
    :class:`~oscillator.Branch` (with its case); one of ``oscillator basins``, ``attractors``,
    ``atlas``, ``curve``, ``lyapunov``, ``frc`` or ``design`` (finished, or the ``save`` of their
    results) the :class:`~oscillator.Basins`, :class:`~oscillator.AttractorsOver`,
    :class:`~oscillator.Atlas`, :class:`~oscillator.Curve`, :class:`~oscillator.LyapunovSpectrum`,
    :class:`~oscillator.FrequencyResponse` or :class:`~oscillator.Design`, as computed (nothing is
    computed again: :mod:`oscillator.report.kinds`).  Every file read is checked.

    Raises
    ------
    InputError
        Not such a folder, or a file in it missing or damaged (named in the message).
    """
    from oscillator.report.kinds import folder_kind as analysis_kind
    from oscillator.report.runs import folder_kind, is_chain_folder, read_run_folder, result_of

    folder = as_folder(folder)
    if is_chain_folder(folder):  # a friction chain's run (docs/systems.md)
        from oscillator.report.chain_runs import read_chain_run

        return read_chain_run(folder)
    kind = analysis_kind(folder)
    if kind is not None:
        found: Basins | AttractorsOver | Atlas | Curve | LyapunovSpectrum | FrequencyResponse | Design
        found = kind.at("read")(folder)
        return found
    if folder_kind(folder) == "branch":
        from oscillator.report.orbit_folders import read_branch

        return read_branch(folder).branch
    run = read_run_folder(folder)
    if run.run.get("kind") == "orbit":
        from oscillator.report.orbit_folders import orbit_of_folder

        return orbit_of_folder(folder, run.case, run.events, run.run)
    return result_of(run)
