"""The package's :class:`~oscillator.presenting.Presenter`: the results drawn, saved and shown by
report/ (each module imported when first used, so that ``import oscillator`` stays light)."""

from __future__ import annotations

#: ``typing.TYPE_CHECKING`` without importing ``typing`` (see :mod:`oscillator.presenting`).
TYPE_CHECKING = False

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Mapping
    from pathlib import Path

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

__all__ = ["Views"]


class Views:
    """Figures from :mod:`oscillator.report.figures` and :mod:`oscillator.report.orbits`, run
    folders from :mod:`oscillator.report.runs`, rich displays from :mod:`oscillator.report.notebook`."""

    def plot_result(self, result: Result, panel: str, window: tuple[float, float] | None) -> Figure:
        from oscillator.report.figures import draw_panel

        return draw_panel(
            result.trajectory, result.events, result.case, panel, window=window, t_final=result.final_state[0]
        )

    def save_result(self, result: Result, folder: str | Path, *, formats: str, figures: bool, report: bool) -> Path:
        from oscillator.report.runs import save_result

        return save_result(result, folder, formats=formats, figures=figures, report=report)

    def result_html(self, result: Result) -> str:
        from oscillator.report.notebook import result_html

        return result_html(result)

    def save_orbit(self, orbit: Orbit, folder: str | Path) -> Path:
        from oscillator.report.orbit_folders import save_orbit

        return save_orbit(orbit, folder)

    def orbit_html(self, orbit: Orbit) -> str:
        from oscillator.report.notebook import orbit_html

        return orbit_html(orbit)

    def plot_branch(self, branch: Branch, coordinate: str, sweep_points: pd.DataFrame | None) -> Figure:
        from oscillator.report.orbits import branch_figure

        return branch_figure(branch, coordinate, sweep_points)

    def plot_multipliers(self, branch: Branch) -> Figure:
        from oscillator.report.orbits import multipliers_figure

        return multipliers_figure(branch)

    def save_branch(self, branch: Branch, folder: str | Path, *, coordinate: str) -> Path:
        from oscillator.report.orbit_folders import save_branch

        return save_branch(branch, folder, coordinate=coordinate)

    def branch_html(self, branch: Branch) -> str:
        from oscillator.report.notebook import branch_html

        return branch_html(branch)

    def plot_global(self, found: object, **options: object) -> Figure:
        """The figure of an analysis's result (:mod:`oscillator.report.kinds`), as its command
        draws it."""
        from oscillator.report.kinds import kind_of

        figure: Figure = kind_of(found).at("figure")(found, **options)
        return figure

    def save_global(self, found: object, folder: str | Path) -> Path:
        """An analysis's result written as its command writes its folder."""
        from oscillator.io.files import as_folder
        from oscillator.report.kinds import save

        return save(found, as_folder(folder))

    def global_html(self, found: object) -> str:
        from oscillator.report.kinds import html

        return html(found)

    def plot_system(self, chain: FrictionChain) -> Figure:
        from oscillator.report.chain_figures import schematic_figure

        return schematic_figure(chain)

    def plot_chain_design(self, design: ChainDesign, sweeps: Mapping[float, pd.DataFrame] | None) -> Figure:
        from oscillator.report.chain_frequency import design_figure

        return design_figure(design, sweeps)

    def plot_noise(self, found: Noise | ChainNoise) -> Figure:
        from oscillator.report.noise import noise_figure

        return noise_figure(found)

    def plot_noise_response(self, found: FrequencyResponse, table: pd.DataFrame, column: str) -> Figure:
        from oscillator.report.noise import noise_response_figure

        return noise_response_figure(found, table, column)

    def plot_chain_basins(self, basins: ChainBasins) -> Figure:
        from oscillator.report.attractors import basins_figure

        return basins_figure(basins)

    def plot_chain_frequency(self, response: ChainFrequencyResponse, measure: str | None) -> Figure:
        from oscillator.report.chain_frequency import sweep_figure

        return sweep_figure(response.sweeps, response.chain, response.param, response, measure)

    def plot_chain_result(self, result: ChainResult) -> Figure:
        from oscillator.report.chain_figures import motion_figure

        return motion_figure(result)

    def save_chain_result(self, result: ChainResult, folder: str | Path, *, figures: bool, report: bool) -> Path:
        from oscillator.report.chain_runs import save_chain_result

        return save_chain_result(result, folder, figures=figures, report=report)
