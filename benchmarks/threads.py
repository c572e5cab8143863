"""BLAS's threads (oscillator/threads.py): the same work in fresh processes with the package's one
BLAS thread and with one per core (``OPENBLAS_NUM_THREADS`` set to the cores, as before the
package chose), on a quiet machine and with every other core kept busy by a spinning process
(a loaded machine, a test run beside it). Wall and CPU time, the least of ``--repeats``.

The work: docs/damper-design.md's worst blade amplitude over the band at three loads (periodic
orbits of a declared system, their tangents through matrix exponentials), and the worked design
of docs/design.md on one worker (landings, orbits and their sensitivities on the article's system).

Usage: python benchmarks/threads.py [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WORK = {
    "worst_over, blade damper, 3 loads": """
import oscillator
machine = oscillator.load_system("docs/systems/blade-damper.toml")
for load in (0.05, 0.47, 3.0):
    oscillator.worst_over(machine.with_values({"platform.F": load}), "x_max:blade", ("Omega", 0.6, 1.6))
""",
    "design (docs/design.md's worked example), one worker": """
from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.optimise import design
design("instance-1", {"d1": (2.5, 4.5), "K6": (1.0, 40.0)}, {"Omega": (1.4, 1.6)}, "x_max_m1",
       ["impact_max_right <= 5", "rest_m2 <= 0.01"], band=3, starts=2, candidates=8,
       settings=AttractorSettings(transient=100, record=8), workers=1)
""",
}
#: Prints the wall and CPU seconds of the work (after the imports and a first call that loads the
#: compiled kernels).
TIMED = """
import sys, time
work = sys.stdin.read()
exec(work)
wall, cpu = time.perf_counter(), time.process_time()
exec(work)
print(time.perf_counter() - wall, time.process_time() - cpu)
"""
SPIN = "while True: pass"


def _timed(work: str, threads: int | None) -> tuple[float, float]:
    environment = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    if threads is not None:
        environment["OPENBLAS_NUM_THREADS"] = str(threads)
    done = subprocess.run([sys.executable, "-c", TIMED], input=work, capture_output=True, text=True, cwd=ROOT,
                          env=environment, check=True)  # fmt: skip
    wall, cpu = (float(v) for v in done.stdout.split())
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    print(f"benchmarks/threads.py, {dt.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}, {cores} cores")
    for loaded in (False, True):
        spinners = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(cores - 1)] if loaded else []
        try:
            print("with every other core busy:" if loaded else "quiet:")
            for name, work in WORK.items():
                one = min(_timed(work, None) for _ in range(args.repeats))
                many = min(_timed(work, cores) for _ in range(args.repeats))
                print(f"  {name}: one BLAS thread {one[0]:.2f} s wall, {one[1]:.2f} s CPU; "
                      f"{cores} threads {many[0]:.2f} s wall, {many[1]:.2f} s CPU "
                      f"({many[0] / one[0]:.2f}x the wall, {many[1] / one[1]:.2f}x the CPU)")  # fmt: skip
        finally:
            for spinner in spinners:
                spinner.kill()
                spinner.wait()
    print(f"load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
