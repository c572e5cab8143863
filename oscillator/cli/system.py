"""The commands on a system file (a friction chain, docs/systems.md): ``oscillator run FILE`` and
``oscillator show FILE`` take one where they take a case (:mod:`oscillator.cli.run`,
:mod:`oscillator.cli.cases` hand it here)."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from rich import box
from rich.table import Table
from rich.text import Text

from oscillator.cli.console import fail, load, message, out, say
from oscillator.cli.inputs import figure_file, write_figure
from oscillator.cli.resumable import with_progress
from oscillator.errors import InputError, OscillatorError, SimulationFailed
from oscillator.io.files import check_new
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from oscillator.attractors.chain_frequency import ChainFrequencyResponse
    from oscillator.io.files import FolderClaim
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.chain_orbits import ChainOrbit

__all__ = ["finished", "frc_system", "guessed", "orbit_system", "run_system", "show_system"]

#: Options of ``run`` that act on the article's cases only, and what to do instead.
_CASE_ONLY = {
    "--sample": "the trajectory is kept at every step",
    "--window": "the figures show the whole run",
    "--engine": "a system runs on CVODE",
    "--keep-events-from": "every event is kept",
}


def _events_table(events) -> Table:  # type: ignore[no-untyped-def]
    table = Table(title="switching events", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for header, justify in (("t (s)", "right"), ("element", "left"), ("kind", "left"), ("rule", "left")):
        table.add_column(header, justify=justify)  # type: ignore[arg-type]
    rows = list(events.itertuples(index=False))
    shown = rows if len(rows) <= 40 else [*rows[:20], None, *rows[-20:]]
    for row in shown:
        if row is None:
            table.add_row("…", f"{len(rows) - 40} more", "", "")
        else:
            table.add_row(f"{row.t:.6f}", printable(row.element), row.kind, f"{row.theorem} {row.equations}")
    return table


def changed(chain: FrictionChain, assignments: list[str]) -> FrictionChain:
    """The chain with ``--set NAME=VALUE`` applied (``platform.F=0.5``, ``blade.m=2``, ``Omega=1.3``)."""
    from oscillator.io.expressions import parse_value

    values = {}
    for item in assignments:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--set {printable(item)}: write NAME=VALUE, e.g. --set platform.F=0.5", field="--set")
        values[name.strip()] = parse_value(text.strip(), field=f"--set {printable(name.strip())}")
    return chain.with_values(values)


def _prepare(
    path: Path,
    *,
    t_end: float | None,
    out_dir: Path | None,
    fmt: str,
    quiet: bool,
    case_only: list[str],
    assignments: list[str],
) -> tuple[FrictionChain, FolderClaim]:
    """Every check before anything is created, then the output folder claimed."""
    try:
        if fmt not in ("csv", "parquet", "both"):
            raise InputError(f"--format must be one of csv, parquet, both, got {printable(fmt)}", field="--format")
        if case_only:
            flag = case_only[0]
            raise InputError(
                f"{flag} applies to the article's cases, not to a system file: {_CASE_ONLY[flag]}", field=flag
            )
        if out_dir is not None:
            check_new(out_dir, option="--out")
        load("oscillator.hybrid.chain_run", "oscillator.report.chain_runs", notice=not quiet)
        from oscillator.hybrid.chain_run import run_end
        from oscillator.io.chains import load_system
        from oscillator.report.runs import claim_output

        chain = changed(load_system(path), assignments)
        run_end(chain, t_end)
        return chain, claim_output(out_dir, path.stem)
    except OscillatorError as error:
        raise fail(message(error)) from None


def run_system(
    path: Path,
    *,
    t_end: float | None,
    out_dir: Path | None,
    fmt: str,
    no_plots: bool,
    no_report: bool,
    quiet: bool,
    case_only: list[str],
    assignments: list[str],
) -> None:
    """``oscillator run FILE`` for a system file: simulate, write the folder, print the events."""
    chain, claim = _prepare(
        path, t_end=t_end, out_dir=out_dir, fmt=fmt, quiet=quiet, case_only=case_only, assignments=assignments
    )
    from oscillator.report.chain_runs import finish_chain_run, write_chain_run

    try:
        from oscillator.hybrid.chain_run import simulate_chain

        result = simulate_chain(chain, t_end)
        failure = None
    except SimulationFailed as error:
        result, failure = error.result, error  # type: ignore[assignment]
    except BaseException:
        claim.abandon()
        raise
    folder = write_chain_run(result, claim, formats=fmt, command=["oscillator", *sys.argv[1:]])
    if failure is not None:
        raise fail(f"{failure}\nthe partial result is in {folder}", 1)
    if not quiet:
        title = chain.title or path.stem
        say((printable(title), "bold"), f": {len(chain.masses)} masses, {len(chain.elements)} elements")
        out.print(_events_table(result.events) if len(result.events) else "no switching events")
        say(f"energy audit residual {result.energy.residual:.2e} J")
    try:
        finish_chain_run(folder, result, figures=not no_plots, report=not no_report)
    except Exception as error:  # the tables are safe
        raise fail(
            f"the figures or report could not be made ({type(error).__name__}: {error}); the tables are in {folder}", 1
        ) from None
    if quiet:
        out.print(printable(str(folder)))
    else:
        say("written to ", (str(folder), "bold"))


def show_system(path: Path, figure: Path | None) -> None:
    """``oscillator show FILE`` for a system file: its masses and elements, and its schematic."""
    try:
        from oscillator.io.chains import load_system

        chain = load_system(path)
        target = figure_file(figure if figure is not None else Path(f"{path.stem}-schematic.png"), "--figure")
    except OscillatorError as error:
        raise fail(message(error)) from None
    say(
        (printable(chain.title or path.stem), "bold"),
        f": Omega = {chain.Omega:g} rad/s, g = {chain.g:g}, t0 = {chain.t0:g} s",
    )
    masses = Table(title="masses", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for column in ("name", "m (kg)", "x (m)", "v (m/s)"):
        masses.add_column(column)
    for m in chain.masses:
        masses.add_row(printable(m.name), f"{m.m:g}", f"{m.x:g}", f"{m.v:g}")
    out.print(masses)
    elements = Table(title="elements", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for column in ("name", "type", "on", "with", "values"):
        elements.add_column(column)
    for e in chain.elements:
        values = ", ".join(
            f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {printable(str(v))}"
            for k, v in e.values.items()
            if v is not None
        )
        elements.add_row(printable(e.name), e.type, printable(e.on), printable(e.with_ or "ground"), values)
    out.print(elements)
    from oscillator.report.chain_figures import schematic_figure

    write_figure(schematic_figure(chain), target)
    say("schematic written to ", (str(target), "bold"))


def guessed(text: str | None, names: tuple[str, ...]) -> list[float] | None:
    """``--guess`` as one number per name of the system's state."""
    from oscillator.io.expressions import parse_value

    if text is None:
        return None
    parts = [part.strip() for part in text.split(",")]
    values = [parse_value(part, field="--guess") for part in parts] if len(parts) == len(names) else []
    if not values or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        raise InputError(
            f"--guess must be {len(names)} numbers, one for each of {', '.join(names)}, got {printable(text)}",
            field="--guess",
        )
    return [float(v) for v in values]


