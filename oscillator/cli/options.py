"""The command line's shared options, declared once: every command that takes one takes it with
the same flag, metavar and help (and its default from the library's settings where it has one)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

__all__ = [
    "LANDING_ENGINES",
    "AxisOption",
    "CaseArgument",
    "EngineOption",
    "FullTransientOption",
    "LandingEngineOption",
    "NoPlotsOption",
    "QuietOption",
    "RecordOption",
    "ResumableOutOption",
    "SchedulerOption",
    "SetOption",
    "TransientOption",
    "WorkersOption",
]

#: ``CASE``: a named case or a case file.
CaseArgument = Annotated[
    str, typer.Argument(metavar="CASE", help="A named case (oscillator list) or a case file (.toml).")
]
#: ``--set NAME=VALUE``: an override of the case.
SetOption = Annotated[
    list[str] | None,
    typer.Option(
        "--set", metavar="NAME=VALUE", help="Override a parameter, initial value or solver option (repeatable)."
    ),
]
#: ``--quiet``: only the output folder printed.
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder (for scripts).")]
#: ``--no-plots``: the tables and report without figures.
NoPlotsOption = Annotated[bool, typer.Option("--no-plots", help="Skip the figures.")]
#: ``--transient`` and ``--record`` of the global analyses (their defaults: the command's settings).
TransientOption = Annotated[
    int | None, typer.Option("--transient", metavar="N", help="Forcing periods run before recording.")
]
RecordOption = Annotated[int | None, typer.Option("--record", metavar="N", help="Forcing periods recorded after it.")]
#: ``--full-transient``: every start runs the whole transient, settled or not.
FullTransientOption = Annotated[
    bool,
    typer.Option(
        "--full-transient",
        help="Run the whole --transient before recording, even where the motion has settled sooner.",
    ),
]
#: ``--cutoff``: the cut-off of the response measures ``force_above`` and ``a_above`` (docs/noise.md).
CutoffOption = Annotated[
    float | None,
    typer.Option(
        "--cutoff",
        metavar="HZ",
        help="The measures force_above and a_above: the RMS of the harmonics above HZ (0: all but the mean).",
    ),
]
#: Why a system file refuses ``--cutoff``.
NO_CUTOFF = "--cutoff applies to the article's cases' force_above and a_above"
#: ``--workers`` and ``--scheduler``: where the many runs run.
WorkersOption = Annotated[
    int | None,
    typer.Option(
        "--workers",
        metavar="N",
        help="Local processes (default: every core; a computation of fewer than 1,000 landings: this process).",
    ),
]
SchedulerOption = Annotated[
    str | None,
    typer.Option("--scheduler", metavar="ADDRESS", help="Run on a Dask cluster: tcp://HOST:PORT of its scheduler."),
]
#: ``--engine``: which integrator runs the case (:mod:`oscillator.engines`).
EngineOption = Annotated[
    str | None,
    typer.Option(
        "--engine",
        metavar="NAME",
        help="The integrator: cvode (CVODE through its C API, the default), sksundae (CVODE through "
        "scikit-sundae's Python API), dop853 (DOP853 with CVODE's root search, compiled) or scipy "
        "(SciPy's solve_ivp).",
    ),
]
#: ``--engine`` of the many-start analyses: which integrator lands the starts.
#: The engines ``--engine`` of the many-start analyses and of the explorer names.
LANDING_ENGINES = ("dop853", "cvode")
LandingEngineOption = Annotated[
    str,
    typer.Option(
        "--engine",
        metavar="NAME",
        help="The integrator of the starts: dop853 (each start run whole in compiled code, the default) or "
        "cvode (the reference, through simulate).",
    ),
]
#: ``--out DIR`` of a resumable command: the folder, new or the same computation's to resume.
ResumableOutOption = Annotated[
    Path | None,
    typer.Option(
        "--out",
        metavar="DIR",
        help="Output folder (default: runs/CASE-COMMAND-YYYYmmdd-HHMMSS); the same folder again resumes.",
    ),
]
#: ``--x NAME LOW HIGH N``: an axis of a grid.
AxisOption = tuple[str, float, float, int]
