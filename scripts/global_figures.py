"""Run the commands docs/attractors.md and docs/atlas.md show, and copy their figures into
docs/images/, printing what each took and what it found (the numbers the pages quote).

Usage: python scripts/global_figures.py [--only NAME ...]   (about 12 minutes on 2 cores)
"""

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

IMAGES = Path(__file__).resolve().parents[1] / "docs" / "images"
UEDA = ("--set m1=1 --set K1=0 --set K2=1 --set C1=0.05 --set C2=0 --set Q1=7.5 --set Omega=1 --set mu_k=0.005 "
        "--set mu_s=0.01 --set P1=0 --set P2=0 --set Q2=0 --set x2=0 --set v2=0 --set d=1000 --set d1=1000 "
        "--set x1=2.5 --set v1=0 --set t0=0").split()  # fmt: skip
CURVE = "--kind sliding --at Omega=1.6,Q2=71.1577416".split()
#: name -> (the command's arguments after `oscillator`, with {out} for its folder; figure -> image).
JOBS = {
    "basins": ("basins instance-1 --set Q2=71.165 --x x2 2 7 30 --y v2 -5 5 30 --transient 100 --record 16".split(),
               {"basins": "attractors-basins-q2-71.165"}),
    "ueda-basins": (["basins", "instance-1", *UEDA, *"--x x1 -3 3 30 --y v1 -6 6 30".split()],
                    {"basins": "attractors-basins-ueda"}),
    "attractors": ("attractors instance-1 --param Q2 --from 71.10 --to 71.20 --steps 11 --x x2 2 7 5 --y v2 -5 5 5"
                   .split(), {"attractors": "attractors-over-q2"}),
    "lyapunov": (["lyapunov", "instance-1", *UEDA, "--periods", "1500"], {"lyapunov": "lyapunov-ueda-friction"}),
    "atlas": ("atlas instance-1 --x Omega 1.3 1.85 80 --y Q2 68.5 72 60".split(),
              {"atlas": "atlas-omega-q2", "atlas-lyapunov": "atlas-omega-q2-lyapunov"}),
    "curve": (["curve", "instance-1", *CURVE, *"--x Omega 1.59 1.62 --y Q2 70.9 71.3".split()],
              {"curve": "curve-sliding"}),
    "atlas-band": ("atlas instance-1 --x Omega 1.585 1.62 36 --y Q2 70.6 71.4 24".split(), {}),
    "curve-band": (["curve", "instance-1", *CURVE, *"--x Omega 1.585 1.62 --y Q2 70.6 71.4".split(),
                    "--over", "{atlas-band}"], {"curve": "curve-over-atlas"}),
}  # fmt: skip


def found(folder: Path) -> str:
    """What a folder holds, in a few words (the numbers the pages quote)."""
    if (folder / "curve.parquet").exists():
        ends = json.loads((folder / "curve.json").read_text(encoding="utf-8"))["ends"]
        return f"{len(pd.read_parquet(folder / 'curve.parquet'))} points; ends: {'; '.join(ends)}"
    if (folder / "lyapunov.json").exists():
        return "exponents " + ", ".join(map(str, json.loads((folder / "lyapunov.json").read_text())["exponents"]))
    if (folder / "atlas.parquet").exists():
        table = pd.read_parquet(folder / "atlas.parquet")
        first = table[table.attractor <= 0]
        shares = (first.regime.value_counts(normalize=True) * 100).round(1).to_dict()
        return f"regimes (% of points) {shares}; coexisting at {int((first.coexisting > 1).sum())} points"
    table = pd.read_parquet(folder / "attractors.parquet")
    return "; ".join(f"{row.name} {row.fraction:.1%}" for row in table.itertuples(index=False))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", choices=sorted(JOBS), help="run these only (and what they need)")
    chosen = parser.parse_args().only or list(JOBS)
    IMAGES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        folders = {name: Path(scratch) / name for name in JOBS}
        for name, (arguments, figures) in JOBS.items():
            if name not in chosen and not any(f"{{{name}}}" in " ".join(JOBS[c][0]) for c in chosen):
                continue
            command = [a.format(**{k: str(v) for k, v in folders.items()}) for a in arguments]
            started = time.perf_counter()
            subprocess.run([sys.executable, "-m", "oscillator", *command, "--out", str(folders[name])], check=True,
                           stdout=subprocess.DEVNULL)  # fmt: skip
            print(f"{name}: {time.perf_counter() - started:.1f} s; {found(folders[name])}", flush=True)
            for figure, image in figures.items():
                shutil.copy(folders[name] / "figures" / f"{figure}.png", IMAGES / f"{image}.png")
                print(f"  wrote {IMAGES / f'{image}.png'}", flush=True)


if __name__ == "__main__":
    main()
