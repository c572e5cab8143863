"""Save the outputs of commit ba6ba92 (before the issue-12 move) for tests/test_unchanged.py.

Run once, with that commit installed; kept to show how the files were made.
"""

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).parents[2]))
from oscillator.sweep import run_point

from conftest import random_case
from oscillator import SweepSettings, case_names, load_case, simulate

out = Path(__file__).parent
audit = {}


def save(name, result):
    result.events.to_parquet(out / f"{name}.events.parquet")
    result.trajectory.to_parquet(out / f"{name}.trajectory.parquet")
    stats = {k: v for k, v in result.stats.items() if k != "wall_time"}
    audit[name] = {"energy": result.energy, "stats": stats, "final_state": list(result.final_state)}


for name in case_names():
    save(name, simulate(name, t_end=40.0) if name.startswith("bifurcation") else simulate(name))
for seed in (1, 145, 200):
    save(f"random-{seed}", simulate(random_case(seed)))
save("instance-1-grid", simulate("instance-1", t_end=20.0, t_eval=np.linspace(1, 20, 191)))
r = simulate("instance-1", t_end=60.0, record_trajectory=False, keep_events_from=30.0)
save("instance-1-keep", r)
case = load_case("bifurcation-omega")
settings = SweepSettings(param="Omega", start=1.59, stop=1.62, steps=4, transient=30, record=10)
rows = [run_point(case, settings, i, v) for i, v in enumerate([1.59, 1.6, 1.605, 1.62])]
summary = pd.concat([r.summary for r in rows], ignore_index=True).drop(columns=["wall_time"])
summary.to_parquet(out / "sweep.summary.parquet")
pd.concat([r.poincare for r in rows], ignore_index=True).to_parquet(out / "sweep.poincare.parquet")
pd.concat([r.switches for r in rows], ignore_index=True).to_parquet(out / "sweep.switches.parquet")
(out / "audit.json").write_text(json.dumps(audit, indent=1, sort_keys=True))
