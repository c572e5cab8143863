"""``oscillator calibrate``: parameters fitted to measured motion (docs/calibration.md)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.text import Text

from oscillator.cli.commands import command
from oscillator.cli.console import fail, load, out, say
from oscillator.cli.design import parse_ranges
from oscillator.cli.options import CaseArgument, NoPlotsOption, QuietOption, ResumableOutOption, SetOption
from oscillator.cli.resumable import computing, locked, new_folder, outputs, refusing, say_reused, with_progress
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.io.cases import Case
    from oscillator.model.chains import FrictionChain

__all__ = ["calibrate"]

VaryOption = Annotated[
    list[str],
    typer.Option("--vary", metavar="NAME=LOW,HIGH", help="A parameter fitted, within its range (repeat it)."),
]
DataArgument = Annotated[
    Path,
    typer.Argument(
        metavar="DATA",
        help="A CSV file of measurements: Omega,measure,value[,sigma] (steady responses), t,variable,value[,sigma] "
        "(a time series) or kind,t[,mass or element,sigma] (event times).",
    ),
]


def _model(case: str, assignments: list[str] | None) -> Case | FrictionChain:
    """The article's case or a declared machine (a system file), with ``--set`` applied."""
    from oscillator.io.chains import load_system, system_path

    path = system_path(case)
    if path is None:
        from oscillator.cli.inputs import case_from

        return case_from(case, None, assignments)
    from oscillator.cli.system import changed

    return changed(load_system(path), assignments or [])


def _name(model: Any, case: str) -> str:
    return Path(case).stem if case.lower().endswith(".toml") else str(getattr(model, "name", case))


@command(128, "Calibrate: fit parameters to measured responses, a time series or event times.")
def calibrate(
    case: CaseArgument,
    data: DataArgument,
    vary: VaryOption,
    over: Annotated[
        str, typer.Option("--over", metavar="NAME", help="The parameter steady responses were measured at.")
    ] = "Omega",
    starts: Annotated[
        int, typer.Option("--starts", metavar="N", help="Fits from the model's values and N - 1 more.")
    ] = 1,
    loss: Annotated[
        str, typer.Option("--loss", help="linear (least squares), or soft_l1, huber, cauchy, arctan for outliers.")
    ] = "linear",
    f_scale: Annotated[
        float,
        typer.Option("--f-scale", metavar="R", help="The residual (in sigma) beyond which a robust loss discounts."),
    ] = 1.0,
    level: Annotated[float, typer.Option("--level", metavar="P", help="The confidence intervals' level.")] = 0.95,
    set_: SetOption = None,
    out_dir: ResumableOutOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """Fit parameters of a case or a system file to measurements: steady responses at several
    values of --over, a time series or event times (docs/calibration.md). Prints the estimate with
    its standard errors and intervals and what the data cannot determine; writes estimate.csv,
    residuals.csv, calibration.json, fitted.toml (the model at the estimate), the figure of the
    data against the fitted model and a report. Each start's fit is kept as it ends: the same
    command with the same --out resumes.

    \b
    Examples:
      oscillator calibrate docs/systems/rattler.toml docs/measured/rattler-response.csv --vary floor.mu_k=0.02,0.14 \
        --vary floor.mu_s=0.14,0.4 --vary stop.K=10,200 --set floor.mu_k=0.08 --set floor.mu_s=0.2 --set stop.K=30
    """
    with refusing():
        ranges = parse_ranges(vary)
        model = _model(case, set_)
        from oscillator.io.measurements import read_measurements

        table = read_measurements(data)
        load("oscillator.calibrating.fit", "oscillator.calibrating.store", notice=not quiet)
        from oscillator.calibrating.store import calibration_store

        options: dict[str, Any] = {"over": over, "starts": starts, "loss": loss, "f_scale": f_scale}
        folder = out_dir if out_dir is not None else new_folder(_name(model, case), "calibration")
        store = calibration_store(folder, model, table, ranges, **options)
        store.check()
        lock, client = locked(store.folder, None)
    with computing(store, "starts", lock, client):
        from oscillator.calibrating.fit import calibrate as fit

        run = functools.partial(fit, model, table, ranges, level=level, store=store, **options)
        found = with_progress(run, f"{_name(model, case)}: calibration", "starts", quiet)
        from oscillator.report.calibration import summary

        store.write_status("computed", **summary(found))
    say_reused(store, store.reused, "starts", quiet)
    _finish(found, store.folder, not no_plots, quiet)


def _finish(found: Any, folder: Path, plots: bool, quiet: bool) -> None:
    """The folder's outputs written (the model at the estimate, the tables, the figure, the
    report), each file whole."""
    from oscillator.io.cases import Case, case_to_toml
    from oscillator.io.chains import chain_to_toml
    from oscillator.io.files import atomic_path
    from oscillator.report.calibration import write_calibration

    def write() -> list[str]:
        fitted = found.fitted
        with atomic_path(folder / "fitted.toml") as temporary:  # the model at the estimate
            temporary.write_text(case_to_toml(fitted) if isinstance(fitted, Case) else chain_to_toml(fitted), "utf-8")
        return write_calibration(found, folder, plots=plots)

    problems = outputs(folder, "starts", write)
    if not quiet:
        for line in str(found).splitlines():
            out.print(Text(line))
    say("written to ", (printable(str(folder)), "bold"))
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {printable(str(folder))}", 1)
