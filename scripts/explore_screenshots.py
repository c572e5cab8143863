"""The screenshots of docs/explore.md, taken in headless Chromium from ``oscillator explore`` as a
user runs it: the explorer of the impacting system with its orbit asked for, and an atlas with a
cell clicked.

Usage: python scripts/explore_screenshots.py
"""

import subprocess
import sys
import tempfile
from pathlib import Path

from oscillator.exploring.driving import Served, browser_page, wait_revision

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"
COMMAND = str(Path(sys.executable).with_name("oscillator"))


def case() -> None:
    with Served("instance-1", "--set", "d=1", "--set", "d1=3.5", "--set", "Omega=1.5", "--periods", "20") as served:
        with browser_page(1300, 1500) as (page, elsewhere):
            page.goto(served.url)
            wait_revision(page, 1)
            page.get_by_text("Orbit and multipliers").click()
            page.locator(".oscillator-orbit-found").wait_for(timeout=60e3)
            page.wait_for_timeout(500)
            page.screenshot(path=IMAGES / "explore-case.png", full_page=False)
            assert not elsewhere, elsewhere


def atlas() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "atlas"
        subprocess.run(
            [COMMAND, "atlas", "instance-1", "--x", "Omega", "1.3", "1.85", "12", "--y", "Q2", "68.5", "72", "8",
             "--out", str(folder), "--no-plots", "--quiet"],
            check=True,
        )  # fmt: skip
        with Served(str(folder), "--periods", "20") as served, browser_page(1300, 1100) as (page, _):
            page.goto(served.url)
            wait_revision(page, 1)
            box = page.locator(".bk-Canvas").first.bounding_box()
            page.mouse.click(box["x"] + 0.55 * box["width"], box["y"] + 0.45 * box["height"])
            page.locator(".oscillator-picked-found[data-click='1']").wait_for(timeout=60e3)
            wait_revision(page, 2)
            page.wait_for_timeout(500)
            page.screenshot(path=IMAGES / "explore-atlas.png", full_page=False)


if __name__ == "__main__":
    case()
    atlas()
