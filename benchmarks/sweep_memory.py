"""Peak memory of a sweep against its number of points: it should stay flat.

Runs the same short sweep (Instance 1, Omega in [1.5, 1.7], 10 + 5 periods a point) with N and
4 N points, each in a fresh process, and prints the peak resident set size of each.

Usage: python benchmarks/sweep_memory.py [N]   (default N = 25)
"""

import json
import subprocess
import sys
import tempfile

CHILD = r"""
import json, resource, sys, time
from pathlib import Path
from oscillator import SweepSettings, load_case
from oscillator.analysis.sweeps import run_sweep
steps, folder = int(sys.argv[1]), Path(sys.argv[2])
settings = SweepSettings(param="Omega", start=1.5, stop=1.7, steps=steps, transient=10, record=5)
started = time.perf_counter()
run_sweep(load_case("bifurcation-omega"), settings, folder, workers=1)
print(json.dumps({"points": steps, "seconds": time.perf_counter() - started,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def measure(steps: int) -> dict:
    with tempfile.TemporaryDirectory() as scratch:
        done = subprocess.run([sys.executable, "-c", CHILD, str(steps), f"{scratch}/sweep"], capture_output=True,
                              text=True, check=True)  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 25
    rows = [measure(n), measure(4 * n)]
    print(f"{'points':>8} {'seconds':>9} {'peak RSS (MB)':>14}")
    for row in rows:
        print(f"{row['points']:>8} {row['seconds']:>9.1f} {row['peak_rss_mb']:>14.1f}")
    print(f"peak memory ratio {4 * n} vs {n} points: {rows[1]['peak_rss_mb'] / rows[0]['peak_rss_mb']:.3f}")


if __name__ == "__main__":
    main()
