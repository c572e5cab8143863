"""``oscillator orbit`` and ``oscillator continue``: periodic orbits, their multipliers, branches.

``continue`` follows the exit codes of :mod:`oscillator.cli.app`: 0 when the branch reached the
end of the range; 1 when it ended early (the corrector failed, ``--max-points`` was reached, it
came back after a fold) or a figure could not be drawn, the branch so far kept in its folder
marked ``"incomplete"``; 130 on Ctrl-C, the branch so far kept marked ``"interrupted"``.
"""

from __future__ import annotations

import cmath
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich import box
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from oscillator.cli.commands import command
from oscillator.cli.console import err, fail, load, message, out, say
from oscillator.cli.inputs import case_from, figure_file, refuse_taken, table_file, write_figure, write_table
from oscillator.cli.options import CaseArgument, QuietOption, SetOption
from oscillator.errors import InputError, Interrupted, OscillatorError, Reason, SimulationFailed
from oscillator.io.expressions import parse_value
from oscillator.io.signals import interrupts_deferred
from oscillator.model.system import ARTICLE
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.io.cases import Case
    from oscillator.io.files import FolderClaim
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.chain_noise import ChainNoise
    from oscillator.orbits.noise import Noise
    from oscillator.orbits.shooting import Orbit

__all__ = ["continue_", "orbit", "write_spectra"]

PeriodOption = Annotated[int, typer.Option("--period", metavar="N", help="Forcing periods per return (1 to 1000).")]
GuessOption = Annotated[
    str | None,
    typer.Option("--guess", metavar="X1,V1,X2,V2", help="Start Newton from this state at the section."),
]
TransientOption = Annotated[
    int | None,
    typer.Option("--transient", metavar="N", help="Forcing periods simulated before Newton (default 100)."),
]
SensitivitiesOption = Annotated[
    str | None,
    typer.Option(
        "--sensitivities",
        metavar="NAMES",
        help="Also print the orbit's exact derivatives in these parameters (comma-separated, e.g. d1,K3,Omega).",
    ),
]
NoiseOption = Annotated[
    bool, typer.Option("--noise", help="Also print its noise measures: impacts, impulses, impact power, levels.")
]
NoiseFigureOption = Annotated[
    Path | None,
    typer.Option(
        "--noise-figure",
        metavar="FILE",
        help="Also draw its spectra (contact forces, accelerations: dB against frequency) to FILE (.png, .svg, .pdf).",
    ),
]
NoiseTableOption = Annotated[
    Path | None,
    typer.Option(
        "--noise-table",
        metavar="FILE",
        help="Also write its spectra, harmonic by harmonic, to FILE (.csv, .parquet).",
    ),
]
SectionOption = Annotated[
    float | None,
    typer.Option("--section", metavar="T", help="The section's time in s (default: the case's t0; needs --guess)."),
]
COORDINATES = ARTICLE.state


def _guess(text: str | None) -> tuple[float, ...] | None:  # four numbers
    """``--guess X1,V1,X2,V2`` as four numbers."""
    if text is None:
        return None
    parts = text.split(",")
    if len(parts) != 4:
        raise InputError(f"--guess must be four numbers X1,V1,X2,V2, got {shown(text)}", field="--guess")
    values = tuple(parse_value(part.strip(), field="--guess") for part in parts)
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        raise InputError(f"--guess must be four numbers X1,V1,X2,V2, got {shown(text)}", field="--guess")
    return tuple(float(v) for v in values)


def _code(error: OscillatorError) -> int:
    return 1 if isinstance(error, SimulationFailed) else 2


