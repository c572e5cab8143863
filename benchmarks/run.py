"""Benchmarks: prints a table and writes it as JSON (benchmarks/results.json).

1. each Instance: wall time (best of 3), events, CVODE steps, right-hand-side calls;
2. throughput (forcing periods per second) on Instance 1's system at Omega = 1.6 (with sliding)
   and 1.85 (without), trajectory off;
3. the same rules on SciPy's solve_ivp (DOP853, events; benchmarks/scipy_baseline.py) at the
   tolerance whose event times match a 1e-13 reference as closely as ours, and the ratio;
4. the default bifurcation-omega sweep (111 values x 150 periods) on this machine's cores;
5. peak memory of long runs with the trajectory off (fresh processes), to show it is flat.

Usage: python benchmarks/run.py [--quick] [--memory-periods N] [--json PATH]
  --quick: skip the sweep, and use 2,000 and 20,000 periods for the memory runs.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from scipy_baseline import run_scipy

from oscillator import load_case, simulate

HERE = Path(__file__).resolve().parent
WINDOW = 20  # forcing periods over which event-time accuracy is compared


def best_of(n, function):
    times, result = [], None
    for _ in range(n):
        started = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - started)
    return min(times), result


def instances() -> list[dict]:
    rows = []
    for i in range(1, 6):
        name = f"instance-{i}"
        wall, result = best_of(3, lambda name=name: simulate(name))
        rows.append({"case": name, "wall_s": wall, "events": result.stats["events"],
                     "cvode_steps": result.stats["returns"], "rhs_calls": result.stats["rhs_evaluations"]})  # fmt: skip
    return rows


def switching_times(events) -> np.ndarray:
    return np.array([e[0] for e in events if e[2] != "grazing"])


def throughput(omega: float, periods: int) -> dict:
    case = load_case("instance-1")
    case = case.__class__(**{**case.__dict__, "parameters": case.parameters.replace(Omega=omega)})
    period = case.parameters.period
    t0 = case.initial.t0
    wall, result = best_of(2, lambda: simulate(case, t_end=t0 + periods * period, record_trajectory=False))
    return {"omega": omega, "periods": periods, "wall_s": wall, "periods_per_s": periods / wall,
            "rhs_calls_per_period": result.stats["rhs_evaluations"] / periods}  # fmt: skip


def accuracy_and_baseline(omega: float) -> dict:
    case = load_case("instance-1")
    case = case.__class__(**{**case.__dict__, "parameters": case.parameters.replace(Omega=omega)})
    t_end = case.initial.t0 + WINDOW * case.parameters.period
    reference = simulate(case, t_end=t_end, rtol=1e-13, atol=1e-13, record_trajectory=False).events
    reference = reference[reference.kind != "grazing"].t.to_numpy()
    ours_wall, ours = best_of(3, lambda: simulate(case, t_end=t_end, record_trajectory=False))
    ours_times = ours.events[ours.events.kind != "grazing"].t.to_numpy()
    ours_error = float(np.max(np.abs(ours_times - reference)))
    trials = []
    for tol in (1e-9, 1e-10, 1e-11, 1e-12):
        events, _ = run_scipy(case, t_end, rtol=tol, atol=tol)
        times = switching_times(events)
        error = float(np.max(np.abs(times - reference))) if len(times) == len(reference) else float("inf")
        trials.append((tol, error))
    # the loosest SciPy tolerance at least as accurate as ours (else the most accurate one)
    good = [tol for tol, error in trials if error <= ours_error]
    chosen = max(good) if good else min(trials, key=lambda item: item[1])[0]
    scipy_wall, (events, stats) = best_of(2, lambda: run_scipy(case, t_end, rtol=chosen, atol=chosen))
    scipy_error = float(np.max(np.abs(switching_times(events) - reference)))
    return {"omega": omega, "periods": WINDOW, "ours_error_s": ours_error, "ours_wall_s": ours_wall,
            "scipy_rtol": chosen, "scipy_error_s": scipy_error, "scipy_wall_s": scipy_wall,
            "scipy_rhs_calls": stats["rhs_evaluations"], "speedup": scipy_wall / ours_wall,
            "scipy_trials": trials}  # fmt: skip


def sweep() -> dict:
    import tempfile

    from oscillator.sweep import run_sweep

    case = load_case("bifurcation-omega")
    with tempfile.TemporaryDirectory() as scratch:
        outcome = run_sweep(case, case.sweep, Path(scratch) / "sweep")
    return {"points": outcome.points, "periods_per_point": case.sweep.transient + case.sweep.record,
            "workers": os.cpu_count(), "wall_s": outcome.wall_time}  # fmt: skip


MEMORY_CHILD = r"""
import json, resource, sys, time
from oscillator import load_case, simulate
periods = int(sys.argv[1])
case = load_case("instance-1")
started = time.perf_counter()
t_end = case.initial.t0 + periods * case.parameters.period
result = simulate(case, t_end=t_end, record_trajectory=False, keep_events_from=t_end)
print(json.dumps({"periods": periods, "wall_s": time.perf_counter() - started, "events": result.stats["events"],
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "energy_residual": result.energy["residual"]}))
"""


def memory(periods: int) -> dict:
    done = subprocess.run([sys.executable, "-c", MEMORY_CHILD, str(periods)], capture_output=True, text=True)
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit code {done.returncode}"
        return {"periods": periods, "wall_s": float("nan"), "peak_rss_mb": float("nan"),
                "energy_residual": float("nan"), "error": last}  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--memory-periods", type=int, default=None)
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    args = parser.parse_args()
    long_run = args.memory_periods or (20_000 if args.quick else 100_000)
    simulate("instance-1")  # compile the kernels (numba caches them on disk) before timing

    results = {"machine": {"platform": platform.platform(), "python": platform.python_version(),
                           "cores": os.cpu_count()}}  # fmt: skip
    results["instances"] = instances()
    results["throughput"] = [throughput(1.6, 200), throughput(1.85, 200)]
    results["baseline"] = [accuracy_and_baseline(1.6), accuracy_and_baseline(1.85)]
    results["sweep"] = None if args.quick else sweep()
    results["memory"] = [memory(long_run // 10), memory(long_run)]

    print(f"machine: {results['machine']['platform']}, {results['machine']['cores']} cores\n")
    print(f"{'case':<12}{'wall (s)':>10}{'events':>8}{'CVODE steps':>13}{'RHS calls':>11}")
    for row in results["instances"]:
        print(
            f"{row['case']:<12}{row['wall_s']:>10.4f}{row['events']:>8}{row['cvode_steps']:>13}{row['rhs_calls']:>11}"
        )
    print(f"\n{'Omega':<8}{'periods/s':>11}{'RHS calls/period':>18}")
    for row in results["throughput"]:
        print(f"{row['omega']:<8}{row['periods_per_s']:>11.1f}{row['rhs_calls_per_period']:>18.0f}")
    print(f"\nagainst SciPy solve_ivp (DOP853, events), {WINDOW} periods, event times vs a 1e-13 reference:")
    print(
        f"{'Omega':<8}{'ours err':>10}{'ours (s)':>10}{'SciPy rtol':>11}{'SciPy err':>11}{'SciPy (s)':>11}{'ratio':>8}"
    )
    for row in results["baseline"]:
        print(f"{row['omega']:<8}{row['ours_error_s']:>10.1e}{row['ours_wall_s']:>10.3f}{row['scipy_rtol']:>11.0e}"
              f"{row['scipy_error_s']:>11.1e}{row['scipy_wall_s']:>11.3f}{row['speedup']:>8.1f}")  # fmt: skip
    if results["sweep"]:
        s = results["sweep"]
        print(f"\nbifurcation-omega sweep: {s['points']} values x {s['periods_per_point']} periods on "
              f"{s['workers']} cores: {s['wall_s']:.1f} s")  # fmt: skip
    print(f"\n{'periods':>10}{'wall (s)':>10}{'peak RSS (MB)':>15}{'energy residual (J)':>21}")
    for row in results["memory"]:
        print(f"{row['periods']:>10}{row['wall_s']:>10.1f}{row['peak_rss_mb']:>15.1f}{row['energy_residual']:>21.2e}"
              + (f"  failed: {row['error']}" if "error" in row else ""))  # fmt: skip
    args.json.write_text(json.dumps(results, indent=2, default=float) + "\n", encoding="utf-8")
    print(f"\nwritten to {args.json}")


if __name__ == "__main__":
    main()
