"""Regenerate docs/bifurcation.md's numbers and figures from one run of the two Section 7 sweeps.

Usage: python scripts/bifurcation.py [--workers N] [--out DIR]

Runs the sweeps bifurcation-omega and bifurcation-q2 (111 values x 150 forcing periods each) on
every core, then locates, to 1e-8 in the parameter, every change that the sweeps' summaries show
between neighbouring values: where sliding starts or stops (``sliding``), where the number of
switches per period changes while sliding does not (``grazing``), and where the period changes
(``period``). It writes the diagrams to docs/images/ and, in docs/bifurcation.md, replaces the
text between each ``<!-- generated: NAME -->`` and ``<!-- end -->`` with the tables and figures of
this run. Prints its progress; takes about ten minutes on two cores.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import itertools
import multiprocessing
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

from oscillator import load_case
from oscillator.analysis.locate import locate
from oscillator.analysis.sweeps import read_sweep, run_sweep
from oscillator.report.markup import Table, to_markdown
from oscillator.report.sweep_figures import write_sweep_figures

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "bifurcation.md"
IMAGES = ROOT / "docs" / "images"
SCENES = ("bifurcation-omega", "bifurcation-q2")
INDICATORS = (("sliding", "sliding"), ("period", "period"), ("grazing", "switches_per_period"))


def say(text: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {text}", flush=True)


def changes(summary, param: str) -> list[tuple[str, float, float]]:
    """The neighbouring values between which an indicator changes: (what, a, b), one per pair.

    A change of sliding is located as such; otherwise a change of the period; otherwise a change
    of the switches per period (a pair of crossings appears or disappears: grazing).
    """
    ok = summary[summary.status == "ok"].sort_values(param)
    found = []
    rows = list(ok.itertuples(index=False))
    for below, above in itertools.pairwise(rows):
        for what, column in INDICATORS:
            if getattr(below, column) != getattr(above, column):
                found.append((what, getattr(below, param), getattr(above, param)))
                break
    return found


def locate_one(name: str, what: str, a: float, b: float):
    case = load_case(name)
    settings = case.sweep
    started = time.perf_counter()
    found = locate(case, settings, what, (a, b), tolerance=1e-8)
    return name, what, found, time.perf_counter() - started


def ranges_table(summary, param: str) -> Table:
    """Consecutive values with the same sliding, period and switches per period."""
    ok = summary[summary.status == "ok"].sort_values(param)
    rows, group = [], []
    key = None
    for row in ok.itertuples(index=False):
        this = (bool(row.sliding), int(row.period), float(row.switches_per_period))
        if key is not None and this != key:
            rows.append(_range_row(group, param, key))
            group = []
        key = this
        group.append(row)
    if group:
        rows.append(_range_row(group, param, key))
    header = (f"{param} from", "to", "values", "m2 rests", "period", "switches / period", "rest time / period (s)")
    return Table(header, tuple(rows))


def _range_row(group, param, key) -> tuple[str, ...]:
    sliding, period, switches = key
    rest = [row.rest_time_per_period for row in group]
    rests = f"{min(rest):.3g} - {max(rest):.3g}" if sliding else "0"
    return (f"{getattr(group[0], param):.6g}", f"{getattr(group[-1], param):.6g}", str(len(group)),
            "yes" if sliding else "no", str(period) if period else "none", f"{switches:g}", rests)  # fmt: skip


def changes_table(located, param: str) -> Table:
    rows = []
    for _, what, found, wall in sorted(located, key=lambda item: item[2].value):
        below, above = found.below.iloc[0], found.above.iloc[0]
        column = dict(INDICATORS)[what]
        shown = {True: "rests", False: "never rests"} if what == "sliding" else {}
        change = f"{shown.get(below[column], f'{below[column]:g}')} → {shown.get(above[column], f'{above[column]:g}')}"
        rows.append((f"{found.value:.10f}", what, change,
                     f"{found.width:.1e}", str(found.iterations), f"{wall:.0f}"))  # fmt: skip
    header = (param, "what changes", "below → above", "bracket width", "bisections", "wall time (s)")
    return Table(header, tuple(rows))


def replace_generated(text: str, name: str, content: str) -> str:
    pattern = re.compile(rf"(<!-- generated: {re.escape(name)} -->\n).*?(<!-- end -->)", re.S)
    if not pattern.search(text):
        raise SystemExit(f"{PAGE} has no <!-- generated: {name} --> ... <!-- end --> section")
    return pattern.sub(lambda m: m.group(1) + content + m.group(2), text)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", type=Path, default=None, help="keep the sweep folders here")
    options = parser.parse_args(argv)
    scratch = options.out or Path(tempfile.mkdtemp(prefix="bifurcation-"))
    for name in SCENES:  # one run: nothing resumed, so that the wall times are the sweeps'
        shutil.rmtree(scratch / name, ignore_errors=True)
    text = PAGE.read_text(encoding="utf-8")
    walls, to_locate, summaries = {}, [], {}
    for name in SCENES:
        case = load_case(name)
        folder = scratch / name
        say(f"{name}: sweeping {case.sweep.param} over {case.sweep.steps} values on {options.workers} workers")
        started = time.perf_counter()
        run_sweep(case, case.sweep, folder, workers=options.workers,
                  progress=lambda done, total: say(f"  {done}/{total}") if done % 20 == 0 else None)  # fmt: skip
        walls[name] = time.perf_counter() - started
        tables = read_sweep(folder)
        summaries[name] = tables["summary"]
        for path in write_sweep_figures(tables, case.sweep.param, case.sweep.mass, folder / "figures", title=name):
            if path.suffix == ".png":
                target = IMAGES / f"{name}-{path.stem.removeprefix('fig-14-').replace('bifurcation', 'fig-14')}.png"
                shutil.copy(path, target)
        to_locate += [(name, *change) for change in changes(tables["summary"], case.sweep.param)]
        say(f"{name}: {walls[name]:.1f} s; {len(changes(tables['summary'], case.sweep.param))} changes to locate")
    located = []
    context = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(options.workers, mp_context=context) as pool:
        futures = [pool.submit(locate_one, *job) for job in to_locate]
        for future in cf.as_completed(futures):
            result = future.result()
            located.append(result)
            say(f"located {result[1]} of {result[0]} at {result[2].param} = {result[2].value:.10f} "
                f"({len(located)}/{len(futures)})")  # fmt: skip
    for name in SCENES:
        param = load_case(name).sweep.param
        mine = [item for item in located if item[0] == name]
        content = to_markdown([ranges_table(summaries[name], param), changes_table(mine, param)])
        content += (f"\nThe sweep took {walls[name]:.0f} s on {options.workers} worker processes; each located "
                    f"change {min(item[3] for item in mine):.0f}-{max(item[3] for item in mine):.0f} s.\n")  # fmt: skip
        text = replace_generated(text, name, content)
    PAGE.write_text(text, encoding="utf-8")
    say(f"wrote {PAGE} and {IMAGES}/bifurcation-*.png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
