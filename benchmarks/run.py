"""Benchmarks: prints a table and writes it as JSON (benchmarks/results.json).

1. each Instance: wall time (best of 3), events, CVODE steps, right-hand-side calls;
2. throughput (forcing periods per second) on Instance 1's system at Omega = 1.6 (with sliding)
   and 1.85 (without), trajectory off;
3. the same rules on SciPy's solve_ivp (DOP853, events; benchmarks/scipy_baseline.py) at the
   tolerance whose event times match a 1e-13 reference as closely as ours, and the ratio;
4. the default bifurcation-omega sweep (111 values x 150 periods) on this machine's cores;
5. peak memory of long runs with the trajectory off (fresh processes), to show it is flat;
6. the soak of issue 6: Instances 3 and 5 over N/10 and N forcing periods (fresh processes): wall
   time, events, peak memory and the energy-audit residual;
7. the floor of scikit-sundae's callbacks: the cost of one CVODE step of a trivial problem whose
   right-hand side is a Python function, which bounds the speed of any CVODE-based simulator here;
8. the engines side by side (C-level CVODE, scikit-sundae's Python API, SciPy on the package's
   compiled formulas), 5 interleaved repeats, medians, on Instance 1's system;
9. the Python work per root return outside the engine (switching decisions, events, recording),
   and the cost of building the event table per event;
10. start-up: `simulate("instance-1", t_end=2)` in a fresh process with numba's cache empty (the
   first run after an install) and filled (every later run);
11. periodic orbits on Instance 1's system: one evaluation of the stroboscopic map without and
   with its monodromy matrix, a Newton step, `find_orbit` from a transient, and continuation
   (the Q2 and Omega branches of docs/orbits.md): seconds per point, against a sweep's point.

Usage: python benchmarks/run.py [--quick] [--only SECTION ...] [--memory-periods N] [--soak-periods N]
                                [--json PATH]
  --quick: a check that every section runs, in under a minute: a 5-value sweep, 500 periods for
  the memory runs and the soak, short throughput and baseline windows; its figures are not the
  benchmark's. Every section prints a line when it starts and each measurement as it
  ends.
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

from oscillator import load_case, resolve_case, simulate

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
        rows.append({"case": name, "wall_s": wall, "events": result.stats.events,
                     "cvode_steps": result.stats.returns, "rhs_calls": result.stats.rhs_evaluations})  # fmt: skip
    return rows


def switching_times(events) -> np.ndarray:
    return np.array([e[0] for e in events if e[2] != "grazing"])


def say(text: str) -> None:
    print(f"  [{time.strftime('%H:%M:%S')}] {text}", flush=True)


def throughput(omega: float, periods: int) -> dict:
    case = resolve_case("instance-1", Omega=omega)
    period = case.parameters.period
    t0 = case.initial.t0
    wall, result = best_of(2, lambda: simulate(case, t_end=t0 + periods * period, record_trajectory=False))
    say(f"Omega = {omega}: {periods} periods in {wall:.2f} s")
    return {"omega": omega, "periods": periods, "wall_s": wall, "periods_per_s": periods / wall,
            "rhs_calls_per_period": result.stats.rhs_evaluations / periods}  # fmt: skip


def accuracy_and_baseline(omega: float, window: int = WINDOW) -> dict:
    case = resolve_case("instance-1", Omega=omega)
    t_end = case.initial.t0 + window * case.parameters.period
    reference = simulate(case, t_end=t_end, rtol=1e-13, atol=1e-13, record_trajectory=False).events
    reference = reference[reference.kind != "grazing"].t.to_numpy()
    ours_wall, ours = best_of(3, lambda: simulate(case, t_end=t_end, record_trajectory=False))
    steps_wall, at_steps = best_of(3, lambda: simulate(case, t_end=t_end))  # the trajectory at every step
    grid = np.arange(case.initial.t0, t_end, case.parameters.period / 50)
    grid_wall, _ = best_of(3, lambda: simulate(case, t_end=t_end, t_eval=grid))  # 50 rows a period
    assert len(at_steps.events) == len(ours.events)  # the same events (to CVODE's rounding of its own outputs)
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
    in_cvode = min(_time_in_cvode(case, t_end) for _ in range(3))
    scipy_error = float(np.max(np.abs(switching_times(events) - reference)))
    say(f"Omega = {omega}: ours {ours_wall:.3f} s off, {steps_wall:.3f} s at every step, {grid_wall:.3f} s on a "
        f"grid; SciPy {scipy_wall:.3f} s at rtol {chosen:g}")  # fmt: skip
    return {"omega": omega, "periods": window, "ours_error_s": ours_error, "ours_wall_s": ours_wall,
            "ours_steps_wall_s": steps_wall, "ours_grid_wall_s": grid_wall, "trajectory_rows": len(at_steps.trajectory),
            "scipy_rtol": chosen, "scipy_error_s": scipy_error, "scipy_wall_s": scipy_wall,
            "scipy_rhs_calls": stats["rhs_evaluations"], "speedup": scipy_wall / ours_wall,
            "speedup_steps": scipy_wall / steps_wall, "speedup_grid": scipy_wall / grid_wall,
            "in_cvode_s": in_cvode, "speedup_bound": scipy_wall / in_cvode, "scipy_trials": trials}  # fmt: skip


def _time_in_cvode(case, t_end) -> float:
    """Seconds spent in CVODE's calls (the integrator, the compiled callbacks, its root finding)
    during a run with the trajectory off: what is left with no Python at all, which bounds the
    ratio to SciPy that any supervisor on CVODE can reach."""
    from oscillator.engines.cvode_c import CCvodeEngine

    spent = [0.0]

    class Timed(CCvodeEngine):
        def advance(self, *args, **kwargs):
            started = time.perf_counter()
            try:
                return super().advance(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - started

    simulate(case, t_end=t_end, record_trajectory=False, engine=Timed)
    return spent[0]


def sweep(steps: int | None = None) -> dict:
    import dataclasses
    import tempfile

    from oscillator.analysis.sweeps import run_sweep

    case = load_case("bifurcation-omega")
    settings = case.sweep if steps is None else dataclasses.replace(case.sweep, steps=steps)

    def progress(done: int, total: int) -> None:
        if done % 10 == 0 or done == total:
            say(f"{done}/{total} values")

    with tempfile.TemporaryDirectory() as scratch:
        outcome = run_sweep(case, settings, Path(scratch) / "sweep", progress=progress)
    return {"points": outcome.points, "periods_per_point": settings.transient + settings.record,
            "workers": os.cpu_count(), "wall_s": outcome.wall_time}  # fmt: skip


MEMORY_CHILD = r"""
import json, resource, sys, time
from oscillator import load_case, simulate
periods, name = int(sys.argv[1]), sys.argv[2]
case = load_case(name)
started = time.perf_counter()
t_end = case.initial.t0 + periods * case.parameters.period
result = simulate(case, t_end=t_end, record_trajectory=False, keep_events_from=t_end)
print(json.dumps({"case": name, "periods": periods, "wall_s": time.perf_counter() - started,
                  "events": result.stats.events,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "energy_residual": result.energy.residual,
                  "relative_residual": abs(result.energy.residual) / sum(
                      abs(getattr(result.energy, k)) for k in ("forcing", "feedback", "damping", "friction"))}))
