"""Behaviour unchanged by the architecture of issues 12 and 26: the same events, trajectories, energy
audits and sweep tables as before, by value to 1e-12.

``tests/data/unchanged/`` holds the outputs of commit ba6ba92 (the flat package, itself checked
against the independent implementation), made by ``tests/data/unchanged/make.py``.  Solver counts
are not compared: a new toolchain (numba, LLVM, SUNDIALS) may take other steps to the same
values, and the values are what a user reads.
"""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import random_case
from oscillator import SweepSettings, case_names, load_case, simulate
from oscillator.analysis.sweep_points import run_point

DATA = Path(__file__).parent / "data" / "unchanged"
AUDIT = json.loads((DATA / "audit.json").read_text())
#: By value: numbers to 1e-12 (relative, and absolute near zero), text and integers exactly.
SAME = {"check_exact": False, "rtol": 1e-12, "atol": 1e-12}


def runs():
    for name in case_names():
        yield name, lambda name=name: simulate(name, t_end=40.0) if name.startswith("bifurcation") else simulate(name)
    for seed in (1, 145, 200):
        yield f"random-{seed}", lambda seed=seed: simulate(random_case(seed))
    yield "instance-1-grid", lambda: simulate("instance-1", t_end=20.0, t_eval=np.linspace(1, 20, 191))
    yield "instance-1-keep", lambda: simulate("instance-1", t_end=60.0, record_trajectory=False, keep_events_from=30.0)


@pytest.mark.parametrize(("name", "run"), list(runs()), ids=[name for name, _ in runs()])
def test_the_same_run_as_before(name, run):
    result = run()
    before = pd.read_parquet(DATA / f"{name}.events.parquet")
    pd.testing.assert_frame_equal(result.events[before.columns], before, **SAME)
    pd.testing.assert_frame_equal(result.trajectory, pd.read_parquet(DATA / f"{name}.trajectory.parquet"), **SAME)
    audit = AUDIT[name]
    energy = dataclasses.asdict(result.energy)
    scale = max(abs(audit["energy"]["E0"]), abs(audit["energy"]["E1"]), 1.0)
    for key, value in audit["energy"].items():  # the residual is a difference of the others: to their scale
        assert energy[key] == pytest.approx(value, rel=1e-12, abs=1e-12 * scale), key
    assert list(result.final_state) == pytest.approx(audit["final_state"], rel=1e-12, abs=1e-12)
    assert result.stats.events == audit["stats"].get("events", result.stats.events)


def test_the_same_sweep_tables_as_before():
    case = load_case("bifurcation-omega")
    settings = SweepSettings(param="Omega", start=1.59, stop=1.62, steps=4, transient=30, record=10)
    points = [run_point(case, settings, i, v) for i, v in enumerate([1.59, 1.6, 1.605, 1.62])]
    for table in ("summary", "poincare", "switches"):
        now = pd.concat([getattr(p, table) for p in points], ignore_index=True)
        before = pd.read_parquet(DATA / f"sweep.{table}.parquet")  # columns added since are not compared
        pd.testing.assert_frame_equal(now[before.columns], before, **SAME)
