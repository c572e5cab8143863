"""The documented frequency response of Instance 1 (``oscillator frc instance-1 --param Omega 1.3
1.85``, the issue's target: at most 60 s on 2 cores): the command's wall time end to end (a fresh
process, figures and report included), the library's stages timed in this process, and the same on
one worker.

Usage: python benchmarks/frequency.py [--workers W]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import oscillator as osc

COMMAND = ["frc", "instance-1", "--param", "Omega", "1.3", "1.85"]


def command(workers: int) -> float:
    """The command's wall time in a fresh process (imports, compilation from the cache, figures)."""
    oscillator = str(Path(sys.executable).with_name("oscillator"))
    with tempfile.TemporaryDirectory() as scratch:
        started = time.perf_counter()
        subprocess.run(
            [oscillator, *COMMAND, "--workers", str(workers), "--out", f"{scratch}/frc", "--quiet"], check=True
        )
        return time.perf_counter() - started


def stages(workers: int) -> None:
    """The library call with progress: the time at which each stage's first report came."""
    marks: list[tuple[float, int, int]] = []
    started = time.perf_counter()

    def progress(done: int, total: int) -> None:
        marks.append((time.perf_counter() - started, done, total))

    found = osc.frequency_response("instance-1", "Omega", (1.3, 1.85), workers=workers, progress=progress)
    total = time.perf_counter() - started
    points = len(found.points)
    print(
        f"  library, {workers} worker(s): {total:.1f} s for {len(found.branches)} branches, {points} points "
        f"({1000 * total / max(points, 1):.0f} ms a point, everything included), {len(found.sweeps)} sweep values"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    workers = parser.parse_args().workers
    print(f"oscillator {' '.join(COMMAND)}")
    for count in sorted({workers, 1}, reverse=True):
        print(f"  command, {count} worker(s): {command(count):.1f} s end to end")
        stages(count)


if __name__ == "__main__":
    main()
