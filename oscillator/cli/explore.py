"""``oscillator explore``: the explorer in the browser, served on this machine (docs/explore.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from oscillator.cli.commands import command
from oscillator.cli.console import fail, load, message, say, warn
from oscillator.cli.inputs import case_from, check_engine
from oscillator.cli.options import LANDING_ENGINES, SetOption
from oscillator.errors import InputError, OscillatorError

#: ``--engine`` of the explorer: which integrator draws each change.
DrawingEngineOption = Annotated[
    str,
    typer.Option(
        "--engine",
        metavar="NAME",
        help="The integrator that draws each change: dop853 (compiled; CVODE checks each motion once the "
        "controls rest, and replaces it if an event differs) or cvode (the reference, slower to redraw).",
    ),
]


@command(
    150,
    "Explore a case or system file in the browser: move a parameter, see the motion; click a map, see its attractor.",
)
def explore(
    target: Annotated[
        str,
        typer.Argument(
            metavar="CASE|FOLDER",
            help="A named case, a case file (.toml), a system file (.toml, docs/systems.md), or a folder the atlas, "
            "basins, sweep or frc command wrote.",
        ),
    ],
    set_: SetOption = None,
    periods: Annotated[
        int, typer.Option("--periods", metavar="N", help="Forcing periods simulated on every change (1 to 10000).")
    ] = 50,
    port: Annotated[int, typer.Option("--port", metavar="PORT", help="The port to serve on (0: a free one).")] = 5006,
    address: Annotated[
        str,
        typer.Option(
            "--address",
            metavar="ADDRESS",
            help="The address to serve on: this machine only (127.0.0.1) unless another is given, with a warning.",
        ),
    ] = "127.0.0.1",
    engine: DrawingEngineOption = "dop853",
) -> None:
    """Serve the explorer of CASE, of a system file, or of an atlas, basins, sweep or frc FOLDER,
    on this machine and print its address; open it in a browser.  Every parameter and the start
    have a slider (a system file's: every number by its name, platform.F); on each change the
    motion is simulated again (drawn with the compiled DOP853, then checked by CVODE; a system
    file's with CVODE) and the time series, phase portraits, stroboscopic points and event table
    redraw.  On a folder's picture, a click on a cell or point shows the attractors there.  Ctrl-C
    stops.

    \b
    Examples:
      oscillator explore instance-3 --set Omega=2.2 --periods 20
      oscillator explore docs/systems/blade-damper.toml --set platform.F=0.5
      oscillator explore runs/atlas --port 5007
    """
    try:
        from oscillator.exploring.serving import check_address, is_loopback, serve

        check_engine(engine, LANDING_ENGINES)
        check_address(address, port)  # before the numerical libraries load
        load("oscillator.exploring.app", notice=True)
        from oscillator.exploring.app import Explorer
        from oscillator.exploring.scene import check_periods

        check_periods(periods)
        case, picture = _opened(target, set_)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted", code=130) from None
    if not is_loopback(address):
        warn(
            f"serving on {address}: anyone who can reach this machine on port {port} can open the explorer and run "
            "simulations on it; serve on 127.0.0.1 (the default) unless that is what you want"
        )

    def page() -> object:  # one explorer per browser tab, on the folder read once above
        return Explorer(case, periods, picture=picture, engine=engine).layout

    def ready(url: str) -> None:
        say(f"explorer of {target} at {url} (Ctrl-C stops it)")

    try:
        serve(page, address=address, port=port, title=f"oscillator explore {target}", ready=ready)
    except OscillatorError as error:
        raise fail(message(error)) from None
    say("stopped")


def _opened(target: str, set_: list[str] | None) -> tuple[Any, Any]:
    """The case or system to explore and the folder's map (None for a case), read once."""
    from oscillator.exploring.maps import picture_of
    from oscillator.exploring.subjects import ChainSubject
    from oscillator.io.chains import load_system, system_path

    system = system_path(target)
    if system is not None:
        from oscillator.cli.system import changed

        return ChainSubject(changed(load_system(system), set_ or []), system.stem), None
    picture = picture_of(target) if Path(target).is_dir() else None
    if picture is not None and set_:
        raise InputError("--set applies to a case, not to a folder (its map has its own values)", field="--set")
    return (picture.case if picture is not None else case_from(target, None, set_)), picture
