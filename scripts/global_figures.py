"""Run the commands docs/attractors.md, docs/atlas.md, docs/frequency.md and docs/design.md show
(and the frequency page's two Python examples), and copy their figures into docs/images/,
printing what each took and what it found (the numbers the pages quote).

Usage: python scripts/global_figures.py [--only NAME ...]   (about 17 minutes on 2 cores)
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
DESIGN = ("--vary d1=2.5,4.5 --vary K6=1,40 --over Omega 1.4 1.6 --objective x_max_m1 --band 3 --starts 2 "
          "--transient 100 --record 8").split()  # fmt: skip
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
    "frc": ("frc instance-1 --param Omega 1.3 1.85".split(), {"frequency-x-pp": "frequency-instance-1"}),
    "frc-window": ("frc instance-1 --set Q2=71.165 --param Omega 1.5999 1.6001 --starts 16".split(),
                   {"frequency-x-pp": "frequency-window"}),
    "frc-impacts": ("frc instance-1 --set d=1 --set d1=3.5 --param Omega 1.3 1.85".split(),
                    {"frequency-impact-max": "frequency-impacts"}),
    "design": (["design", "instance-1", *DESIGN, "--constraint", "impact_max_right <= 5", "--constraint",
                "rest_m2 <= 0.01", "--candidates", "8"],
               {"design-search": "design-search", "design-response": "design-response"}),
    "design-front": (["design", "instance-1", *DESIGN, "--objective", "impact_max_right", "--candidates", "8",
                      "--front", "9"], {"design-front": "design-front"}),
}  # fmt: skip
#: The frequency page's Python examples: name -> (the block's heading on the page, the image).
EXAMPLES = {"duffing": ("A hardening Duffing oscillator", "frequency-duffing"),
            "doubling": ("**A period doubling.**", "frequency-doubling")}  # fmt: skip


def found(folder: Path) -> str:
    """What a folder holds, in a few words (the numbers the pages quote)."""
    if (folder / "best.json").exists():
        best = json.loads((folder / "best.json").read_text(encoding="utf-8"))
        return f"design {best['design']}, worst {best['objective']}, runs {best['runs']}"
    if (folder / "frc.json").exists():
        sweeps = pd.read_parquet(folder / "sweeps.parquet")
        bifurcations = pd.read_parquet(folder / "bifurcations.parquet")
        jumps = {d: sweeps[(sweeps.direction == d) & sweeps.jump].iloc[:, 1].round(6).tolist() for d in ("up", "down")}
        kinds = bifurcations.iloc[:, :3].round(7).values.tolist()
        return f"{len(pd.read_parquet(folder / 'points.parquet'))} points; jumps {jumps}; bifurcations {kinds}"
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


def example(name: str) -> None:
    """Run one of the frequency page's Python examples as shown, and save its figure."""
    import oscillator as osc

    heading, image = EXAMPLES[name]
    page = (IMAGES.parent / "frequency.md").read_text(encoding="utf-8")
    block = page.split(heading, 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    code = "\n".join(line[2:] if line.startswith("  ") else line for line in block.splitlines())
    scope = {"osc": osc}
    started = time.perf_counter()
    exec(compile(code, "docs/frequency.md", "exec"), scope)
    result = scope["found"]
    folds, jumps = result.folds.Omega.round(5).tolist(), (result.jumps("up"), result.jumps("down"))
    print(f"{name}: {time.perf_counter() - started:.1f} s; {len(result.points)} points; folds {folds}; jumps {jumps}")
    result.plot("x_pp").savefig(IMAGES / f"{image}.png", dpi=110)
    print(f"  wrote {IMAGES / f'{image}.png'}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", choices=sorted([*JOBS, *EXAMPLES]), help="run these only")
    chosen = parser.parse_args().only or [*JOBS, *EXAMPLES]
    for name in EXAMPLES:
        if name in chosen:
            example(name)
    IMAGES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        folders = {name: Path(scratch) / name for name in JOBS}
        for name, (arguments, figures) in JOBS.items():
            if name not in chosen and not any(f"{{{name}}}" in " ".join(JOBS[c][0]) for c in chosen if c in JOBS):
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