def orbit_system(
    target: str,
    assignments: list[str] | None,
    period: int,
    guess: str | None,
    transient: int | None,
    section: float | None,
    max_iterations: int,
    sensitivities: str | None,
    noise: tuple[bool, Path | None, Path | None] = (False, None, None),
) -> bool:
    """``oscillator orbit FILE`` if ``target`` is a system file: the chain's periodic orbit
    (:func:`~oscillator.orbits.chain_orbits.find_chain_orbit`), its multipliers and events, and
    where ``noise`` asks (whether to, the figure's and the table's files) its noise measures and
    spectra; whether it was one."""
    from oscillator.io.chains import load_system, system_path

    path = system_path(target)
    if path is None:
        return False
    try:
        from oscillator.orbits.chain_orbits import find_chain_orbit
        from oscillator.orbits.chain_tangents import check_names

        chain = changed(load_system(path), assignments or [])
        names = check_names(chain, [n.strip() for n in (sensitivities or "").split(",") if n.strip()])
        if sensitivities is not None and not names:
            raise InputError("--sensitivities needs names of the system's numbers, e.g. platform.F,Omega")
        start = guessed(guess, chain.system.state)
        found = find_chain_orbit(
            chain,
            None if start is None else np.asarray(start),
            period=period,
            section=section,
            transient=100 if transient is None else transient,
            max_iterations=max_iterations,
        )
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    except KeyboardInterrupt:
        raise fail("interrupted", code=130) from None
    title = printable(chain.title or path.stem)
    out.print(Text(f"{title}: period-{found.period} orbit at t = {found.section:g} s (the section)"))
    state = ", ".join(f"{printable(n)} = {v:.10g}" for n, v in zip(chain.system.state, found.state, strict=True))
    out.print(Text(f"  {state}"))
    out.print(Text(f"  residual {found.residual:.1e} after {found.iterations} Newton step(s); {found.verdict}"))
    table = Table(title="Floquet multipliers", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for column in ("multiplier", "modulus"):
        table.add_column(column, justify="right")
    for mu in found.multipliers:
        table.add_row(f"{mu.real:+.6e} {mu.imag:+.6e}i", f"{abs(mu):.6e}")
    out.print(table)
    if found.events.empty:
        out.print(Text("no switching event over the period (every element keeps its mode)"))
    else:
        out.print(_events_table(found.events))
    if names:
        _print_sensitivities(found, names)
    if noise[0]:
        _print_noise(found, noise[1], noise[2])
    return True


def _print_noise(found: ChainOrbit, figure: Path | None, spectra: Path | None) -> None:
    """The orbit's noise measures and levels (docs/noise.md), after the orbit; its spectra drawn
    and written where asked (:func:`~oscillator.cli.orbit.write_spectra`)."""
    from oscillator.cli.orbit import write_spectra

    try:
        measured = found.noise()
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    kinds = ("impact_rate", "impact_velocity", "impulse", "impact_energy", "impact_power")
    headers = ("closings /s", "fastest (m/s)", "impulse (N s)", "energy per closing (J)", "power (W)")
    rows = [
        (name, *(f"{measured.measures[f'{kind}:{name}']:.4g}" for kind in kinds), f"{spectrum.level():.2f}")
        for name, spectrum in measured.forces.items()
    ]
    _print_rows("Noise measures of the stops and contacts", ("element", *headers, "force level (dB re 1 N)"), rows)
    rows = [(name, f"{spectrum.level():.2f}") for name, spectrum in measured.accelerations.items()]
    _print_rows("Noise measures of the masses", ("mass", "acceleration level (dB re 1e-6 m/s^2)"), rows)
    sliding = [e.name for e in found.chain.elements if e.type == "friction"]
    rows = [
        (name, f"{measured.measures[f'slip_steps:{name}']:.0f}", f"{measured.measures[f'slip_step_max:{name}']:.6g}")
        for name in sliding
    ]
    if rows:
        _print_rows("Stick-slip of the friction elements", ("element", "steps", "largest step (m/s^2)"), rows)
    write_spectra(measured, figure, spectra)


def _print_rows(title: str, headers: tuple[str, ...], rows: list[tuple[str, ...]]) -> None:
    """A table of ``rows`` under ``headers``, the first column (a name from the file) printable."""
    table = Table(title=title, title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    shown = [(printable(name), *values) for name, *values in rows]
    for k, header in enumerate(headers):  # a header wraps; a value is never cut
        widest = max((len(row[k]) for row in shown), default=0)
        table.add_column(header, justify="left" if k == 0 else "right", overflow="fold", min_width=widest)
    for row in shown:
        table.add_row(*row)
    out.print(table)


def _print_sensitivities(found: ChainOrbit, names: tuple[str, ...]) -> None:
    """The orbit's derivatives in ``names``, after the orbit (printed already: a refusal keeps it)."""
    try:
        derivatives = found.sensitivities(names)
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    for title, frame in (
        ("Sensitivities of the section point", derivatives.state),
        ("Sensitivities of the measures", derivatives.measures),
    ):
        table = Table(title=title, title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
        table.add_column("")
        for column in frame.columns:
            table.add_column(printable(str(column)), justify="right", no_wrap=True)
        for row, values in frame.iterrows():
            table.add_row(printable(str(row)), *(f"{value:+.6g}" for value in values))
        out.print(table)


def frc_system(
    target: str,
    assignments: list[str] | None,
    param: tuple[str, float, float],
    counts: tuple[int, int | None, int],
    transient: int | None,
    out_dir: Path | None,
    case_only: list[str],
    plots: bool,
    quiet: bool,
    noise: bool = False,
) -> bool:
    """``oscillator frc FILE`` if ``target`` is a system file: the chain's period-1 orbit swept up
    and down ``param``'s span over ``sweep`` values (:func:`~oscillator.orbits.chain_response.
    frequency_sweep`), and with ``seeds`` every branch (``counts = (sweep, seeds, starts)``:
    :func:`~oscillator.attractors.chain_frequency.chain_frequency_response`), with ``noise`` every
    orbit's levels and spectra (:func:`~oscillator.orbits.chain_noise.sweep_noise`), the folder
    written (:mod:`oscillator.report.chain_frequency`), the jumps and the failed values said;
    whether it was one."""
    from oscillator.io.chains import load_system, system_path

    path = system_path(target)
    if path is None:
        return False
    name, low, high = param
    sweep, seeds, starts = counts
    try:
        if case_only:
            raise InputError(
                f"{case_only[0]} applies to the article's cases; a system file's frequency response is a sweep up "
                "and down (--sweep N values) and, with --seeds N, its period-1 branches",
                field=case_only[0],
            )
        if seeds is None and starts != 1:
            raise InputError("--starts goes with --seeds N: the starts at each seed value", field="--starts")
        if not (2 <= sweep <= 100_000) or not low < high:
            raise InputError(f"--sweep must be 2 to 100000 values over LOW < HIGH, got {sweep} over {low:g}..{high:g}")
        if out_dir is not None:
            check_new(out_dir, option="--out")
        load("oscillator.orbits.chain_response", notice=not quiet)
        from oscillator.report.runs import claim_output

        chain = changed(load_system(path), assignments or [])
        chain.with_values({name: low}).with_values({name: high})  # both ends checked, the field named
        claim = claim_output(out_dir, f"{path.stem}-frc")
    except OscillatorError as error:
        raise fail(message(error)) from None
    try:
        periods = 100 if transient is None else transient
        label = f"{printable(chain.title or path.stem)}: sweeps over {printable(name)}"
        compute = functools.partial(_swept, chain, (name, low, high), (sweep, seeds, starts), periods)
        table, response = with_progress(compute, label, "orbits", quiet)
    except BaseException:
        claim.abandon()
        raise
    from oscillator.report.chain_frequency import finish_chain_sweeps, write_chain_sweeps

    heard, interrupted = _sweep_noise(table, chain, name, quiet) if noise else (None, False)
    command = ["oscillator", *sys.argv[1:]]
    folder = write_chain_sweeps(table, chain, name, claim, command=command, response=response, noise=heard)
    _said_sweeps(table, chain, name, quiet)
    _said_branches(response, quiet)
    spectra = None if heard is None else heard[1]
    finished(folder, (lambda: finish_chain_sweeps(folder, table, chain, name, response, spectra)) if plots else None)
    if interrupted:
        raise fail(f"interrupted while measuring the noise; the sweeps are in {printable(str(folder))}", 130)
    return True


def _sweep_noise(
    table: pd.DataFrame, chain: FrictionChain, name: str, quiet: bool
) -> tuple[tuple[pd.DataFrame, pd.DataFrame] | None, bool]:
    """Every orbit's levels and spectra (``--noise``), and whether Ctrl-C stopped it (the sweeps
    are written all the same)."""
    from oscillator.orbits.chain_noise import sweep_noise

    label = f"{printable(chain.title or 'the system')}: noise of the sweeps' orbits"
    try:
        return with_progress(functools.partial(sweep_noise, table, chain, name), label, "orbits", quiet), False
    except KeyboardInterrupt:
        return None, True
    except OscillatorError as error:
        raise fail(message(error), code=1) from None


def _swept(
    chain: FrictionChain,
    span: tuple[str, float, float],
    counts: tuple[int, int | None, int],
    periods: int,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[pd.DataFrame, ChainFrequencyResponse | None]:
    """The sweeps' table, and with seeds the response with its branches (None without)."""
    name, low, high = span
    sweep, seeds, starts = counts
    if seeds is None:
        import pandas as pd

        up, down = _both_ways(chain, np.linspace(low, high, sweep), name, periods, progress)
        return pd.concat([up, down], ignore_index=True), None
    from oscillator.attractors.atlas import fresh_starts
    from oscillator.attractors.chain_frequency import chain_frequency_response
    from oscillator.model.parameters import check_count

    states = fresh_starts(chain, check_count(starts, "--starts", 1, 1000))
    options = {"seeds": seeds, "states": states, "sweep": sweep, "transient": periods, "progress": progress}
    response = chain_frequency_response(chain, name, (low, high), **options)  # type: ignore[arg-type]
    return response.sweeps, response


def _said_branches(response: ChainFrequencyResponse | None, quiet: bool) -> None:
    """How many branches, and each fold and change of stability."""
    if quiet or response is None:
        return
    out.print(Text(f"  {len(response.branches)} branch(es) of period-1 orbits"))
    for row in response.bifurcations().itertuples(index=False):
        out.print(Text(f"  branch {row[0]}: {row[1]} at {printable(response.param)} = {row[2]:.8g}"))
    for why in response.skipped:
        out.print(Text(f"  no branch from {printable(why)}"))


def finished(folder: Path, draw: Callable[[], None] | None) -> None:
    """The figures drawn into a folder whose tables are written (``draw``, unless None), then the
    folder said; a figure that cannot be drawn fails the command (exit 1) naming the folder that
    keeps the tables."""
    if draw is not None:
        try:
            draw()
        except Exception as error:  # the tables are safe
            raise fail(
                f"the figure could not be drawn ({type(error).__name__}: {error}); the tables are in {folder}", 1
            ) from None
    say("written to ", (printable(str(folder)), "bold"))


def _both_ways(
    chain: FrictionChain,
    values: np.ndarray,
    name: str,
    periods: int,
    progress: Callable[[int, int], None] | None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The sweep up and the sweep down, ``progress(done, total)`` told over both."""
    from oscillator.orbits.chain_response import frequency_sweep

    total = 2 * len(values)

    def told(offset: int) -> Callable[[int, int], None] | None:
        return None if progress is None else (lambda done, _: progress(offset + done, total))

    up = frequency_sweep(chain, values, param=name, transient=periods, progress=told(0))
    down = frequency_sweep(chain, values[::-1], param=name, transient=periods, progress=told(len(values)))
    return up.assign(direction="up"), down.assign(direction="down")


def _said_sweeps(table: pd.DataFrame, chain: FrictionChain, name: str, quiet: bool) -> None:
    """Each sweep's largest displacement of each mass and where it jumps; the values with no orbit."""
    if quiet:
        return
    for direction, rows in table.groupby("direction", sort=False):
        found = rows[rows.status != "failed"]
        for mass in chain.system.masses:
            if len(found):
                worst = found.loc[found[f"x_max:{mass}"].idxmax()]
                largest = f"{worst[f'x_max:{mass}']:.6g} m at {name} = {worst[name]:.6g}"
                out.print(Text(f"  sweep {direction}: largest x_max of {printable(str(mass))} {largest}"))
        failed = ", ".join(f"{v:.6g}" for v in rows[rows.status == "failed"][name])
        if failed:
            out.print(Text(f"  sweep {direction}: no orbit found at {name} = {failed}"))


def check_system(path: Path) -> None:
    """``oscillator check FILE`` for a system file: its run's events against its ``[[expected]]``
    ones (the nearest event of the element and kind); exit 1 if one is out of tolerance."""
    try:
        from oscillator.io.chains import expected_events

        chain, expected = expected_events(path)
        if not expected:
            raise InputError(
                f"{printable(str(path))} has no [[expected]] events to check against; add some (docs/systems.md)",
                field="case",
            )
        load("oscillator.hybrid.chain_run", notice=True)
        from oscillator.hybrid.chain_run import run_end, simulate_chain

        end = run_end(chain, None)
        late = [e for e in expected if e.t > end]
        if late:
            raise InputError(
                f"expected event {late[0].label!r} at t = {late[0].t:g} s is after the run's end {end:g} s; "
                "set [run] t_end",
                field="t",
            )
        events = simulate_chain(chain).events
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    table = Table(
        title=f"{printable(chain.title or path.stem)}: expected events (s)", title_justify="left", header_style="bold"
    )
    for column in ("event", "element", "kind", "expected", "run", "difference", ""):
        table.add_column(column)
    failed = 0
    for e in expected:
        same = events[(events.element == e.element) & (events.kind == e.kind)]
        if same.empty:
            ran, verdict = None, False
        else:
            ran = float(same.t.iloc[(same.t - e.t).abs().argmin()])
            verdict = abs(ran - e.t) <= e.tolerance
        failed += not verdict
        shown_run = "none" if ran is None else f"{ran:.6f}"
        difference = "" if ran is None else f"{ran - e.t:+.2e}"
        table.add_row(
            e.label, printable(e.element), e.kind, f"{e.t:g}", shown_run, difference, "ok" if verdict else "OUT"
        )
    out.print(table)
    if failed:
        raise fail(f"{failed} expected event(s) out of tolerance", 1)
    say(f"all {len(expected)} expected events within tolerance")
