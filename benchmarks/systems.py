"""Friction chains (issue 51, docs/systems.md): what a new system costs, and the chain path's speed.

1. the first run of a new system in a fresh process, numba's cache filled (the class compiled once,
   at install or by an earlier run): `import oscillator`, a chain never seen (random masses and
   elements), 10 forcing periods; the import, the run, a second system (other values) in the same
   process and the whole process, each measured;
2. the article's system on both paths, alternating, 5 repeats, medians: `simulate` (the built-in
   path) against `simulate_chain(article_chain(...))`, Instance 1 over 200 forcing periods with
   the trajectory at every step (the chain path records it always), and their ratio;
3. throughput of the three docs/systems/ machines: forcing periods and events per second;
4. the friction damper's orbit (Newton with the exact monodromy) and its frequency sweep over
   docs/systems.md's band at three normal loads (11 values each), warm, medians of 3;
5. the map's derivative at the damper's orbit and at a vibro-impact orbit with a cubic spring
   (tests/test_chain_sensitivities.py's): exact (the tangent pass: the exponential of each mode's
   Jacobian where the field is affine, DOP853 where it is not) against the central differences
   the orbits used before (two period maps a coordinate), medians of 5 alternating, and their
   largest difference; the sensitivities in three numbers; docs/damper-design.md's design.

Usage: python benchmarks/systems.py
"""

from __future__ import annotations

import datetime as dt
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_FIRST_RUN = """
import time
started = time.perf_counter()
import numpy as np
import oscillator
imported = time.perf_counter()
chain = oscillator.FrictionChain(Omega=1.7)
rng = np.random.default_rng({seed})
for i in range(4):
    chain = chain.mass(f"m{{i}}", m=float(rng.uniform(0.5, 2)), v=float(rng.uniform(-1, 1)))
    chain = chain.spring(f"m{{i}}", None if i == 0 else f"m{{i-1}}", k=float(rng.uniform(1, 3)))
    chain = chain.friction(f"m{{i}}", mu_s=0.3, mu_k=0.2, w=float(rng.uniform(0, 0.3)))
    chain = chain.jenkins(f"m{{i}}", kt=2.0, F=float(rng.uniform(0.1, 0.5)))
chain = chain.force("m3", Q=float(rng.uniform(5, 10))).stop("m0", side="right", at=0.5, K=100.0)
ran = time.perf_counter()
result = oscillator.simulate_chain(chain)
done = time.perf_counter()
oscillator.simulate_chain(chain.with_values({{"m0.m": 3.0, "m3.x": 0.2}}))
again = time.perf_counter()
print(imported - started, done - ran, len(result.events), again - done)
"""


