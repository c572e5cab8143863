"""``python -m oscillator CASE [--t-end T]``: run a case and print its switching events.

A named case (``instance-1`` ... ``instance-5``) or a case file.  Prints the event table, the
comparison with the article's times where the case has them, and the energy audit.  Exit code
0 on success, 1 when an expected time is outside its tolerance, 2 on bad input or a solver
failure (one line, no traceback).
"""

from __future__ import annotations

import argparse
import sys

from oscillator import OscillatorError, case_names, load_case, simulate
from oscillator.reproduction import compare

_COLUMNS = ["t", "mass", "kind", "boundary", "from_domain", "to_domain", "theorem", "equation"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m oscillator",
        description="Simulate a case of the 2-DOF frictional oscillator and print its switching events.",
        epilog=f"named cases: {', '.join(case_names())}",
    )
    parser.add_argument("case", help="a named case or the path of a case file (.toml)")
    parser.add_argument("--t-end", type=float, default=None, help="end time in s (default: the case's)")
    args = parser.parse_args(argv)
    try:
        case = load_case(args.case)
        result = simulate(case, t_end=args.t_end)
    except OscillatorError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(f"{case.name}: {case.title}")
    print(f"t0 = {case.initial.t0} s to t_end = {result.final_state[0]} s\n")
    events = result.events[_COLUMNS]
    print(events.to_string(index=False, float_format=lambda v: f"{v:.6f}") if len(events) else "no switching events")
    energy = result.energy
    print(
        f"\nenergy audit: E0 = {energy['E0']:.6f} J, E1 = {energy['E1']:.6f} J, residual = {energy['residual']:.2e} J"
    )
    if not case.expected:
        return 0
    table = compare(case, result)
    print("\ncomparison with the article (and the independent reference):")
    shown = table[["label", "article", "reference", "ours", "within_article", "within_reference"]]
    print(shown.to_string(index=False, float_format=lambda v: f"{v:.4f}"))
    ok = bool((table.within_article & table.within_reference).all())
    print("all expected times within tolerance" if ok else "SOME EXPECTED TIMES ARE OUT OF TOLERANCE")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
