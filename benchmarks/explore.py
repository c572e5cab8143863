"""The explorer's latency in a real browser (Debian's Chromium through Playwright): from a slider's
change to the page redrawn with the new motion (50 forcing periods of Instance 1, the trajectory on
a grid of 64 points a period), and from a click on an atlas cell to its attractors shown.

Two paths for the slider: the explorer's default, each change drawn with the compiled DOP853 and
checked by CVODE once the controls rest, and ``--engine cvode``, each change drawn with the
reference itself.  A user looks at each motion before the next change: the next key press follows
each redraw after ``--pause`` s (more than the runner's quiet time, 0.15 s: a change within it of
the one before is taken as part of a burst and waits for the keys to rest; a pause shorter than
CVODE's delay, 0.4 s, stops its check).  Then, on the default path, the time from a change to
CVODE's verdict shown, the controls left at rest after each change; and a burst of 30 key presses
30 ms apart: the simulations it ran, and the time from its last press to the last value drawn.

Each change is a key press on the ``K3`` slider's handle (alternately right and left, so the
value moves back and forth by one step); the time runs, in the page, from the key press until the
frame is painted in which the status line shows the new revision (the figures and the table come in
the same message).  A click is timed from outside, from the click until its attractors are shown.
Served by ``oscillator explore`` in its own process, as a user runs it.

Usage: python benchmarks/explore.py [--changes N] [--clicks N]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from oscillator.exploring.driving import Served, browser_page, click_map, wait_revision


def slider(changes: int, *options: str, checked: bool = False, pause: float = 0.3) -> list[float]:
    with Served("instance-1", *options) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1, checked=checked)
        handle = page.locator(".control-K3 .noUi-handle")
        handle.focus()
        times = []
        for k in range(changes):
            page.wait_for_timeout(1e3 * pause)
            page.keyboard.press("ArrowRight" if k % 2 == 0 else "ArrowLeft")
            times.append(wait_revision(page, k + 2, checked=checked) / 1e3)  # timed in the page, from the key press
        assert not elsewhere, elsewhere
    return times


def burst() -> tuple[int, float]:
    """30 key presses 30 ms apart: the simulations drawn, and s from the last press to its value drawn."""
    with Served("instance-1") as served, browser_page() as (page, _):
        page.goto(served.url)
        wait_revision(page, 1, checked=True)
        before = int(page.locator("span[data-revision]").get_attribute("data-runs"))
        handle = page.locator(".control-K3 .noUi-handle").element_handle()
        page.evaluate(
            """async (h) => { for (let k = 0; k < 30; k++) {
                 h.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowLeft', bubbles: true}));
                 await new Promise(r => setTimeout(r, 30)); } }""",
            handle,
        )
        after = wait_revision(page, 31) / 1e3
        return int(page.locator("span[data-revision]").get_attribute("data-runs")) - before, after


def clicks(count: int) -> list[float]:
    import subprocess
    import sys

    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "atlas"
        command = str(Path(sys.executable).with_name("oscillator"))
        subprocess.run(
            [command, "atlas", "instance-1", "--x", "Omega", "1.5", "1.7", "6", "--y", "Q2", "70", "71.5", "4",
             "--out", str(folder), "--no-plots", "--quiet"],
            check=True, capture_output=True,
        )  # fmt: skip
        with Served(str(folder)) as served, browser_page() as (page, _):
            page.goto(served.url)
            wait_revision(page, 1)
            times = []
            rng = np.random.default_rng(1)
            for k in range(count):
                x, y = rng.uniform(0.15, 0.7), rng.uniform(0.15, 0.85)
                started = time.perf_counter()
                click_map(page, x, y, k + 1)
                times.append(time.perf_counter() - started)
                wait_revision(page, k + 2)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--changes", type=int, default=40)
    parser.add_argument("--clicks", type=int, default=10)
    parser.add_argument("--pause", type=float, default=0.3)
    arguments = parser.parse_args()
    print(f"{time.strftime('%Y-%m-%d')}, load {open('/proc/loadavg').read().split()[0]}")
    runs, after = burst()
    print(
        f"a burst of 30 key presses 30 ms apart: {runs} simulations drawn, the last {1e3 * after:.0f} ms after "
        "its last press"
    )
    for name, times in (
        ("slider change -> page redrawn (dop853, the default)", slider(arguments.changes, pause=arguments.pause)),
        (
            "slider change -> page redrawn (--engine cvode)",
            slider(arguments.changes, "--engine", "cvode", pause=arguments.pause),
        ),
        ("slider change -> CVODE's verdict shown (default)", slider(arguments.changes // 4, checked=True)),
        ("atlas click -> attractors shown", clicks(arguments.clicks)),
    ):
        ms = 1e3 * np.array(times)
        median, p95 = statistics.median(ms), np.percentile(ms, 95)
        print(f"{name}: {len(ms)} times, median {median:.0f} ms, 95th percentile {p95:.0f} ms, max {ms.max():.0f} ms")


if __name__ == "__main__":
    main()
