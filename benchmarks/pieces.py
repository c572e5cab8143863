"""A smooth piece integrated again in compiled code (issue 53, oscillator/orbits/pieces.py) against
SciPy's ``solve_ivp(method="DOP853")`` with a Python right-hand side (the code before, kept here as
the baseline), the old and the new in one run, on the same computations:

1. ``response()`` of Instance 1's orbit at four frequencies over one period (min of 5);
2. the frequency response of Instance 1 over Omega in [1.3, 1.85] (``oscillator.frequency_response``
   on one worker, in this process: the library call of ``oscillator frc instance-1 --param Omega 1.3
   1.85``), and the largest difference between the two tables of points;
3. the hardening oscillator (docs/systems/hardening.toml) continued over Omega in [0.8, 1.6], its
   tangents through a cubic spring integrated on every piece, and its Lyapunov spectrum over 100
   periods;
4. a branch's measures (``branch_responses`` on 60 points of Instance 1's response from Omega = 1.79)
   with each point refined as before (``find_orbit(tol=1e-12)`` then a run of its own for the
   measures) and as now (Newton's ``floor``, the measures on its last run), the compiled pieces in
   both, and how far apart the two tables are.

The trajectory is not recorded on any of these paths (period maps and their pieces only).

Usage: python benchmarks/pieces.py
"""

from __future__ import annotations

import datetime
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

import oscillator as osc
import oscillator.orbits.chain_tangents as chain_tangents
import oscillator.orbits.response as response_module
from oscillator.model.fields import C3, K3, coefficients
from oscillator.model.kernels import rates
from oscillator.orbits.chain_branch import continue_chain_orbit
from oscillator.orbits.pieces import chain_tangent_rates
from oscillator.orbits.tangent import tangent_rates

HARDENING = Path(__file__).resolve().parents[1] / "docs" / "systems" / "hardening.toml"


def _extremum_events(c: np.ndarray, flags: tuple[int, int, bool, bool]) -> list[Callable[[float, np.ndarray], float]]:
    s1, s2, left, right = flags

    def function(which: int) -> Callable[[float, np.ndarray], float]:
        def event(t: float, y: np.ndarray) -> float:
            r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, right)
            if which == 2:
                return float(c[K3] * (y[1] - y[3]) + c[C3] * (r[1] - r[3])) if left else 1.0
            return float(r[2 * which + 1]) if (s1, s2)[which] else 1.0

        return event

    return [function(which) for which in range(3)]


