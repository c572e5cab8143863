"""The engines on Instance 1's system, every figure of a line from one run: throughput per core of
CVODE and of DOP853 through ``simulate`` (trajectory off), of a start landed whole in compiled
code (``hybrid.batch.land_compiled``), their event accuracy against a tight reference, and
landings per second through ``land`` with each engine (the same labels asserted).

Usage: python benchmarks/engines.py [--periods N] [--starts N] [--repeats N]
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from run import best_of

import oscillator as osc
from oscillator.attractors.mapping import WINDOW_ROWS, AttractorSettings, land
from oscillator.engines.dop853 import EVALS, new_work
from oscillator.hybrid.batch import OK, land_compiled, options_vector
from oscillator.hybrid.recording import SaveAt
from oscillator.model.events import WIDTH
from oscillator.model.fields import coefficients


def simulated(case, engine, periods, repeats):
    t_end = periods * case.parameters.period
    return best_of(repeats, lambda: osc.simulate(case, t_end=t_end, engine=engine, save=SaveAt(steps=False)))


def compiled(case, periods, repeats):
    """One start landed whole in compiled code over ``periods`` periods (no settling): the time,
    and the field's evaluations a period."""
    p, o = case.parameters, case.options
    work = new_work(p, o)

    def run():
        work[:] = new_work(p, o)
        points, rows = np.empty((3, 6)), np.empty((WINDOW_ROWS * 3, WIDTH))
        settings = (False, periods - 2, 2, 1e-6, 1)
        status, _, _ = land_compiled(
            coefficients(p), 0.0, p.period, np.array(case.initial.y), work, options_vector(o), settings, points, rows
        )
        assert status == OK
        return work[EVALS] / periods

    run()
    return best_of(repeats, run)


def event_error(case, engine, periods):
    t_end = periods * case.parameters.period
    reference = osc.simulate(case, t_end=t_end, rtol=1e-13, atol=1e-13, save=SaveAt(steps=False)).events
    events = osc.simulate(case, t_end=t_end, engine=engine, save=SaveAt(steps=False)).events
    assert events[["mass", "kind", "to_domain"]].equals(reference[["mass", "kind", "to_domain"]])
    return float(np.max(np.abs(events.t.to_numpy() - reference.t.to_numpy())))


def throughput(periods, repeats):
    print(f"Instance 1's system, {periods} forcing periods, one core, best of {repeats} (trajectory off)")
    header = "| Omega | cvode (ms/period) | dop853 via simulate | compiled landing | compiled vs cvode |"
    print(header + " events/period | event error cvode | event error dop853 |")
    for omega in (1.6, 1.85):
        case = osc.resolve_case("instance-1", Omega=omega)
        for engine in ("cvode", "dop853"):
            simulated(case, engine, 5, 1)  # compiled and loaded
        t_cvode, result = simulated(case, "cvode", periods, repeats)
        t_dop, _ = simulated(case, "dop853", periods, repeats)
        t_compiled, evaluations = compiled(case, periods, repeats)
        errors = [event_error(case, engine, 30) for engine in ("cvode", "dop853")]
        per = [1e3 * t / periods for t in (t_cvode, t_dop, t_compiled)]
        print(
            f"| {omega} | {per[0]:.3f} | {per[1]:.3f} | {per[2]:.4f} ({periods / t_compiled:,.0f} periods/s, "
            f"{evaluations:.0f} field calls/period) | **{t_cvode / t_compiled:.1f}x** | "
            f"{len(result.events) / periods:.1f} | {errors[0]:.1e} | {errors[1]:.1e} |"
        )


def landings(count, repeats):
    case = osc.resolve_case("instance-1", Q2=71.165)
    rng = np.random.default_rng(1)
    starts = np.column_stack(
        [np.full(count, 3.0), np.zeros(count), rng.uniform(2, 7, count), rng.uniform(-5, 5, count)]
    )
    print(f"\nlandings through land(), {count} random starts of the basins' slice (Q2 = 71.165, 100 + 16 periods)")
    print("| transient | cvode (starts/s) | dop853 (starts/s) | ratio | the same landings |")
    for settle in (True, False):
        compiled_settings = AttractorSettings(transient=100, record=16, settle=settle)
        reference = dataclasses.replace(compiled_settings, engine="cvode")
        timing = {}
        for settings in (reference, compiled_settings):
            land(case, settings, 0, starts[0])
            timing[settings.engine] = best_of(
                repeats, lambda s=settings: [land(case, s, i, x) for i, x in enumerate(starts)]
            )
        (t_ref, a), (t_new, b) = timing["cvode"], timing["dop853"]
        same = all(
            (x.period, x.signature, x.rests, x.contacts, x.transient)
            == (y.period, y.signature, y.rests, y.contacts, y.transient)
            for x, y in zip(a, b, strict=True)
        )
        print(
            f"| {'settled' if settle else 'whole'} | {count / t_ref:.1f} | {count / t_new:.1f} | "
            f"**{t_ref / t_new:.1f}x** | {same} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=400)
    parser.add_argument("--starts", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    options = parser.parse_args()
    throughput(options.periods, options.repeats)
    landings(options.starts, options.repeats)


if __name__ == "__main__":
    main()
