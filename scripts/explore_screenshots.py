"""The screenshots of docs/explore.md, taken in headless Chromium from ``oscillator explore`` as a
user runs it: the explorer of the impacting system with its orbit asked for, an atlas with a cell
clicked, a frequency response with a branch point clicked, and the vibration conveyor's system
file (docs/systems.md).

Usage: python scripts/explore_screenshots.py [case|atlas|frc|system ...]
"""

import subprocess
import sys
import tempfile
from pathlib import Path

from oscillator.exploring.driving import Served, browser_page, click_map, wait_revision

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


def system() -> None:
    """The conveyor of docs/systems/conveyor.toml: its walls' contacts shaded, the part stuck."""
    path = IMAGES.parent / "systems" / "conveyor.toml"
    with Served(str(path), "--set", "drive.Q=18", "--periods", "12") as served:
        with browser_page(1300, 1500) as (page, elsewhere):
            page.goto(served.url)
            wait_revision(page, 1)
            page.wait_for_timeout(500)
            page.screenshot(path=IMAGES / "explore-system.png", full_page=False)
            assert not elsewhere, elsewhere


def atlas() -> None:
    clicked(
        "explore-atlas.png",
        ["atlas", "instance-1", "--x", "Omega", "1.3", "1.85", "12", "--y", "Q2", "68.5", "72", "8"],
        (0.55, 0.45),
    )


#: docs/frequency.md's hardening Duffing oscillator: one branch that folds twice.
DUFFING = {"m1": 1.0, "K1": 1.0, "K2": 0.05, "C1": 0.05, "C2": 0.0, "K3": 0.0, "C3": 0.0, "m2": 1.5, "K4": 1.0,
           "K5": 0.0, "C4": 0.2, "C5": 0.0, "mu_k": 0.0, "mu_s": 0.0, "P1": 0.0, "P2": 0.0, "d": 1000.0,
           "d1": 1000.0, "Q1": 0.2, "Q2": 0.1, "Omega": 0.8, "x1": 0.0, "v1": 0.0, "x2": 0.0, "v2": 0.1}  # fmt: skip


def frc() -> None:
    given = {name: value for name, value in DUFFING.items() if name != "Omega"}  # Omega is the --param
    command = ["frc", "instance-1", *(f"--set={name}={value}" for name, value in given.items())]
    command += [
        "--param",
        "Omega",
        "0.8",
        "1.6",
        "--seeds",
        "3",
        "--sweep",
        "11",
        "--transient",
        "400",
        "--record",
        "8",
    ]
    clicked("explore-frc.png", command, (0.42, 0.45))


def clicked(image: str, command: list[str], at: tuple[float, float]) -> None:
    """The folder ``command`` writes, served; a click at ``at`` (fractions of the picture's canvas)."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "folder"
        subprocess.run([COMMAND, *command, "--out", str(folder), "--no-plots", "--quiet"], check=True)
        with Served(str(folder), "--periods", "20") as served, browser_page(1300, 1100) as (page, _):
            page.goto(served.url)
            wait_revision(page, 1)
            click_map(page, *at)
            wait_revision(page, 2)
            page.wait_for_timeout(500)
            page.screenshot(path=IMAGES / image, full_page=False)


if __name__ == "__main__":
    TAKEN = {"case": case, "atlas": atlas, "frc": frc, "system": system}
    for name in sys.argv[1:] or list(TAKEN):
        TAKEN[name]()