"""


def memory(periods: int, name: str = "instance-1") -> dict:
    """A run of ``periods`` forcing periods of a case in a fresh process, trajectory and events off."""
    say(f"{name}: {periods} periods in a fresh process ...")
    done = subprocess.run([sys.executable, "-c", MEMORY_CHILD, str(periods), name], capture_output=True, text=True)
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit code {done.returncode}"
        return {"case": name, "periods": periods, "wall_s": float("nan"), "events": 0, "peak_rss_mb": float("nan"),
                "energy_residual": float("nan"), "error": last}  # fmt: skip
    row = json.loads(done.stdout.strip().splitlines()[-1])
    say(f"{name}: {periods} periods in {row['wall_s']:.1f} s, peak RSS {row['peak_rss_mb']:.1f} MB")
    return row


def callback_floor(steps: int = 200_000) -> dict:
    """Microseconds per CVODE step of x'' = -x with a one-line Python right-hand side."""
    from sksundae.cvode import CVODE

    def rhs(t, y, yp):
        yp[0] = y[1]
        yp[1] = -y[0]

    solver = CVODE(rhs, method="Adams", rtol=1e-10, atol=1e-10, max_step=1e-3, max_num_steps=10 * steps)
    solver.init_step(0.0, np.array([1.0, 0.0]))
    started = time.perf_counter()
    out = solver.step(steps * 1e-3, tstop=steps * 1e-3)
    wall = time.perf_counter() - started
    return {"rhs_calls": int(out.nfev), "us_per_call": wall / out.nfev * 1e6}


def print_instances(rows: list[dict]) -> None:
    print(f"{'case':<12}{'wall (s)':>10}{'events':>8}{'CVODE steps':>13}{'RHS calls':>11}")
    for row in rows:
        print(
            f"{row['case']:<12}{row['wall_s']:>10.4f}{row['events']:>8}{row['cvode_steps']:>13}{row['rhs_calls']:>11}"
        )


def print_throughput(rows: list[dict]) -> None:
    print(f"{'Omega':<8}{'periods/s':>11}{'RHS calls/period':>18}")
    for row in rows:
        print(f"{row['omega']:<8}{row['periods_per_s']:>11.1f}{row['rhs_calls_per_period']:>18.0f}")


def print_baseline(rows: list[dict]) -> None:
    print(f"against SciPy solve_ivp (DOP853, events), {rows[0]['periods']} periods, event times vs a 1e-13 reference:")
    print(f"{'Omega':<8}{'ours err':>10}{'SciPy rtol':>11}{'SciPy err':>11}{'SciPy (s)':>11}   "
          f"{'ours, trajectory: off (s)':>26}{'ratio':>7}{'every step (s)':>16}{'ratio':>7}"
          f"{'grid (s)':>10}{'ratio':>7}{'in CVODE (s)':>14}{'bound':>7}")  # fmt: skip
    for row in rows:
        print(f"{row['omega']:<8}{row['ours_error_s']:>10.1e}{row['scipy_rtol']:>11.0e}{row['scipy_error_s']:>11.1e}"
              f"{row['scipy_wall_s']:>11.3f}   {row['ours_wall_s']:>26.3f}{row['speedup']:>7.1f}"
              f"{row['ours_steps_wall_s']:>16.3f}{row['speedup_steps']:>7.1f}{row['ours_grid_wall_s']:>10.3f}"
              f"{row['speedup_grid']:>7.1f}{row['in_cvode_s']:>14.3f}{row['speedup_bound']:>7.1f}")  # fmt: skip
    print("  in CVODE: the run's time inside CVODE's calls alone (trajectory off); bound: SciPy / that, the ratio a")
    print("  supervisor with no Python cost at all would reach on the same CVODE steps")


def print_sweep(s: dict) -> None:
    print(f"bifurcation-omega sweep: {s['points']} values x {s['periods_per_point']} periods on "
          f"{s['workers']} cores: {s['wall_s']:.1f} s")  # fmt: skip


def print_long_runs(rows: list[dict]) -> None:
    print(f"{'case':<12}{'periods':>9}{'wall (s)':>10}{'events':>10}{'peak RSS (MB)':>15}"
          f"{'energy residual (J)':>21}{'relative':>10}")  # fmt: skip
    for row in rows:
        print(f"{row['case']:<12}{row['periods']:>9}{row['wall_s']:>10.1f}{row['events']:>10}{row['peak_rss_mb']:>15.1f}"
              f"{row['energy_residual']:>21.2e}{row.get('relative_residual', float('nan')):>10.1e}"
              + (f"  failed: {row['error']}" if "error" in row else ""))  # fmt: skip


def print_floor(floor: dict) -> None:
    print(f"scikit-sundae floor: {floor['us_per_call']:.2f} us per CVODE step of a 2-equation problem with a "
          f"Python right-hand side ({floor['rhs_calls']} calls)")  # fmt: skip


def engines(periods: int, repeats: int = 5) -> list[dict]:
    """Milliseconds per forcing period of each engine, interleaved repeats, medians."""
    rows = []
    for omega in (1.6, 1.85):
        case = resolve_case("instance-1", Omega=omega)
        t_end = case.initial.t0 + periods * case.parameters.period
        walls: dict[str, list[float]] = {"cvode": [], "sksundae": [], "scipy": []}
        for _ in range(repeats):
            for name in walls:
                started = time.perf_counter()
                simulate(case, t_end=t_end, record_trajectory=False, engine=name)
                walls[name].append(time.perf_counter() - started)
        row = {"omega": omega, "periods": periods}
        row |= {name: 1e3 * float(np.median(w)) / periods for name, w in walls.items()}
        say(f"Omega = {omega}: " + ", ".join(f"{k} {row[k]:.2f} ms/period" for k in walls))
        rows.append(row)
    return rows


def per_root(periods: int, repeats: int = 7) -> dict:
    """Python work per root return outside the engine, measured by replaying a run.

    A run of Instance 1 records every return of the C engine; the same run is then replayed by
    an engine that hands back those returns without integrating, so that the supervisor takes
    the same decisions and everything timed is the supervisor's loop, the switching rules, the
    guards and the event log (the least disturbed of the repeats: the machine is shared).
    """
    import oscillator.hybrid.supervisor as supervisor
    from oscillator.engines import Step
    from oscillator.engines.cvode_c import CCvodeEngine
    from oscillator.io.tables import events_frame

    case = resolve_case("instance-1", Omega=1.6)
    t_end = case.initial.t0 + periods * case.parameters.period
    returns: list[Step] = []

    class Recorded(CCvodeEngine):
        def advance(self, *args, **kwargs):
            step = super().advance(*args, **kwargs)
            returns.append(Step(step.t, step.y.copy(), step.kind, step.roots))
            return step

    real = simulate(case, t_end=t_end, record_trajectory=False, engine=Recorded)

    class Replay:
        name, rhs_evaluations, restarts = "replay", 0, 0

        def __init__(self, *_):
            self.returns = iter(returns)

        def reset(self, mode, t, y):
            pass

        def advance(self, target, *, t_stop, one_step):
            step = next(self.returns)
            return Step(step.t, step.y.copy(), step.kind, step.roots)

        def close(self):
            pass

    spent = {"resolve": 0.0}
    resolve = supervisor.resolve_rows

    def timed_resolve(*args, **kwargs):
        started = time.perf_counter()
        try:
            return resolve(*args, **kwargs)
        finally:
            spent["resolve"] += time.perf_counter() - started

    samples = []
    for _ in range(repeats):
        started = time.perf_counter()
        replayed = simulate(case, t_end=t_end, record_trajectory=False, engine=Replay)
        samples.append(time.perf_counter() - started)
    supervisor.resolve_rows = timed_resolve
    try:
        resolving = min(_resolve_time(case, t_end, Replay, spent) for _ in range(repeats))
    finally:
        supervisor.resolve_rows = resolve
    assert replayed.events.equals(real.events), "the replay must take the run's decisions"
    roots, wall = real.stats.root_returns, real.stats.wall_time
    rows = _event_records(case, t_end)
    table_wall, _ = best_of(5, lambda: events_frame(rows))
    row = {"periods": periods, "root_returns": roots, "wall_ms_per_period": 1e3 * wall / periods,
           "us_per_root_outside_engine": 1e6 * min(samples) / roots, "us_per_root_in_resolve": 1e6 * resolving / roots,
           "events": len(rows), "us_per_event_table_row": 1e6 * table_wall / max(len(rows), 1)}  # fmt: skip
    say(f"{row['us_per_root_outside_engine']:.1f} us per root return outside the engine "
        f"({row['us_per_root_in_resolve']:.1f} us in resolve_rows); "
        f"event table {row['us_per_event_table_row']:.2f} us/row")  # fmt: skip
    return row


def _resolve_time(case, t_end, engine, spent) -> float:
    spent["resolve"] = 0.0
    simulate(case, t_end=t_end, record_trajectory=False, engine=engine)
    return spent["resolve"]


def _event_records(case, t_end):
    """The run's events as the supervisor records them (event rows), for timing the table build."""
    from oscillator.engines import build_engine
    from oscillator.hybrid.record import RunRecord
    from oscillator.hybrid.recording import SaveAt, recording
    from oscillator.hybrid.supervisor import Supervisor

    p, options = case.parameters, case.options
    policy = recording(SaveAt(steps=False), max_rows=options.max_trajectory_rows, period=p.period)
    record = RunRecord()
    Supervisor(p, options, build_engine(None, p, options), policy).run(case.initial.t0, case.initial.y, t_end, record)
    return record.events.rows


