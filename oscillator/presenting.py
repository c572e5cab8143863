"""How the library's results show themselves: drawn, saved, rendered in Jupyter.

:class:`~oscillator.Result`, :class:`~oscillator.Orbit` and :class:`~oscillator.Branch` live
in the layers that compute them (hybrid/, orbits/), below the figures, the run folders and the
reports that present them (report/).  Their ``plot``, ``save`` and ``_repr_html_`` methods call
the :class:`Presenter` registered here, which the package registers when it is imported
(``oscillator/__init__.py``, from :mod:`oscillator.views`): the computing layers import nothing
above them, and the presentation can be swapped (a test registers its own).
"""

from __future__ import annotations

#: ``typing.TYPE_CHECKING`` without importing ``typing``: ``import oscillator`` imports this
#: module, and stays a few milliseconds.
TYPE_CHECKING = False

if TYPE_CHECKING:  # pragma: no cover - annotations only: this module imports nothing at run time
    from collections.abc import Mapping
    from pathlib import Path
    from typing import Protocol

    import pandas as pd
    from matplotlib.figure import Figure

    from oscillator.attractors.chain_attractors import ChainBasins
    from oscillator.attractors.chain_frequency import ChainFrequencyResponse
    from oscillator.attractors.frequency import FrequencyResponse
    from oscillator.designing.chain_design import ChainDesign
    from oscillator.hybrid.chain_run import ChainResult
    from oscillator.hybrid.result import Result
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.branch import Branch
    from oscillator.orbits.chain_noise import ChainNoise
    from oscillator.orbits.noise import Noise
    from oscillator.orbits.shooting import Orbit
else:
    Protocol = object

__all__ = ["Presented", "Presenter", "presenter", "register"]


class Presenter(Protocol):
    """What the results' presentation methods call (a structural type: :class:`oscillator.views.Views`
    is one)."""

    def plot_result(self, result: Result, panel: str, window: tuple[float, float] | None) -> Figure: ...

    def save_result(self, result: Result, folder: str | Path, *, formats: str, figures: bool, report: bool) -> Path: ...

    def result_html(self, result: Result) -> str: ...

    def save_orbit(self, orbit: Orbit, folder: str | Path) -> Path: ...

    def orbit_html(self, orbit: Orbit) -> str: ...

    def plot_branch(self, branch: Branch, coordinate: str, sweep_points: pd.DataFrame | None) -> Figure: ...

    def plot_multipliers(self, branch: Branch) -> Figure: ...

    def save_branch(self, branch: Branch, folder: str | Path, *, coordinate: str) -> Path: ...

    def branch_html(self, branch: Branch) -> str: ...

    def plot_global(self, found: object, **options: object) -> Figure: ...

    def save_global(self, found: object, folder: str | Path) -> Path: ...

    def global_html(self, found: object) -> str: ...

    def plot_system(self, chain: FrictionChain) -> Figure: ...

    def plot_chain_basins(self, basins: ChainBasins) -> Figure: ...

    def plot_chain_frequency(self, response: ChainFrequencyResponse, measure: str | None) -> Figure: ...

    def plot_chain_result(self, result: ChainResult) -> Figure: ...

    def save_chain_result(self, result: ChainResult, folder: str | Path, *, figures: bool, report: bool) -> Path: ...

    def plot_chain_design(self, design: ChainDesign, sweeps: Mapping[float, pd.DataFrame] | None) -> Figure: ...

    def plot_noise(self, found: Noise | ChainNoise) -> Figure: ...

    def plot_noise_response(self, found: FrequencyResponse, table: pd.DataFrame, column: str) -> Figure: ...


_registered: list[Presenter] = []


def register(presenter: Presenter) -> None:
    """Use ``presenter`` from now on."""
    _registered[:] = [presenter]


def presenter() -> Presenter:
    """The registered presenter."""
    if not _registered:  # only if oscillator/__init__.py was bypassed
        raise RuntimeError("no presenter is registered: import the oscillator package")
    return _registered[0]


class Presented:
    """What every global analysis's result does through the presenter: save itself as its command
    writes its folder (:func:`oscillator.read_run` reads it back) and show itself in Jupyter."""

    __slots__ = ()

    def save(self, folder: str | Path) -> Path:
        """Write this result into ``folder`` (new) as its command writes its folder: tables,
        figures, report, and what makes the result again; :func:`oscillator.read_run` reads it
        back."""
        return presenter().save_global(self, folder)

    def _repr_html_(self) -> str:
        return presenter().global_html(self)
