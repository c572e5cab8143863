"""Continuation of a periodic orbit in a parameter, and the bifurcations along the branch.

Pseudo-arclength continuation (Keller 1977; Allgower & Georg 2003, Ch. 2) of the zeros of
``F(y, lam) = P(y; lam) - y`` in ``u = (y, lam / sigma)`` with ``sigma = |stop - start|``:
a tangent predictor ``u + ds t`` and a Newton corrector on ``F = 0`` and ``t . (u - u_pred) = 0``.
``dF/dy = M - I`` is the monodromy matrix (:mod:`oscillator.orbits.shooting`); ``dF/dlam`` is a
central difference of the map.  The branch follows unstable parts and turns at folds.

Between two points, the branch has a bifurcation where

* the orbit's event signature changes (:func:`~oscillator.orbits.signature.cyclic_signature`): a
  rest interval appears or disappears (``sliding_onset`` / ``sliding_vanish``, named as the
  parameter increases) or a pair of other switches does (``grazing``): the map is continuous
  but not differentiable there, and its multipliers may jump;
* ``lam`` turns back (``fold``), or a multiplier leaves the unit circle at -1
  (``period_doubling``) or as a complex pair (``torus``), with the signature unchanged.

Each is located by bisection along the branch, to ``locate_tol`` in the parameter.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.engines import check_engine
from oscillator.errors import Interrupted, Reason
from oscillator.io.cases import Case
from oscillator.orbits.branch import Branch, Skipped, point_columns
from oscillator.orbits.corrector import Continuer, Located, OrbitPoint
from oscillator.orbits.locating import between, end_point, own_kind
from oscillator.orbits.settings import ContinuationSettings, check_settings
from oscillator.orbits.shooting import STATE, orbit_case, start_of
from oscillator.orbits.stroboscopic import ORBIT_ENGINE, ORBIT_ENGINES

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.chain_branch import ChainBranch

__all__ = ["ContinuationSettings", "check_settings", "continue_orbit"]


#: The branch has stalled where, over this many steps, the parameter turned back at every other
#: one or more and the steps' net advance is less than :data:`STALL_NET` of their length: the
#: corrector goes back and forth at a point it cannot step across (a contact or a rest starting
#: on an orbit whose mass rests all period: 1234 of 1315 points at one value, measured).
STALL_WINDOW = 12
STALL_NET = 0.25


def _of_chain(
    chain: FrictionChain,
    param: str,
    span: tuple[float, float],
    guess: Sequence[float] | np.ndarray | None,
    step: float | None,
    max_points: int,
    transient: int | None,
) -> ChainBranch:
    """:func:`continue_orbit` for a friction chain: its period-1 orbit's branch."""
    from oscillator.orbits.chain_branch import continue_chain_orbit

    return continue_chain_orbit(
        chain,
        param=param,
        start=span[0],
        stop=span[1],
        guess=None if guess is None else np.asarray(guess, dtype=float),
        step=0.1 if step is None else step,
        max_points=max_points,
        transient=100 if transient is None else transient,
    )