STARTUP_CHILD = (
    "import time; t = time.perf_counter(); from oscillator import simulate; "
    "simulate('instance-1', t_end=2.0); print(time.perf_counter() - t)"
)


def startup() -> dict:
    """Seconds to import and run a short case in a fresh process: numba's cache empty, then filled;
    and the README's first command (`oscillator run instance-3`, without figures) likewise, whose
    first run compiles with a second process beside it and a progress bar."""
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        runs = [subprocess.run([sys.executable, "-c", STARTUP_CHILD], env=env, capture_output=True, text=True,
                               check=True) for _ in range(3)]  # fmt: skip
    cold, *warm = (float(r.stdout.strip().splitlines()[-1]) for r in runs)
    command = [sys.executable, "-m", "oscillator", "run", "instance-3", "--no-plots", "--no-report", "--quiet"]
    walls = []
    with tempfile.TemporaryDirectory() as folder:
        env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(folder) / "cache")}
        for i in range(2):
            started = time.perf_counter()
            subprocess.run([*command, "--out", str(Path(folder) / f"run-{i}")], env=env, check=True,
                           capture_output=True)  # fmt: skip
            walls.append(time.perf_counter() - started)
    row = {"cold_s": cold, "warm_s": min(warm), "cli_cold_s": walls[0], "cli_warm_s": walls[1]}
    row |= _refusals()
    say(
        f"simulate(): first run after an install {cold:.1f} s, later runs {row['warm_s']:.1f} s; "
        f"`oscillator run instance-3`: {walls[0]:.1f} s, then {walls[1]:.1f} s"
    )
    return row


