"""Every kind of result an analysis returns, in one registry (:data:`KINDS`): its name, its type,
the marker file its folder holds, and how it is written into a folder, read back, drawn, shown
in Jupyter and how its report is rebuilt.

Every reader goes through it, so that a new kind of result is one entry here: the results'
``save``, ``plot`` and ``_repr_html_`` (:mod:`oscillator.views`), :func:`oscillator.read_run`,
``oscillator report`` and the explorer's maps.  A command's folder and a ``save``'s are the same
folder: the marker names the kind, and ``read`` reads either, computing nothing.  (A run, an
orbit and a branch keep their ``run.json``: :mod:`oscillator.report.runs` reads them.)
"""

from __future__ import annotations

import dataclasses
import importlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from oscillator.errors import InputError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.attractors.atlas import Atlas
    from oscillator.attractors.basins import Basins
    from oscillator.attractors.following import AttractorsOver
    from oscillator.attractors.frequency import FrequencyResponse
    from oscillator.attractors.lyapunov import LyapunovSpectrum
    from oscillator.designing.optimise import Design
    from oscillator.report import markup as mk

__all__ = ["KINDS", "Kind", "folder_kind", "html", "kind_of", "save"]


@dataclasses.dataclass(frozen=True)
class Kind:
    """One kind of result.  Its type and functions are named ``"module:name"`` and imported when
    first used (:meth:`at`), so that finding a folder's kind imports nothing heavy.

    ``write(found, folder)`` writes the result into an empty folder as its command writes it
    (marker, ``case.toml``, tables, figures, report) and returns what could not be drawn;
    ``read(folder)`` reads a command's or a ``save``'s folder back; ``figure(found, **options)``
    is its ``plot``; ``blocks(found)`` its report's text (:mod:`oscillator.report.markup`);
    ``rebuild(folder)`` writes its tables, figures and report again from what the folder keeps
    (``oscillator report``) and returns what could not be drawn; where such a folder is not
    rebuilt, ``refusal`` says why and what to do instead."""

    name: str
    type: str
    marker: str
    what: str
    write: str
    read: str
    figure: str
    blocks: str
    rebuild: str = ""
    refusal: str = ""

    def at(self, role: str) -> Any:
        """The object named for ``role`` (``"type"``, ``"write"``, ``"read"``, ...)."""
        module, name = getattr(self, role).split(":")
        return getattr(importlib.import_module(module), name)


_HERE = __name__


def _marker(folder: Path, marker: str, known: dict[str, Any], name: str, layout: int | None = None) -> None:
    """A saved folder's marker (the identity, status ``saved``, the format of the parts its
    command keeps: the attractors' store's by default) and ``case.toml`` (a declared system's
    ``system.toml``)."""
    from oscillator.attractors.store import FORMAT
    from oscillator.io.files import atomic_path

    layout = FORMAT if layout is None else layout
    kept = {"identity": known, "format": layout, "case_name": name}
    text = json.dumps(kept | {"status": "saved"}, indent=2, default=str)
    source = ("system.toml", known["system"]) if "system" in known else ("case.toml", known["case"])
    for file, content in ((marker, text), (source[0], str(source[1]))):
        with atomic_path(folder / file) as temporary:
            temporary.write_text(content, encoding="utf-8")


def _write_basins(found: Basins, folder: Path) -> list[str]:
    from oscillator.analysis.store import identity
    from oscillator.report.attractors import write_basins

    known = identity(found.found.case, x=found.x, y=found.y, settings=found.found.settings)
    _marker(folder, "basins.json", known, found.found.case.name)
    return write_basins(found, folder)


def _write_following(found: AttractorsOver, folder: Path) -> list[str]:
    from oscillator.analysis.store import identity
    from oscillator.attractors.following import default_coordinate
    from oscillator.report.attractors import name_of, write_following

    fresh = found.found[0].labels[list(found.case.system.state)].to_numpy()[: found.fresh]
    settings = found.found[0].settings
    known = identity(found.case, param=found.param, values=found.values, states=fresh, settings=settings)
    _marker(folder, "attractors.json", known, name_of(found.case))
    return write_following(found, folder, coordinate=default_coordinate(found.case), branches=[])