def continue_orbit(
    case: Case | str,
    *,
    param: str,
    start: float,
    stop: float,
    period: int = 1,
    section: float | None = None,
    guess: Sequence[float] | np.ndarray | None = None,
    transient: int | None = None,
    step: float | None = None,
    max_points: int = 400,
    tol: float = 1e-9,
    locate_tol: float = 1e-9,
    progress: Callable[[float], None] | None = None,
    engine: str = ORBIT_ENGINE,
    **overrides: float,
) -> Branch:
    """Continue the period-``period`` orbit in ``param`` from ``start`` to ``stop``: a :class:`Branch`
    (a system's period-1 orbit: a :class:`~oscillator.orbits.chain_branch.ChainBranch`, ``step``
    its largest arclength step as a fraction of the span, 0.1 by default).

    Parameters
    ----------
    case : Case or str
    param : str
        Any parameter of :class:`~oscillator.Parameters` (``"Q2"``, ``"Omega"``, ...).
    start, stop : float
        The parameter's range; the branch starts at the orbit found at ``start`` (as
        :func:`~oscillator.find_orbit` finds it) and ends when it passes ``stop`` (or comes back
        past ``start`` after folds).  Both must be valid values of ``param`` with the case's
        other parameters, and at least ``10 locate_tol`` apart.
    period, section, guess, transient, tol
        As for :func:`~oscillator.find_orbit`.
    step : float, optional
        The largest step along the branch, in units of ``|stop - start|``, in ``[1e-6, 1]``
        (default 1/40).
    max_points : int
        The most points computed (2 to 100000).
    locate_tol : float
        Bifurcations are located to this in the parameter (``> 0``).
    progress : callable, optional
        Called with the fraction of ``[start, stop]`` covered after each point.
    engine : str
        The period maps' engine, as for :func:`~oscillator.find_orbit`: ``"dop853"`` (compiled,
        the default) or ``"cvode"`` (the reference).
    **overrides
        Any other parameter, initial value or solver option.

    Returns
    -------
    Branch
        ``complete`` is False when the branch ended before ``stop`` (the corrector failed,
        ``max_points`` was reached, or the branch came back past ``start``), and ``message``
        says where and why; the points so far are kept.

    Raises
    ------
    InputError
        Bad input.
    SimulationFailed
        No orbit at ``start`` (Newton failed there, or the simulation did).
    Interrupted
        Ctrl-C: a ``KeyboardInterrupt`` whose ``result`` is the branch so far (``complete``
        False, ``message`` saying where it was interrupted).

    Examples
    --------
    >>> from oscillator import continue_orbit
    >>> branch = continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5)
    >>> branch.bifurcations[["Q2", "kind"]].round(6).values.tolist()
    [[71.157742, 'sliding_vanish']]
    """
    from oscillator.model.chains import FrictionChain as Chain

    if isinstance(case, Chain):  # a declared machine (oscillator/orbits/chain_branch.py)
        return _of_chain(case, param, (start, stop), guess, step, max_points, transient)  # type: ignore[return-value]
    settings = check_settings(
        case,
        param=param,
        start=start,
        stop=stop,
        period=period,
        section=section,
        guess=guess,
        transient=transient,
        step=step,
        max_points=max_points,
        tol=tol,
        locate_tol=locate_tol,
        progress=progress,
        **overrides,
    )
    start, stop = settings.start, settings.stop
    base = orbit_case(case, {**overrides, param: start})
    engine = check_engine(engine, among=ORBIT_ENGINES)
    section_, y_start = start_of(base, section, guess, transient, engine=engine)
    cont = Continuer(base, param, section_, settings.period, abs(stop - start), settings.tol, engine)
    direction = 1.0 if stop > start else -1.0

    trace = _Trace(cont.first(y_start, start, direction), cont.scale, param)
    try:
        complete, message = _trace_branch(cont, trace, settings, progress)
    except KeyboardInterrupt:
        last = trace.points[-1].lam
        trace.reason = Reason.INTERRUPTED
        partial = trace.branch(base, section_, settings.period, False, f"interrupted at {param} = {last:.10g}")
        raise Interrupted(partial) from None
    return trace.branch(base, section_, settings.period, complete, message)


def _trace_branch(
    cont: Continuer, trace: _Trace, settings: ContinuationSettings, progress: Callable[[float], None] | None
) -> tuple[bool, str]:
    """Step along the branch from its first point to ``stop``; ``(complete, why it ended)``."""
    param, sigma, points = cont.param, cont.sigma, trace.points
    start, stop, ds_max = settings.start, settings.stop, settings.step
    max_points, locate_tol = settings.max_points, settings.locate_tol
    direction = 1.0 if stop > start else -1.0
    ds, ds_min = ds_max / 4, ds_max / 2**12
    lo, hi = min(start, stop), max(start, stop)
    while len(points) < max_points:
        a = points[-1]
        b = cont.along(a, ds)
        fits = isinstance(b, OrbitPoint) and b.iterations <= 5
        own = own_kind(cont, a, b) if isinstance(b, OrbitPoint) and fits and not b.same_kind(a) else None
        if own is not None and ds <= ds_min:  # the corrector keeps jumping: take a's kind there
            b = OrbitPoint(
                own.y,
                own.lam,
                own.image,
                cont.tangent(cont.jacobian(own.y, own.lam, own.image), a.tangent, 1.0),
                own.iterations,
            )
        elif not isinstance(b, OrbitPoint) or not fits or own is not None:
            if ds <= ds_min:
                why = f": {b.message} ({b.reason})" if isinstance(b, Skipped) else " (it kept jumping to another orbit)"
                trace.reason = b.reason if isinstance(b, Skipped) else Reason.NO_CONVERGENCE
                return False, f"the corrector failed at {param} = {a.lam:.10g} with the smallest step{why}"
            ds /= 2
            continue
        if not lo - 1e-12 * sigma <= b.lam <= hi + 1e-12 * sigma:
            end = end_point(cont, a, b, stop if (b.lam - stop) * direction > 0 else start)
            if isinstance(end, Skipped):
                trace.reason = end.reason
                return False, f"no orbit found at {param} = {stop:.10g}, the end of the range: {end.message}"
            trace.add(between(cont, a, end, ds, locate_tol), end)
            if end.lam == stop:
                return True, ""
            trace.reason = Reason.NO_ORBIT
            return False, f"the branch came back to {param} = {start:.10g} after a fold"
        trace.add(between(cont, a, b, ds, locate_tol), b)
        if trace.stalled(sigma):
            trace.reason = Reason.NO_CONVERGENCE
            return False, (
                f"the continuation stalled at {param} = {trace.points[-1].lam:.10g}: its steps went back and forth "
                "without advancing (a point the corrector cannot step across)"
            )
        if progress is not None:
            progress(min(1.0, abs(b.lam - start) / sigma))
        if b.iterations <= 2:
            ds = min(ds * 1.5, ds_max)
    trace.reason = Reason.MAX_POINTS
    return False, (
        f"max_points = {max_points} reached at {param} = {points[-1].lam:.10g}, "
        f"{abs(points[-1].lam - start) / sigma:.0%} of the range"
    )