def old_piece_of(cls: Any, segment: Any, p: Any) -> Any:
    """``_Piece.of`` as it was: SciPy's DOP853 with a Python field and events."""
    c, mode = coefficients(p), segment.mode
    flags = (mode.sign(1), mode.sign(2), mode.left, mode.right)
    none = np.zeros(0, dtype=np.int64)

    def field(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty_like(y)
        tangent_rates(t, y, c, none, *flags, out)
        return out

    start = np.concatenate([segment.y0, np.zeros(9)])
    span = (segment.t0, segment.t1)
    solved = solve_ivp(field, span, start, method="DOP853", rtol=1e-12, atol=1e-12, events=_extremum_events(c, flags))
    ends = [segment.y0, solved.y[:4, -1]]
    speeds = [[abs(y[2 * i - 1]) for y in [*ends, *solved.y_events[i - 1]]] for i in (1, 2)]
    forces = [abs(response_module._left_force(y, c)) for y in [*ends, *solved.y_events[2]]]
    right = [max(float(p.K6 * (y[0] - p.d1)), 0.0) for y in ends]
    return cls(
        segment,
        solved.y[4:, -1],
        (max(speeds[0]), max(speeds[1])),
        (max(right) if mode.right else 0.0, max(forces) if mode.left else 0.0),
    )


def old_along_piece(data: Any, mode: Any, span: Any, start: Any, block: Any, rtol: float) -> Any:
    """A chain's ``_along_piece`` as it was: SciPy's DOP853 with the compiled field called from Python."""
    d, plus, minus = data.of(mode)
    n, shape = len(start), block.shape

    def field(s: float, big: np.ndarray) -> np.ndarray:
        out = np.empty(len(big))
        chain_tangent_rates(s, big, d, plus, minus, data.steps, out)
        return out

    found = solve_ivp(field, span, np.concatenate([start, block.ravel()]), method="DOP853", rtol=rtol,
                      atol=rtol * chain_tangents.ATOL / chain_tangents.RTOL, dense_output=True)  # fmt: skip
    return lambda t: np.asarray(found.sol(t))[n:].reshape(shape)


def _timed(work: Callable[[], Any], repeat: int = 1) -> tuple[float, Any]:
    best, result = float("inf"), None
    for _ in range(repeat):
        started = time.perf_counter()
        result = work()
        best = min(best, time.perf_counter() - started)
    return best, result


def _both(name: str, work: Callable[[], Any], patch: Callable[[bool], None], repeat: int = 1) -> tuple[Any, Any]:
    patch(True)
    try:
        before, old = _timed(work, repeat)
    finally:
        patch(False)
    after, new = _timed(work, repeat)
    print(f"  {name:<58} before {before:8.3f} s   now {after:8.3f} s   {before / after:5.1f}x")
    return old, new


def _patch_response(old: bool, original: Any = response_module._Piece.of) -> None:
    response_module._Piece.of = classmethod(old_piece_of) if old else original  # type: ignore[method-assign]


def _patch_chain(old: bool, original: Any = chain_tangents._along_piece) -> None:
    chain_tangents._along_piece = old_along_piece if old else original


def main() -> None:
    print(f"pieces integrated again: SciPy with a Python field (before) against compiled (now); "
          f"{datetime.date.today()}, load {os.getloadavg()[0]:.2f}")  # fmt: skip
    orbits = [osc.find_orbit("instance-1", Omega=omega).one_period() for omega in (1.3, 1.5, 1.6, 1.85)]
    old, new = _both("response() of four orbits, one period each", lambda: [osc.response(o) for o in orbits],
                     _patch_response, repeat=5)  # fmt: skip
    worst = max(abs(a.columns()[k] - b.columns()[k]) for a, b in zip(old, new, strict=True) for k in a.columns())
    print(f"    largest difference of a measure: {worst:.1e}")
    frc = lambda: osc.frequency_response("instance-1", "Omega", (1.3, 1.85), workers=1)  # noqa: E731
    old, new = _both("frequency_response(instance-1, Omega 1.3..1.85), 1 worker", frc, _patch_response)
    numbers = [c for c in new.points.columns if new.points[c].dtype.kind == "f"]
    same = old.points.shape == new.points.shape
    worst = float(np.nanmax(np.abs(old.points[numbers].to_numpy() - new.points[numbers].to_numpy()))) if same else None
    print(f"    {len(new.points)} points; the same rows: {same}, largest difference {worst:.1e}")
    chain = osc.load_system(HARDENING)
    old, new = _both("continue_chain_orbit(hardening, Omega 0.8..1.6, step 0.1)",
                     lambda: continue_chain_orbit(chain, param="Omega", start=0.8, stop=1.6, step=0.1,
                                                      transient=200), _patch_chain)  # fmt: skip
    print(f"    {len(new.points)} points; largest difference of a state {_largest(old.points, new.points):.1e}")
    _both("lyapunov(hardening), 100 periods", lambda: osc.lyapunov(chain, periods=100, transient=50), _patch_chain)
    refinement()


def old_branch_responses(branch: Any) -> Any:
    """``branch_responses`` as it was: ``find_orbit`` to 1e-12 (the noise chased; unrefined where it
    fails), then ``response`` on a run of its own."""
    import pandas as pd

    rows = []
    for point in branch.points.itertuples(index=False):
        values = point._asdict()
        state = {name: float(values[name]) for name in branch.case.system.state}
        case = osc.resolve_case(branch.case, **{branch.param: float(values[branch.param])}, t0=branch.section, **state)
        try:
            case = osc.find_orbit(case, period=branch.period, guess=list(state.values()), tol=1e-12).one_period()
        except osc.OscillatorError:
            pass
        measured = osc.response(case, branch.period)
        rows.append({branch.param: values[branch.param], "stable": values["stable"], "piece": values["piece"]}
                    | measured.columns())  # fmt: skip
    return pd.DataFrame(rows)


def refinement() -> None:
    branch = osc.continue_orbit("instance-1", param="Omega", start=1.79, stop=1.85, step=0.005, max_points=60)
    timings, tables = {}, {}
    for name, work in (("before", old_branch_responses), ("now", response_module.branch_responses)):
        timings[name], tables[name] = _timed(lambda work=work: work(branch))
    print(f"  {'branch_responses, 60 points of Instance 1 from Omega 1.79':<58} before {timings['before']:8.3f} s"
          f"   now {timings['now']:8.3f} s   {timings['before'] / timings['now']:5.1f}x")  # fmt: skip
    print(f"    largest difference of a measure {_largest(tables['before'], tables['now']):.1e}")


def _largest(a: Any, b: Any) -> float:
    numbers = [c for c in b.columns if b[c].dtype.kind == "f"]
    return float(np.nanmax(np.abs(a[numbers].to_numpy() - b[numbers].to_numpy()))) if a.shape == b.shape else np.nan


if __name__ == "__main__":
    main()