def _write_atlas(found: Atlas, folder: Path) -> list[str]:
    from oscillator.analysis.store import identity
    from oscillator.report.attractors import name_of
    from oscillator.report.plane import write_atlas

    _marker(folder, "atlas.json", identity(found.case, x=found.x, y=found.y, cutoff=found.cutoff), name_of(found.case))
    return write_atlas(found, folder)


def _write_frequency(found: FrequencyResponse, folder: Path) -> list[str]:
    from oscillator.analysis.store import identity
    from oscillator.attractors.frequency_parts import FrequencyStore
    from oscillator.report.frequency import write_frequency

    values = found.sweeps[found.param].to_numpy(float)  # the sweeps run from one end of the span to the other
    span = [float(values.min()), float(values.max())]
    known = identity(found.case, param=found.param, span=span, period=found.period)
    _marker(folder, "frc.json", known, found.case.name, FrequencyStore.FORMAT)
    return write_frequency(found, folder)


def _write_design(found: Design, folder: Path) -> list[str]:
    from oscillator.designing.optimise import DesignStore, design_store
    from oscillator.report.design import write_design

    known = design_store(folder, found.problem, found.settings, len(found.candidates)).identity
    _marker(folder, "design.json", known, found.problem.case.name, DesignStore.FORMAT)
    return write_design(found, folder)


def _read_frequency(folder: Path) -> FrequencyResponse:
    from oscillator.report.frequency import read_frequency

    return read_frequency(folder)[0]


def _rebuild_frequency(folder: Path) -> list[str]:
    from oscillator.report.frequency import read_frequency, write_frequency

    found, measure = read_frequency(folder)
    return write_frequency(found, folder, measure)


def _rebuild_curve(folder: Path) -> list[str]:
    from oscillator.report.plane import read_curve, write_curve

    return write_curve(read_curve(folder), folder)


def _rebuild_design(folder: Path) -> list[str]:
    from oscillator.report.design import read_design, write_design

    return write_design(read_design(folder), folder)


def _basins_blocks(found: Basins) -> list[mk.Block]:
    from oscillator.report.attractors import attractor_table, basins_blocks

    return basins_blocks(found, attractor_table(found))


def _following_blocks(found: AttractorsOver) -> list[mk.Block]:
    from oscillator.report.attractors import following_blocks

    return following_blocks(found, found.table())


def _frequency_blocks(found: FrequencyResponse) -> list[mk.Block]:
    from oscillator.report.frequency import frequency_blocks

    return frequency_blocks(found, [])


def _design_blocks(found: Design) -> list[mk.Block]:
    from oscillator.report.design import design_blocks

    return design_blocks(found, plots=False)


def _lyapunov_blocks(spectrum: LyapunovSpectrum) -> list[mk.Block]:
    from oscillator.report import markup as mk

    rows = tuple((f"lambda{k}", f"{value:.6g}") for k, value in enumerate(spectrum.exponents, start=1))
    title = f"Lyapunov spectrum over {spectrum.periods} forcing periods (1/s)"
    return [mk.Paragraph((mk.Span(title, "strong"),)), mk.Table(("exponent", "value"), rows)]


_ATTRACTORS, _PLANE, _RESULTS = (
    "oscillator.report.attractors",
    "oscillator.report.plane",
    "oscillator.report.global_results",
)