def _refusals() -> dict:
    """The command's start where nothing is computed, the least of 5 fresh processes each:
    ``oscillator --help``, and ``oscillator run`` refusing a malformed case file."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        broken = Path(folder) / "broken.toml"
        broken.write_text("[parameters]\nm1 = = 2\n", encoding="utf-8")
        row = {}
        for key, arguments, code in (("cli_help_s", ["--help"], 0), ("cli_refusal_s", ["run", str(broken)], 2)):
            walls = []
            for _ in range(5):
                started = time.perf_counter()
                done = subprocess.run([sys.executable, "-m", "oscillator", *arguments], capture_output=True, cwd=folder)
                walls.append(time.perf_counter() - started)
                assert done.returncode == code, (arguments, done.returncode, done.stderr)
            row[key] = min(walls)
    return row


def print_engines(rows: list[dict]) -> None:
    print(f"engines, ms per forcing period (medians), {rows[0]['periods']} periods, trajectory off:")
    print(f"{'Omega':<8}{'cvode (C)':>11}{'sksundae':>10}{'scipy':>8}{'sksundae/cvode':>16}")
    for row in rows:
        print(f"{row['omega']:<8}{row['cvode']:>11.2f}{row['sksundae']:>10.2f}{row['scipy']:>8.2f}"
              f"{row['sksundae'] / row['cvode']:>16.1f}")  # fmt: skip


def print_per_root(row: dict) -> None:
    print(f"Instance 1 at Omega = 1.6, {row['periods']} periods, {row['root_returns']} root returns "
          f"({row['wall_ms_per_period']:.2f} ms/period): {row['us_per_root_outside_engine']:.1f} us per root return "
          f"outside the engine ({row['us_per_root_in_resolve']:.1f} us in resolving.resolve_rows); event table "
          f"{row['us_per_event_table_row']:.2f} us per row")  # fmt: skip


def print_startup(row: dict) -> None:
    print(f"start-up (import + a 2 s run, fresh process): {row['cold_s']:.1f} s with numba's cache empty, "
          f"{row['warm_s']:.1f} s with it filled; `oscillator run instance-3 --no-plots`: {row['cli_cold_s']:.1f} s "
          f"with it empty (the first run after an install), {row['cli_warm_s']:.1f} s with it filled; "
          f"`oscillator --help` {row['cli_help_s']:.2f} s, `oscillator run` refusing a malformed case file "
          f"{row['cli_refusal_s']:.2f} s")  # fmt: skip


def orbits(quick: bool) -> dict:
    """Costs of the periodic-orbit tools (medians of repeats; continuation once)."""
    from functools import partial
    from statistics import median

    from oscillator import continue_orbit, find_orbit
    from oscillator.orbits.shooting import orbit_case, period_map

    row: dict = {"maps": []}
    repeats = 3 if quick else 15
    for omega in (1.6, 1.85):
        orbit = find_orbit("instance-1", Omega=omega)
        case = orbit_case("instance-1", {"Omega": omega})
        plain_map = partial(period_map, case, orbit.section, orbit.state, derivative=False)
        full_map = partial(period_map, case, orbit.section, orbit.state)
        plain = median(best_of(1, plain_map)[0] for _ in range(repeats))
        full = median(best_of(1, full_map)[0] for _ in range(repeats))
        newton_wall, again = best_of(1, partial(find_orbit, case, guess=orbit.state + 1e-4))
        transient_wall, _ = best_of(1, partial(find_orbit, "instance-1", Omega=omega))
        entry = {"omega": omega, "switches": len(orbit.events), "map_s": plain, "map_with_monodromy_s": full,
                 "newton_steps": again.iterations, "newton_s_per_step": newton_wall / max(again.iterations, 1),
                 "find_orbit_from_transient_s": transient_wall}  # fmt: skip
        say(f"Omega = {omega}: map {plain * 1e3:.1f} ms, with monodromy {full * 1e3:.1f} ms, "
            f"Newton {entry['newton_s_per_step'] * 1e3:.1f} ms/step, find_orbit {transient_wall:.2f} s")  # fmt: skip
        row["maps"].append(entry)
    branches = [("Q2", 71.5, 70.5), ("Omega", 1.59, 1.62)] if not quick else [("Q2", 71.3, 71.1)]
    row["branches"] = []
    for param, start, stop in branches:
        wall, branch = best_of(1, partial(continue_orbit, "instance-1", param=param, start=start, stop=stop))
        points = len(branch.points)
        entry = {"param": param, "start": start, "stop": stop, "points": points,
                 "bifurcations": len(branch.bifurcations), "wall_s": wall, "s_per_point": wall / points}  # fmt: skip
        say(f"{param} {start} -> {stop}: {points} points, {entry['bifurcations']} bifurcation(s), {wall:.1f} s")
        row["branches"].append(entry)
    case = resolve_case("instance-1")
    t0, period = case.initial.t0, case.parameters.period
    sweep_point, _ = best_of(1, lambda: simulate(case, t_end=t0 + 150 * period, record_trajectory=False))
    row["sweep_point_s"] = sweep_point
    return row


def print_orbits(row: dict) -> None:
    print(f"{'Omega':<7}{'switches':>9}{'map ms':>8}{'+monodromy ms':>15}{'Newton ms/step':>16}{'find_orbit s':>14}")
    for m in row["maps"]:
        print(f"{m['omega']:<7}{m['switches']:>9}{m['map_s'] * 1e3:>8.1f}{m['map_with_monodromy_s'] * 1e3:>15.1f}"
              f"{m['newton_s_per_step'] * 1e3:>16.1f}{m['find_orbit_from_transient_s']:>14.2f}")  # fmt: skip
    for b in row["branches"]:
        print(f"continuation in {b['param']} {b['start']} -> {b['stop']}: {b['points']} points, "
              f"{b['bifurcations']} bifurcation(s) located, {b['wall_s']:.1f} s, {b['s_per_point'] * 1e3:.0f} ms "
              f"per point")  # fmt: skip
    print(f"a sweep's point (150 periods simulated, Instance 1): {row['sweep_point_s'] * 1e3:.0f} ms")


SECTIONS = ("instances", "throughput", "baseline", "sweep", "memory", "soak", "floor", "engines", "per_root", "startup",
            "orbits")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--memory-periods", type=int, default=None)
    parser.add_argument("--soak-periods", type=int, default=None)
    parser.add_argument("--only", choices=SECTIONS, nargs="+", default=None, help="run only these sections")
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    args = parser.parse_args()
    long_run = args.memory_periods or (500 if args.quick else 100_000)
    soak = args.soak_periods or (500 if args.quick else 100_000)
    quick = args.quick
    wanted = set(args.only or SECTIONS)
    simulate("instance-1")  # compile the kernels (numba caches them on disk) before timing

    machine = {"platform": platform.platform(), "python": platform.python_version(), "cores": os.cpu_count()}
    print(f"machine: {machine['platform']}, {machine['cores']} cores")
    measure = {
        "instances": (instances, print_instances),
        "throughput": (lambda: [throughput(omega, 20 if quick else 200) for omega in (1.6, 1.85)], print_throughput),
        "baseline": (
            lambda: [accuracy_and_baseline(omega, 4 if quick else WINDOW) for omega in (1.6, 1.85)],
            print_baseline,
        ),
        "sweep": (lambda: sweep(5 if quick else None), print_sweep),
        "memory": (lambda: [memory(long_run // 10), memory(long_run)], print_long_runs),
        "soak": (
            lambda: [memory(n, name) for name in ("instance-3", "instance-5") for n in (soak // 10, soak)],
            print_long_runs,
        ),
        "floor": (callback_floor, print_floor),
        "engines": (lambda: engines(5 if quick else 30), print_engines),
        "per_root": (lambda: per_root(5 if quick else 300), print_per_root),
        "startup": (startup, print_startup),
        "orbits": (lambda: orbits(quick), print_orbits),
    }
    results = {"machine": machine}
    for section in SECTIONS:
        if section in wanted:
            compute, show = measure[section]
            print(f"\n[{section}]", flush=True)
            results[section] = compute()
            show(results[section])
    args.json.write_text(json.dumps(results, indent=2, default=float) + "\n", encoding="utf-8")
    print(f"\nwritten to {args.json}")


if __name__ == "__main__":
    main()