def first_run(seed: int) -> tuple[float, float, float, int, float]:
    started = time.perf_counter()
    printed = subprocess.run(
        [sys.executable, "-c", _FIRST_RUN.format(seed=seed)], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.split()
    whole = time.perf_counter() - started
    return float(printed[0]), float(printed[1]), whole, int(printed[2]), float(printed[3])


def article_paths(repeats: int = 5) -> tuple[float, float, int, int]:
    import oscillator
    from oscillator.io.cases import resolve_case
    from oscillator.model.chains import article_chain

    case = resolve_case("instance-1")
    case = resolve_case("instance-1", t_end=case.initial.t0 + 200 * case.parameters.period)
    chain = article_chain(case.parameters, case.initial)
    oscillator.simulate(case)
    oscillator.simulate_chain(chain, case.t_end)  # both compiled and warm
    built, chained = [], []
    for _ in range(repeats):
        started = time.perf_counter()
        a = oscillator.simulate(case)
        built.append(time.perf_counter() - started)
        started = time.perf_counter()
        b = oscillator.simulate_chain(chain, case.t_end)
        chained.append(time.perf_counter() - started)
    return statistics.median(built), statistics.median(chained), len(a.events), len(b.events)


def machines() -> list[tuple[str, float, float, int]]:
    import oscillator

    rows = []
    for name in ("blade-damper", "conveyor", "belt-chain"):
        chain = oscillator.load_system(ROOT / "docs" / "systems" / f"{name}.toml")
        oscillator.simulate_chain(chain, chain.t0 + chain.period)
        started = time.perf_counter()
        result = oscillator.simulate_chain(chain, chain.t0 + 100 * chain.period)
        took = time.perf_counter() - started
        rows.append((name, 100 / took, len(result.events) / took, len(result.events)))
    return rows


def orbits(repeats: int = 3) -> tuple[float, float, int]:
    import numpy as np

    import oscillator

    chain = oscillator.load_system(ROOT / "docs" / "systems" / "blade-damper.toml")
    oscillator.find_orbit(chain, transient=60)  # warm
    found, swept, band = [], [], np.linspace(0.6, 1.6, 11)
    for _ in range(repeats):
        started = time.perf_counter()
        orbit = oscillator.find_orbit(chain, transient=60)
        found.append(time.perf_counter() - started)
        started = time.perf_counter()
        for load in (0.0, 0.3, 3.0):
            oscillator.frequency_sweep(chain.with_values({"platform.F": load}), band)
        swept.append(time.perf_counter() - started)
    return statistics.median(found), statistics.median(swept), orbit.iterations


def derivatives(repeats: int = 5) -> list[tuple[str, float, float, float, float]]:
    import numpy as np

    import oscillator
    from oscillator.orbits.chain_orbits import _derivative

    sys.path.insert(0, str(ROOT / "tests"))
    from test_chain_sensitivities import impact_chain, map_differences

    rows = []
    machines = {
        "blade damper (affine)": (oscillator.load_system(ROOT / "docs" / "systems" / "blade-damper.toml"), 60),
        "impacts (cubic spring)": (impact_chain(), 150),
    }
    for name, (chain, transient) in machines.items():
        orbit = oscillator.find_orbit(chain, transient=transient)
        names = list(chain.system.state)
        free = [names.index(n) for n in orbit.free]

        exact, old = [], []
        for _ in range(repeats):
            started = time.perf_counter()
            matrix = _derivative(orbit.run, free)
            exact.append(time.perf_counter() - started)
            started = time.perf_counter()
            reference = map_differences(orbit, free)
            old.append(time.perf_counter() - started)
        started = time.perf_counter()
        orbit.sensitivities(["Omega", *[p for p in chain.parameter_names() if p.endswith((".F", ".K", ".k"))][:2]])
        sensitivities = time.perf_counter() - started
        gap = float(np.abs(matrix - reference).max())
        rows.append((name, statistics.median(exact), statistics.median(old), gap, sensitivities))
    return rows


def design() -> tuple[float, str]:
    import oscillator

    chain = oscillator.load_system(ROOT / "docs" / "systems" / "blade-damper.toml")
    started = time.perf_counter()
    found = oscillator.design(chain, {"platform.F": (0.05, 3.0)}, {"Omega": (0.6, 1.6)}, "x_max:blade")
    return time.perf_counter() - started, found.summary


def main() -> None:
    print(f"friction chains, {dt.date.today()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    first_run(0)  # fills numba's cache if it is not
    print("1. a new system's first run in a fresh process (cache filled): import / run / process, s")
    for seed in (1, 2, 3):
        imported, ran, whole, events, again = first_run(seed)
        print(
            f"   seed {seed}: import {imported:.2f}, run {ran:.3f} ({events} events), another system in the same "
            f"process {again:.3f}, whole process {whole:.2f}"
        )
    built, chained, a, b = article_paths()
    print("2. Instance 1, 200 forcing periods, trajectory at every step (medians of 5, alternating)")
    print(f"   built-in simulate {built:.3f} s ({a} events); chain path {chained:.3f} s ({b} events)")
    print(f"   chain / built-in = {chained / built:.2f}")
    print("3. docs/systems/ machines over 100 forcing periods")
    for name, periods, events, count in machines():
        print(f"   {name}: {periods:.0f} periods/s, {events:.0f} events/s ({count} events)")
    found, swept, steps = orbits()
    print("4. the blade's friction damper (medians of 3, warm)")
    print(f"   find_orbit after 60 periods' transient: {found:.3f} s ({steps} Newton steps)")
    print(f"   frequency_sweep, 3 normal loads x 11 values of Omega: {swept:.2f} s")
    print("5. the map's derivative at an orbit: exact tangent pass against central differences (medians of 5)")
    for name, exact, old, gap, sensitivities in derivatives():
        print(
            f"   {name}: exact {exact * 1e3:.1f} ms, differences {old * 1e3:.1f} ms ({old / exact:.1f}x), largest "
            f"difference {gap:.1e}; sensitivities in 3 numbers {sensitivities * 1e3:.1f} ms"
        )
    took, summary = design()
    print(f"   docs/damper-design.md's design: {took:.1f} s ({summary})")


if __name__ == "__main__":
    main()