class _Trace:
    """The branch as it is traced: its points, where each continuous piece begins, its bifurcations."""

    def __init__(self, first: OrbitPoint, scale: float, param: str) -> None:
        self.param = param
        self.points, self.piece_starts = [first], [0]
        self.rows: list[dict[str, Any]] = []
        #: How many points and bifurcation rows the branch had before each step (to undo steps).
        self.steps: list[tuple[int, int, int]] = []
        self.scale = scale
        #: Why the branch ended early (set where it does).
        self.reason: Reason | None = None

    def add(self, located: list[Located], b: OrbitPoint) -> None:
        """The bifurcations between the last point and ``b``, the orbits on their sides (so the
        branch reaches each bifurcation), then ``b``; a new piece begins after a jump or a gap."""
        self.steps.append((len(self.points), len(self.rows), len(self.piece_starts)))
        for found in located:
            self.rows.append(found.row)
            jump = found.row["jump"]
            self._append(found.left, b)
            if found.right is not None and (math.isnan(jump) or jump > 1e-6 * self.scale):
                self.piece_starts.append(len(self.points))  # the orbit beyond the jump starts a piece
            self._append(found.right, b)
        self.points.append(b)

    def stalled(self, sigma: float) -> bool:
        """Whether the last :data:`STALL_WINDOW` steps went back and forth without advancing; if
        so they are undone (the branch ends where the stall began)."""
        if len(self.steps) < STALL_WINDOW:
            return False
        first = self.steps[-STALL_WINDOW][0] - 1
        ends = [self.points[first]] + [self.points[count - 1] for count, _, _ in self.steps[-STALL_WINDOW + 1 :]]
        ends.append(self.points[-1])
        u = np.array([np.append(p.y, p.lam / sigma) for p in ends])
        moves = np.diff(u, axis=0)
        turns = int(np.sum(np.diff(np.sign(np.diff([p.lam for p in ends]))) != 0))
        path, net = float(np.sum(np.linalg.norm(moves, axis=1))), float(np.linalg.norm(u[-1] - u[0]))
        if turns < STALL_WINDOW // 2 or net >= STALL_NET * path:
            return False
        points, rows, pieces = self.steps[-STALL_WINDOW]
        del self.points[points:], self.rows[rows:], self.piece_starts[pieces:], self.steps[-STALL_WINDOW:]
        return True

    def _append(self, side: OrbitPoint | None, b: OrbitPoint) -> None:
        last = self.points[-1]
        if side is not None and side is not b and not (side.lam == last.lam and np.array_equal(side.y, last.y)):
            self.points.append(side)

    def points_frame(self, param: str) -> pd.DataFrame:
        pieces = np.zeros(len(self.points), dtype=int)
        for start in self.piece_starts[1:]:
            pieces[start:] += 1
        rows = []
        for p, piece in zip(self.points, pieces, strict=True):
            rows.append(
                {
                    param: p.lam,
                    **dict(zip(STATE, p.y, strict=True)),
                    **{f"mu{k + 1}": complex(p.multipliers[k]) for k in range(4)},
                    "stable": p.stable,
                    "signature": str(p.signature),
                    "piece": int(piece),
                    "iterations": p.iterations,
                }
            )
        return pd.DataFrame(rows, columns=point_columns(param))

    def bifurcations_frame(self, param: str) -> pd.DataFrame:
        numbers = dict.fromkeys([param, *STATE, "jump"], float)
        frame = pd.DataFrame(self.rows, columns=[param, "kind", *STATE, "jump", "before", "after"])
        return frame.astype({**numbers, "kind": object, "before": object, "after": object})

    def branch(self, case: Case, section: float, period: int, complete: bool, message: str) -> Branch:
        """The :class:`Branch` traced so far (``case``: the case at its start)."""
        param = self.param
        reason = None if complete else self.reason
        return Branch(
            param,
            self.points_frame(param),
            self.bifurcations_frame(param),
            section,
            period,
            complete,
            message,
            reason,
            case,
        )
