"""A run's four figures saved as PNG and SVG: matplotlib's own ``bbox_inches="tight"`` on each
file (before: every file lays the figure out and measures its text again) against
:func:`oscillator.report.figures.save_figure` (now: laid out once, then drawn once per format).

Both save the same freshly drawn figures of one run of Instance 3 (``oscillator run instance-3``'s
figures), in this process, alternating, the least of twice ``--repeats``; the PNG files are
compared pixel for pixel.

Usage: python benchmarks/figures.py [--case instance-3] [--repeats 5]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import tempfile
import time
from pathlib import Path

import matplotlib as mpl
import numpy as np

import oscillator as osc
from oscillator.report.figures import SAVED_DPI, draw_figures, save_figure


def before(fig, directory: Path, name: str) -> None:
    """What save_figure did before: each format laid out and measured by matplotlib."""
    for suffix in ("png", "svg"):
        fig.savefig(directory / f"{name}.{suffix}", format=suffix, dpi=SAVED_DPI, bbox_inches="tight")


def timed(save, draw, directory: Path, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        figures = draw()
        start = time.perf_counter()
        for name, fig in figures.items():
            save(fig, directory, name)
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="instance-3")
    parser.add_argument("--repeats", type=int, default=5)
    options = parser.parse_args()
    mpl.use("Agg")
    result = osc.simulate(options.case)
    case = result.case
    start = (case.initial.t0, *case.initial.y)

    def draw():
        return draw_figures(result.trajectory, result.events, case.parameters, start, title=case.name)

    load = os.getloadavg()[0]
    when = f"{dt.datetime.now():%Y-%m-%d %H:%M}, load {load:.2f}"
    print(f"figures of {options.case}: {when}, the least of 2 x {options.repeats}")
    with tempfile.TemporaryDirectory() as folder:
        old, new = Path(folder) / "before", Path(folder) / "now"
        old.mkdir()
        new.mkdir()
        draw()  # fonts and mathtext loaded before either is timed
        seconds = {"before": float("inf"), "now": float("inf")}
        for _ in range(2):  # alternating
            seconds["before"] = min(seconds["before"], timed(before, draw, old, options.repeats))
            seconds["now"] = min(seconds["now"], timed(save_figure, draw, new, options.repeats))
        same = all(
            np.array_equal(mpl.image.imread(old / f"{name}.png"), mpl.image.imread(new / f"{name}.png"))
            for name in draw()
        )
    ratio = seconds["before"] / seconds["now"]
    print(f"  4 figures, PNG and SVG: before {seconds['before']:.3f} s, now {seconds['now']:.3f} s ({ratio:.2f}x)")
    print(f"  the PNG files the same pixel for pixel: {same}")


if __name__ == "__main__":
    main()
