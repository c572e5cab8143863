"""The noise measures' spectra (docs/noise.md), measured: the harmonics' waves by products between
exact anchors every 32 harmonics (oscillator/orbits/spectra.py, now) against one complex
exponential each (the code before, kept here as the baseline), in one run, on the same
computations:

1. ``orbit.noise()`` of docs/noise.md's orbit (200 harmonics: both contact forces' and both
   masses' accelerations' spectra), the least of ``--repeats``;
2. a declared system's orbit's spectra (docs/systems/rattler.toml, ``orbit.noise()``);
3. every point of a frequency response (``FrequencyResponse.noise_tables()``: docs/noise.md's
   response over Omega in [1.45, 1.6], computed once, then its points measured both ways), per
   point;

and the largest difference between the two ways' coefficients.  The trajectory is not recorded on
any of these paths (each orbit's pieces only).

Usage: python benchmarks/noise.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import oscillator as osc
import oscillator.orbits.spectra as spectra


def direct(times: np.ndarray, period: float, harmonics: int) -> np.ndarray:
    """The waves before: one complex exponential each."""
    waves: np.ndarray = np.exp(-2j * np.pi * np.outer(np.arange(harmonics + 1), times) / period)
    return waves


def both(call: Callable[[], Any], repeats: int) -> tuple[float, float, Any, Any]:
    """``call`` with the waves before and now, alternating: the least times and the values."""
    products = spectra._waves
    times: dict[str, list[float]] = {"before": [], "now": []}
    values: dict[str, Any] = {}
    for _ in range(repeats):
        for way, waves in (("before", direct), ("now", products)):
            spectra._waves = waves
            started = time.perf_counter()
            try:
                values[way] = call()
            finally:
                spectra._waves = products
            times[way].append(time.perf_counter() - started)
    return min(times["before"]), min(times["now"]), values["before"], values["now"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    repeats = parser.parse_args().repeats
    print(f"benchmarks/noise.py, {datetime.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}")
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    orbit.noise()  # the kernels loaded
    before, now, old, new = both(orbit.noise, repeats)
    gap = max(
        np.abs(old.contacts[c].force.coefficients - new.contacts[c].force.coefficients).max() for c in ("left", "right")
    )
    print(f"  orbit.noise() (docs/noise.md's orbit, 200 harmonics): {before * 1e3:.1f} ms before, "
          f"{now * 1e3:.1f} ms now ({before / now:.1f}x); coefficients apart by {gap:.1e} N")  # fmt: skip
    rattler = osc.find_orbit(osc.load_system("docs/systems/rattler.toml"), transient=100)
    rattler.noise()
    before, now, old, new = both(rattler.noise, repeats)
    gap = float(np.abs(old.forces["stop"].coefficients - new.forces["stop"].coefficients).max())
    print(f"  a declared system's orbit.noise() (rattler.toml): {before * 1e3:.1f} ms before, "
          f"{now * 1e3:.1f} ms now ({before / now:.1f}x); coefficients apart by {gap:.1e} N")  # fmt: skip
    response = osc.frequency_response(osc.resolve_case("instance-1", d=1, d1=3.5), "Omega", (1.45, 1.6), seeds=2)
    points = len(response.points)
    before, now, _, _ = both(response.noise_tables, 1)
    each = f"{before / points * 1e3:.1f} ms a point before, {now / points * 1e3:.1f} ms now ({before / now:.1f}x)"
    print(f"  FrequencyResponse.noise_tables() ({points} points, docs/noise.md's response): {each}")
    print(f"load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