#: Every kind of result.
KINDS: tuple[Kind, ...] = (
    Kind(
        "basins",
        "oscillator.attractors.basins:Basins",
        "basins.json",
        "the basins",
        f"{_HERE}:_write_basins",
        f"{_RESULTS}:read_basins",
        f"{_ATTRACTORS}:basins_figure",
        f"{_HERE}:_basins_blocks",
        rebuild="oscillator.report.rebuilding:rebuild_basins",
    ),
    Kind(
        "attractors",
        "oscillator.attractors.following:AttractorsOver",
        "attractors.json",
        "the attractors over a parameter",
        f"{_HERE}:_write_following",
        f"{_RESULTS}:read_following",
        f"{_ATTRACTORS}:following_figure",
        f"{_HERE}:_following_blocks",
        refusal="an attractors folder is rebuilt by running the command that made it again with the same --out: it "
        "reads its landings back and computes none",
    ),
    Kind(
        "atlas",
        "oscillator.attractors.atlas:Atlas",
        "atlas.json",
        "the atlas",
        f"{_HERE}:_write_atlas",
        f"{_PLANE}:read_atlas",
        f"{_PLANE}:atlas_figure",
        f"{_PLANE}:atlas_blocks",
        rebuild="oscillator.report.rebuilding:rebuild_atlas",
    ),
    Kind(
        "curve",
        "oscillator.orbits.curves:Curve",
        "curve.json",
        "the curve (drawn without an atlas)",
        f"{_PLANE}:write_curve",
        f"{_PLANE}:read_curve",
        f"{_PLANE}:curve_figure",
        f"{_PLANE}:curve_blocks",
        rebuild=f"{_HERE}:_rebuild_curve",
    ),
    Kind(
        "lyapunov",
        "oscillator.attractors.lyapunov:LyapunovSpectrum",
        "lyapunov.json",
        "the Lyapunov spectrum",
        f"{_ATTRACTORS}:write_lyapunov",
        f"{_RESULTS}:read_lyapunov",
        f"{_ATTRACTORS}:lyapunov_figure",
        f"{_HERE}:_lyapunov_blocks",
        refusal="a Lyapunov folder keeps no state to redraw from; run the same lyapunov command with a new --out (it "
        "takes seconds)",
    ),
    Kind(
        "frc",
        "oscillator.attractors.frequency:FrequencyResponse",
        "frc.json",
        "the frequency response",
        f"{_HERE}:_write_frequency",
        f"{_HERE}:_read_frequency",
        "oscillator.report.frequency:frequency_figure",
        f"{_HERE}:_frequency_blocks",
        rebuild=f"{_HERE}:_rebuild_frequency",
    ),
    Kind(
        "design",
        "oscillator.designing.optimise:Design",
        "design.json",
        "the design",
        f"{_HERE}:_write_design",
        "oscillator.report.design:read_design",
        "oscillator.report.design:design_plot",
        f"{_HERE}:_design_blocks",
        rebuild=f"{_HERE}:_rebuild_design",
    ),
)


def kind_of(found: object) -> Kind:
    """The kind of the result ``found``."""
    named = f"{type(found).__module__}:{type(found).__qualname__}"
    for kind in KINDS:
        if named == kind.type:
            return kind
    raise InputError(f"{type(found).__name__} is not a result of an analysis of ours", field="result")


def folder_kind(folder: Path) -> Kind | None:
    """The kind of result a folder holds (by its marker file), or None."""
    return next((kind for kind in KINDS if (folder / kind.marker).is_file()), None)


def save(found: object, folder: str | Path) -> Path:
    """Write ``found`` into ``folder`` (new; it appears whole) as its command writes it;
    :func:`oscillator.read_run` reads it back.  A figure that fails is said in a warning (the
    tables are written)."""
    import warnings

    from oscillator.io.files import claim_folder

    kind = kind_of(found)
    claim = claim_folder(Path(folder))
    try:
        problems = kind.at("write")(found, claim.temporary)
        written = claim.commit()
    except BaseException:
        claim.abandon()
        raise
    for problem in problems:
        warnings.warn(f"{written}: {problem}; the tables are written", stacklevel=3)
    return written


def html(found: object) -> str:
    """A result as its report tells it, without the figures (``plot`` draws them): an HTML
    fragment, every text from a case escaped."""
    from oscillator.report import markup as mk

    blocks = kind_of(found).at("blocks")(found)
    return mk.html_fragment([block for block in blocks if not isinstance(block, mk.Figure)])


def rebuild(folder: Path) -> tuple[str, list[str]] | None:
    """``oscillator report`` on an analysis's folder: its tables, figures and report written again
    from what it keeps; what was rebuilt and what could not be drawn (the tables stay), or None
    for a folder of no kind here.  A folder of a kind that is not rebuilt is refused saying what
    to do instead."""
    kind = folder_kind(folder)
    if kind is None:
        return None
    if kind.refusal:
        raise InputError(f"{printable(str(folder))}: {kind.refusal}", field="folder")
    return kind.what, kind.at("rebuild")(folder)