@command(80, "Find a periodic orbit and its Floquet multipliers.")
def orbit(
    case: CaseArgument,
    set_: SetOption = None,
    period: PeriodOption = 1,
    guess: GuessOption = None,
    transient: TransientOption = None,
    section: SectionOption = None,
    max_iterations: Annotated[
        int, typer.Option("--max-iterations", metavar="N", help="Newton steps before giving up (1 to 200).")
    ] = 20,
    sensitivities: SensitivitiesOption = None,
    noise: NoiseOption = False,
    noise_figure: NoiseFigureOption = None,
    noise_table: NoiseTableOption = None,
) -> None:
    """Find the periodic orbit of the stroboscopic map by Newton's method; print it, its events
    and its Floquet multipliers (and, asked, its derivatives in parameters: docs/sensitivities.md;
    its noise measures: docs/noise.md).

    \b
    A system file (docs/systems.md) takes --set by its names (platform.F=0.5) and --guess as one
    number per name of its state (x:blade,v:blade,...,z:platform); --noise gives its stops',
    contacts', masses' and friction elements' measures and its spectra.

    \b
    Examples:
      oscillator orbit instance-1
      oscillator orbit instance-1 --set Q2=70.5
      oscillator orbit instance-1 --set Q2=70.5 --transient 20 --max-iterations 40
      oscillator orbit instance-1 --set d=1 --set d1=3.5 --set Omega=1.5 --sensitivities d1,K3,Omega
      oscillator orbit instance-1 --set d=1 --set d1=3.5 --set Omega=1.6 --noise
      oscillator orbit instance-1 --set d=1 --set d1=3.5 --set Omega=1.6 --noise-figure spectra.png
      oscillator orbit instance-1 --set d=1 --set d1=3.5 --set Omega=1.6 --noise-table spectra.csv
      oscillator orbit docs/systems/blade-damper.toml --set platform.F=0.5 --transient 60
      oscillator orbit docs/systems/rattler.toml --noise --noise-figure rattler-spectra.png
    """
    from oscillator.cli.system import orbit_system

    files = _noise_files(noise_figure, noise_table)
    asked = (noise or files != (None, None), *files)
    if orbit_system(case, set_, period, guess, transient, section, max_iterations, sensitivities, asked):
        return
    try:
        resolved = case_from(case, None, set_)
        start = _guess(guess)
        names = _names(sensitivities)
        from oscillator.orbits.settings import check_orbit_settings

        check_orbit_settings(period, max_iterations=max_iterations)  # before the numerical libraries load
        load("oscillator.orbits.shooting", notice=True)
        from oscillator.orbits.shooting import find_orbit

        found = find_orbit(
            resolved,
            period=period,
            guess=start,
            transient=transient,
            section=section,
            max_iterations=max_iterations,
        )
    except OscillatorError as error:
        raise fail(message(error), code=_code(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted", code=130) from None
    _print_orbit(resolved.name, found)
    if names:
        _print_sensitivities(found, names)
    if asked[0]:
        _print_noise(found, *files)


def _print_orbit(name: str, found: Orbit) -> None:
    """The orbit found: its section point, Newton's residual, its multipliers and its events."""
    from oscillator.cli.run import _events_table

    state = ", ".join(f"{axis} = {value:.10g}" for axis, value in zip(COORDINATES, found.state, strict=True))
    out.print(Text(f"{printable(name)}: period-{found.period} orbit at t = {found.section:g} s (the section)"))
    out.print(Text(f"  {state}"))
    out.print(Text(f"  residual {found.residual:.1e} after {found.iterations} Newton step(s); {found.verdict}"))
    if found.note:
        out.print(Text(f"  note: {found.note}"))
    table = Table(title="Floquet multipliers", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for column in ("multiplier", "modulus"):
        table.add_column(column, justify="right")
    for mu in found.multipliers:
        table.add_row(_complex_text(mu), f"{abs(mu):.6e}")
    out.print(table)
    out.print(_events_table(found.events))


def _noise_files(figure: Path | None, table: Path | None) -> tuple[Path | None, Path | None]:
    """``--noise-figure``'s and ``--noise-table``'s files, checked before anything is computed."""
    if figure is not None and table is not None and figure.absolute() == table.absolute():
        raise fail("--noise-figure and --noise-table name the same file; give each its own")
    try:
        return (
            None if figure is None else figure_file(figure, "--noise-figure"),
            None if table is None else table_file(table, "--noise-table"),
        )
    except OscillatorError as error:
        raise fail(message(error)) from None


def _names(text: str | None) -> tuple[str, ...]:
    """``--sensitivities``' names, each a parameter (checked before the orbit is sought)."""
    if text is None:
        return ()
    from oscillator.model.parameters import Parameters

    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise InputError("--sensitivities needs parameter names, e.g. d1,K3,Omega", field="sensitivities")
    return tuple(Parameters.check_name(name, "sensitivities", label="--sensitivities") for name in names)


def _print_sensitivities(found: Orbit, names: tuple[str, ...]) -> None:
    """The orbit's derivatives, after the orbit itself (printed already: a refusal keeps it)."""
    try:
        derivatives = found.sensitivities(names)
    except OscillatorError as error:
        raise fail(message(error), code=_code(error)) from None
    from oscillator.orbits.monodromy_derivative import SIMPLE

    columns = [f"d/d{name}" for name in derivatives.params]  # each parameter once
    table = Table(title="Sensitivities of the section point", title_justify="left", box=box.SIMPLE_HEAD)
    table.add_column("")
    for column in columns:
        table.add_column(column, justify="right")
    for row, values in derivatives.state.iterrows():
        table.add_row(str(row), *(f"{value:+.6g}" for value in values))
    out.print(table)
    table = Table(title="Sensitivities of the response measures", title_justify="left", box=box.SIMPLE_HEAD)
    table.add_column("measure", no_wrap=True)
    for column in ("value", *columns):
        table.add_column(column, justify="right", no_wrap=True)
    for row, values in derivatives.measures.iterrows():
        table.add_row(str(row), *(f"{value:+.6g}" for value in values))
    out.print(table)
    table = Table(title="Sensitivities of the Floquet multipliers", title_justify="left", box=box.SIMPLE_HEAD)
    for column in ("multiplier", *columns):
        table.add_column(column, justify="right", no_wrap=True)
    rows = derivatives.multipliers
    for _, row in rows.iterrows():
        table.add_row(_compact(row["value"]), *(_compact(row[c]) if row["simple"] else "none" for c in columns))
    out.print(table)
    if not rows["simple"].all():
        repeated = ", ".join(f"{abs(value):.3g}" for value in rows.loc[~rows["simple"], "value"])
        out.print(
            Text(
                f"none: a repeated multiplier (moduli {repeated}: each within {SIMPLE:g} of another) has no "
                "derivative; zero ones come from the rests (a resting mass's velocity is projected to zero)"
            )
        )
    nearest = (
        f"{derivatives.margins.what[0]}, relative distance {derivatives.margin:.3g}"
        if len(derivatives.margins)
        else "none"
    )
    out.print(Text(f"nearest point without a derivative: {nearest}"))


def _print_noise(found: Orbit, figure: Path | None, spectra: Path | None) -> None:
    """The orbit's noise measures (docs/noise.md), after the orbit itself; their spectra drawn to
    ``figure`` and written to ``spectra`` if given (the tables printed first: a file that cannot be
    written loses nothing)."""
    try:
        measures = found.noise()
    except OscillatorError as error:
        raise fail(message(error), code=_code(error)) from None
    table = Table(title="Noise measures of the contacts", title_justify="left", box=box.SIMPLE_HEAD)
    headers = ("contact", "impacts/s", "impulse (N s)", "energy/impact (J)", "power (W)", "force level (dB re 1 N)")
    for k, column in enumerate(headers):
        table.add_column(column, justify="left" if k == 0 else "right", no_wrap=True)
    for name, c in measures.contacts.items():
        values = (c.rate, c.impulse, c.energy, c.power)
        table.add_row(name, *(f"{v:.6g}" for v in values), f"{c.force.level():.2f}" if c.onsets else "-")
    out.print(table)
    table = Table(title="Noise measures of the masses", title_justify="left", box=box.SIMPLE_HEAD)
    columns = ("mass", "acceleration level (dB re 1e-6 m/s^2)", "stick-slip steps", "largest step (m/s^2)")
    for k, column in enumerate(columns):
        table.add_column(column, justify="left" if k == 0 else "right", no_wrap=True)
    for i, m in measures.masses.items():
        table.add_row(f"m{i}", f"{m.acceleration.level():.2f}", str(m.slips), f"{m.step_max:.6g}")
    out.print(table)
    write_spectra(measures, figure, spectra)


def write_spectra(measures: Noise | ChainNoise, figure: Path | None, spectra: Path | None) -> None:
    """The spectra written to ``spectra`` (``--noise-table``) and drawn to ``figure``
    (``--noise-figure``) where given, after the measures are printed: a file that cannot be written
    exits 1 and loses nothing printed."""

    def table_to(path: Path) -> None:
        write_table(measures.spectra(), path)

    def figure_to(path: Path) -> None:
        write_figure(measures.plot(), path)

    files: tuple[tuple[Path | None, str, Callable[[Path], None], str], ...] = (
        (spectra, "--noise-table", table_to, "spectra written to "),
        (figure, "--noise-figure", figure_to, "spectra drawn to "),
    )
    for target, option, write, done in files:
        if target is None:
            continue
        try:
            write(target)
        except OSError as error:
            why = f"{printable(str(target))}: {printable(error.strerror or str(error))}"
            raise fail(f"{option} {why}; the measures above are complete", code=1) from None
        say(done, (str(target), "bold"))


def _complex_text(value: complex) -> str:
    """A multiplier or its derivative: ``+1.234560e-01 +0.000000e+00i``, or ``nan`` (not simple)."""
    return "nan" if cmath.isnan(value) else f"{value.real:+.6e} {value.imag:+.6e}i"


def _compact(value: complex) -> str:
    """``+0.0119323`` for a real value, ``-0.59391+0.72083i`` for a complex one, ``nan`` (not simple)."""
    if cmath.isnan(value):
        return "nan"
    return f"{value.real:+.6g}" if value.imag == 0 else f"{value.real:+.6g}{value.imag:+.6g}i"


def _progress_bar(name: str) -> tuple[Progress, Callable[[float], None]]:
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
    )
    bar = Progress(*columns, console=err, transient=True)
    task = bar.add_task(printable(name), total=1.0)
    last = [0.0]

    def report(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] > 0.1:
            last[0] = now
            bar.update(task, completed=fraction)

    return bar, report


def _continue_with_progress(
    continue_orbit: Callable[..., Branch], case: Case, settings: dict[str, Any], quiet: bool
) -> Branch:
    if quiet or not err.is_terminal:  # a progress bar only where a person watches
        return continue_orbit(case, **settings)
    bar, report = _progress_bar(case.name)
    with bar:
        return continue_orbit(case, **settings, progress=report)


@command(90, "Continue a periodic orbit in a parameter; locate its bifurcations.", name="continue")
def continue_(
    case: CaseArgument,
    param: Annotated[str, typer.Option("--param", metavar="NAME", help="The parameter to continue in.")],
    start: Annotated[float, typer.Option("--from", metavar="VALUE", help="Start of the parameter's range.")],
    stop: Annotated[float, typer.Option("--to", metavar="VALUE", help="End of the parameter's range.")],
    set_: SetOption = None,
    period: PeriodOption = 1,
    step: Annotated[
        float | None,
        typer.Option("--step", metavar="S", help="Largest step, as a fraction of the range (1e-6 to 1; default 1/40)."),
    ] = None,
    max_points: Annotated[
        int, typer.Option("--max-points", metavar="N", help="The most points computed (2 to 100000).")
    ] = 400,
    guess: GuessOption = None,
    transient: TransientOption = None,
    section: SectionOption = None,
    coordinate: Annotated[
        str | None,
        typer.Option("--coordinate", help="The coordinate at the section drawn (default x2, or x1 if m2 is parked)."),
    ] = None,
    over: Annotated[
        Path | None, typer.Option("--over", metavar="SWEEP_DIR", help="Draw the branch over this sweep's points.")
    ] = None,
    out_dir: Annotated[Path | None, typer.Option("--out", metavar="DIR", help="Output folder.")] = None,
    quiet: QuietOption = False,
) -> None:
    """Continue a periodic orbit in a parameter (pseudo-arclength, through unstable parts and
    folds); locate its sliding, grazing, fold, period-doubling and torus bifurcations.

    Writes branch.parquet, bifurcations.parquet, run.json, figures/branch.png,
    figures/multipliers.png, report.md and report.html into DIR (default
    runs/<case>-continue-<time>). Exit 1 if the branch ended before --to (the branch so far is
    kept), 130 if interrupted (likewise).

    \b
    A system file (docs/systems.md) continues its period-1 orbit by its numbers' names: branch.parquet,
    bifurcations.parquet, run.json, figures/branch.png.

    \b
    Examples:
      oscillator continue instance-1 --param Q2 --from 70.5 --to 71.5 --out runs/q2-branch
      oscillator continue docs/systems/blade-damper.toml --param Omega --from 0.6 --to 0.8
    """
    from oscillator.cli.system_branch import continue_system

    article = (period, section, coordinate, over)
    if continue_system(case, set_, (param, start, stop), (step, max_points, guess, transient), out_dir, article, quiet):
        return
    try:
        resolved, settings, sweep_points, claim = _prepare_continue(
            case,
            set_,
            coordinate,
            over,
            out_dir,
            dict(param=param, start=start, stop=stop, period=period, step=step, max_points=max_points)
            | {"guess": _guess(guess), "transient": transient, "section": section},
        )
    except OscillatorError as error:
        raise fail(message(error), code=_code(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", code=130) from None
    branch = _compute(resolved, settings, claim, quiet)
    _summary(branch, quiet)
    folder = _write(branch, resolved, claim, coordinate or branch.coordinate, sweep_points)
    problem = _finish(folder)
    if quiet:
        out.print(printable(str(folder)))
    else:
        say("written to ", (str(folder), "bold"))
    _exit(branch, folder, problem)


def _prepare_continue(
    case: str,
    set_: list[str] | None,
    coordinate: str | None,
    over: Path | None,
    out_dir: Path | None,
    settings: dict[str, Any],
) -> tuple[Case, dict[str, Any], Any, FolderClaim]:
    """Every check of ``continue`` before anything is computed, then the output folder claimed."""
    if coordinate is not None and coordinate not in COORDINATES:
        raise InputError(
            f"--coordinate must be one of {', '.join(COORDINATES)}, got {shown(coordinate)}", field="--coordinate"
        )
    param = settings["param"]
    refuse_taken(set_, {param: "--param (the continued parameter), with --from and --to"})
    resolved = case_from(case, None, set_)
    from oscillator.io.files import check_new
    from oscillator.orbits.settings import check_settings

    if out_dir is not None:
        check_new(out_dir, option="--out")  # before the numerical libraries load: a refusal is quick
    check_settings(resolved, **settings)
    load("oscillator.orbits.continuation", "oscillator.report.orbit_folders", "oscillator.report.runs", notice=True)
    from oscillator.report.orbit_folders import read_sweep_points
    from oscillator.report.runs import claim_output

    sweep_points = read_sweep_points(over, param, coordinate or "x2") if over is not None else None
    return resolved, settings, sweep_points, claim_output(out_dir, f"{resolved.name}-continue")


def _compute(case: Case, settings: dict[str, Any], claim: FolderClaim, quiet: bool) -> Branch:
    """The branch; on Ctrl-C the branch traced so far (nothing, if the first orbit was not found)."""
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.continuation import continue_orbit

    try:
        return _continue_with_progress(continue_orbit, case, settings, quiet)
    except OscillatorError as error:
        claim.abandon()
        raise fail(message(error), code=_code(error)) from None
    except KeyboardInterrupt as interrupt:  # Interrupted carries the branch so far
        partial = interrupt.result if isinstance(interrupt, Interrupted) else None
        if isinstance(partial, Branch):
            return partial
        claim.abandon()
        raise fail("interrupted before the first orbit was found; nothing was written", code=130) from None
    except BaseException:
        claim.abandon()
        raise


def _summary(branch: Branch, quiet: bool) -> None:
    """The branch in a few lines (before it is written: what is seen is never lost)."""
    if quiet:
        return
    param = branch.param
    first, last = branch.points[param].iloc[0], branch.points[param].iloc[-1]
    say(
        f"{len(branch.points)} points from {param} = {first:.10g} {'up' if last > first else 'down'} to {last:.10g}, "
        f"{len(branch.bifurcations)} bifurcation(s), named as {param} increases"
    )
    for row in branch.bifurcations.itertuples(index=False):
        gap = "  (a gap begins)" if row.after == "" else "  (a gap ends)" if row.before == "" else ""
        out.print(Text(f"  {param} = {getattr(row, param):.10g}  {row.kind}{gap}"))


def _write(branch: Branch, case: Case, claim: FolderClaim, coordinate: str, sweep_points: Any) -> Path:
    """The branch's tables, case and run.json written whole into the claimed folder."""
    from oscillator.report.orbit_folders import write_branch

    try:
        with interrupts_deferred():  # Ctrl-C waits until the tables are written whole
            return write_branch(
                branch,
                case,
                claim,
                coordinate=coordinate,
                sweep_points=sweep_points,
                command=["oscillator", *sys.argv[1:]],
            )
    except KeyboardInterrupt:  # it came while the tables were written: they are whole
        raise fail(
            f"interrupted; the branch is in {claim.target}; `oscillator report {claim.target}` makes its "
            "figures and report",
            130,
        ) from None
    except (OSError, OscillatorError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise fail(
            f"cannot write the branch to {claim.target}: {reason}; nothing was written; free the space or "
            "give another --out, and continue again",
            1,
        ) from None


def _finish(folder: Path) -> str:
    """The figures and the report; what went wrong, if anything (the tables stay either way)."""
    from oscillator.report.orbit_folders import finish_branch

    kept = f"the branch's tables are in {folder}; `oscillator report {folder}` makes its figures and report"
    try:
        load("oscillator.report.orbit_folders")
        finish_branch(folder)
    except KeyboardInterrupt:
        raise fail(f"interrupted; {kept}", 130) from None
    except Exception as error:  # a later step failed: the branch itself is safe
        return f"the figures or report could not be made ({type(error).__name__}: {error}); {kept}"
    return ""


def _exit(branch: Branch, folder: Path, problem: str) -> None:
    """Exit 130 for an interrupted branch, 1 for one that ended early or lacks its figures."""
    if branch.reason is Reason.INTERRUPTED:
        raise fail(f"{branch.message}; the branch so far is in {folder}", 130)
    if not branch.complete:
        raise fail(f"the branch ended early: {branch.message}; the branch so far is in {folder}", 1)
    if problem:
        raise fail(problem, 1)
