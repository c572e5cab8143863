"""The supervisor compiled, for the many-start analyses: starts landed with nothing in Python per root.

:func:`land_compiled` runs one start from the stroboscopic section through its transient and a
recorded window of forcing periods as :class:`~oscillator.hybrid.supervisor.Supervisor` would
with the ``"dop853"`` engine (:mod:`oscillator.engines.dop853`), but in one compiled function: the
mode at the start (:func:`~oscillator.model.resolving.initial_mode`'s rules), the engine's
returns, at every root the check that the state stands in its mode, the switching rules
(:func:`~oscillator.model.switching.resolve_compiled`, all of them) and the guards (an event storm
at one instant or within ``storm_window``, a stall, more than ``max_events`` events), with the
step size carried across switches.  What comes out are arrays: the section points
``P_k = y(t0 + k T)`` of the window with the velocity signs there, the event rows of the window,
and a status.  The transient ends where the section points have settled, checked after 8, 16,
32, ... periods as :func:`oscillator.attractors.mapping.settled` does (:func:`settled_compiled`
is the same test); a motion that settled with period ``n`` is recorded for two cycles, to the
end of a whole number of its cycles (:func:`recorded`), one that did not for ``record``.

A start that fails here is told by a code only (:data:`FAILED`); the caller runs it again with
the reference engine for the words (:func:`oscillator.attractors.mapping.land`).
"""

from __future__ import annotations

import math

import numpy as np

from oscillator.compiled import njit
from oscillator.engines.dop853 import (
    PHI_OUT,
    ROOT,
    STARTED,
    T_CUR,
    T_REF,
    Y_OUT,
    M,
    N,
    R,
    advance,
    grid_returns,
    restart,
)
from oscillator.hybrid.guards import CONSISTENCY, MAX_STALLS, SAME_INSTANT
from oscillator.model.parameters import SolverOptions
from oscillator.model.roots import directions_into, violation_code
from oscillator.model.saltation import carry_compiled
from oscillator.model.switching import MAX_ROWS, initial_compiled, resolve_compiled
from oscillator.model.types import Vector

__all__ = [
    "FAILED",
    "OK",
    "OPTIONS",
    "SETTLE_CHUNK",
    "SHORTER_CYCLE",
    "SWITCH_COLUMNS",
    "WINDOW_FULL",
    "land_compiled",
    "map_compiled",
    "options_vector",
    "recorded",
    "resolved",
    "run_compiled",
    "settled_compiled",
]

#: What :func:`land_compiled` returns as its status: landed; a failure (an engine's failure, a
#: guard, a crossing unseen, numbers that left floating point); more events in the window than
#: its buffer holds.
OK, FAILED, WINDOW_FULL = 0, 1, 2
#: The options vector's entries.
OPTIONS = ("consistency", "velocity_tolerance", "displacement_tolerance", "storm_events", "storm_window", "max_events")
_CONSISTENCY, _VELOCITY, _DISPLACEMENT, _STORM_EVENTS, _STORM_WINDOW, _MAX_EVENTS = range(len(OPTIONS))


def options_vector(options: SolverOptions) -> np.ndarray:
    """The :data:`OPTIONS` of a case's solver options (and the supervisor's consistency tolerance)."""
    values = {"consistency": CONSISTENCY, "velocity_tolerance": options.grazing_velocity_tolerance}
    values["displacement_tolerance"] = options.grazing_displacement_tolerance
    values.update({name: getattr(options, name) for name in ("storm_events", "storm_window", "max_events")})
    return np.array([values[name] for name in OPTIONS], dtype=float)


#: Forcing periods in the first two runs of a settling transient; the runs after double (the
#: compiled landing's and :func:`oscillator.attractors.mapping.land`'s through ``simulate``).
SETTLE_CHUNK = 8


@njit(cache=True, error_model="numpy")
def _set_mode(modes: np.ndarray, s1: int, s2: int, left: int, right: int) -> None:  # pragma: no cover - compiled
    """The engine's mode vector: signs, contact flags and root directions."""
    modes[0], modes[1], modes[2], modes[3] = s1, s2, left, right
    directions_into(modes, 4, s1, s2, left != 0, right != 0)


#: A divisor ``m`` of the period ``n`` a motion seems settled with, whose repeats are within this
#: many times the settling tolerance: the motion is still converging to the shorter cycle (beside a
#: period doubling, alternately), and is not settled yet.
SHORTER_CYCLE = 16.0


@njit(cache=True, error_model="numpy")
def _repeat(points: np.ndarray, end: int, n: int) -> float:  # pragma: no cover - compiled
    """The largest distance between the ``n`` rows before row ``end`` and the ``n`` before them."""
    d = 0.0
    for j in range(n):
        near = 0.0
        for i in range(4):
            near += (points[end - n + j, i] - points[end - 2 * n + j, i]) ** 2
        d = max(d, math.sqrt(near))
    return d


@njit(cache=True, error_model="numpy")
def settled_compiled(points: np.ndarray, count: int, tolerance: float, max_period: int) -> int:  # pragma: no cover
    """:func:`oscillator.attractors.mapping.settled` on the first ``count`` rows of ``points``: the
    period they settled with, 0 if none."""
    largest = 0.0
    for k in range(max(0, count - 8), count):
        for i in range(4):
            largest = max(largest, abs(points[k, i]))
    scale = tolerance * (1.0 + largest) if count else tolerance
    for n in range(1, min(max_period, count // 3) + 1):
        d, d0 = _repeat(points, count, n), _repeat(points, count - n, n)
        if d <= scale and (d == 0.0 or (d < d0 and d / (1.0 - d / d0) <= scale)):
            for m in range(1, n):
                if n % m == 0 and _repeat(points, count, m) <= SHORTER_CYCLE * scale:
                    return 0
            return n
    return 0


@njit(cache=True, error_model="numpy")
def recorded(record: int, period: int, ran: int) -> int:  # pragma: no cover - compiled
    """The forcing periods recorded after a transient of ``ran`` periods that settled with
    ``period`` (0: it did not settle): two of its cycles, enough to read the period and one
    cycle's switches with a repeat to spare, and up to ``period - 1`` more so that the run ends
    after a whole number of its cycles (a start on a periodic orbit ends where it began: a sweep
    that goes on from it keeps the orbit's phase); else ``record`` (at most ``record`` either way)."""
    return min(record, 2 * period + (-ran) % period) if period > 0 else record


@njit(cache=True, error_model="numpy")
def _storm(recent: Vector, filled: int, t: float, count: int, limit: int, window: float) -> tuple[int, bool]:
    """The times of the latest ``limit + 1`` events (a ring) with ``count`` more at ``t``: how many
    are kept, and whether they all fall within ``window`` (the storm guard)."""  # pragma: no cover
    size = limit + 1
    stormy = False
    for _ in range(count):
        recent[filled % size] = t
        filled += 1
        if filled >= size and t - recent[filled % size] <= window:
            stormy = True
    return filled, stormy


@njit(cache=True, error_model="numpy")
def _finite(y: Vector) -> bool:  # pragma: no cover - compiled
    for v in y:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True, error_model="numpy")
def _ordered(ring: np.ndarray, count: int, out: np.ndarray) -> int:  # pragma: no cover - compiled
    """The last points of the ring, oldest first, into ``out``; how many."""
    size = int(ring.shape[0])
    kept = min(count, size)
    for j in range(kept):
        out[j, :] = ring[(count - kept + j) % size, :]
    return kept


@njit(cache=True, error_model="numpy")
def _root(
    w: Vector, modes: np.ndarray, c: Vector, period: float, options: Vector, fired: int, rows: np.ndarray
) -> tuple[tuple[int, int, int, int], int, bool]:  # pragma: no cover - compiled
    """At a root: the state checked against its mode and the instant resolved (the state projected in
    ``w[Y_OUT:]``); the next mode, the events written, and whether all went well."""
    t, y = w[T_REF] + w[T_CUR], w[Y_OUT : Y_OUT + N]
    mode = (modes[0], modes[1], modes[2], modes[3])
    if not _finite(y):
        return mode, 0, False
    if violation_code(t, y, c, mode[0], mode[1], mode[2] != 0, mode[3] != 0, options[_CONSISTENCY]) != 0:
        return mode, 0, False
    state = y[:4].copy()
    after, n, ok = resolve_compiled(
        t, state, c, period, mode, fired, options[_VELOCITY], options[_DISPLACEMENT], rows, 0
    )
    if ok and after != mode:
        y[:4] = state
    return after, n, ok


#: The running counts of one landing (a float vector): the events kept by the storm guard's
#: ring, all events, the window's event rows, root returns without a switch at one instant, the
#: last root's time, and the time the window begins.
TALLY = 6
_FILLED, _TOTAL, _KEPT, _STALLS, _LAST_ROOT, _WINDOW_FROM = range(TALLY)


@njit(cache=True, error_model="numpy")
def resolved(
    w: Vector,
    modes: np.ndarray,
    c: Vector,
    period: float,
    options: Vector,
    fired: int,
    buffers: tuple[np.ndarray, Vector, np.ndarray],
    tally: Vector,
) -> tuple[int, bool]:  # pragma: no cover - compiled
    """A root return resolved (the state projected in ``w[Y_OUT:]``, ``modes`` the mode after),
    counted by the guards, its events kept where the window has begun: the status (:data:`OK` to go
    on) and whether the mode switched (the engine is then to be restarted)."""
    rows, recent, window_rows = buffers
    t = w[T_REF] + w[T_CUR]
    mode = (modes[0], modes[1], modes[2], modes[3])
    after, n, ok = _root(w, modes, c, period, options, fired, rows)
    tally[_TOTAL] += n
    filled, stormy = _storm(recent, int(tally[_FILLED]), t, n, int(options[_STORM_EVENTS]), options[_STORM_WINDOW])
    tally[_FILLED] = filled
    if not ok or stormy or tally[_TOTAL] > options[_MAX_EVENTS]:
        return FAILED, False
    if t >= tally[_WINDOW_FROM] and n:
        kept = int(tally[_KEPT])
        if kept + n > window_rows.shape[0]:
            return WINDOW_FULL, False
        window_rows[kept : kept + n, :] = rows[:n, :]
        tally[_KEPT] = kept + n
    if after != mode:
        _set_mode(modes, after[0], after[1], after[2], after[3])
        tally[_STALLS], tally[_LAST_ROOT] = 0.0, -math.inf
        return OK, True
    same = t - tally[_LAST_ROOT] <= SAME_INSTANT * (1.0 + abs(t))
    tally[_STALLS] = tally[_STALLS] + 1.0 if same and n == 0 else 0.0
    tally[_LAST_ROOT] = t
    return (FAILED if tally[_STALLS] > MAX_STALLS else OK), False


@njit(cache=True, error_model="numpy")
def _start(
    w: Vector,
    modes: np.ndarray,
    c: Vector,
    t0: float,
    period: float,
    start: Vector,
    options: Vector,
    buffers: tuple[np.ndarray, Vector, np.ndarray],
    y: Vector,
) -> tuple[float, int]:  # pragma: no cover - compiled
    """The mode at the start and the engine started in it from ``y`` (the start in its first four
    entries; ``Phi``, the rest projection, where it has room for it): the storm guard's count (-1:
    failed) and the start's event rows (written into the buffers' first)."""
    rows, recent, _ = buffers
    y[:4] = start  # the start as given, as the supervisor starts from it
    w[STARTED] = 0.0  # the first step chosen afresh: a landing does not depend on the one before
    mode, n, ok = initial_compiled(t0, start.copy(), c, period, rows)
    filled, stormy = _storm(recent, 0, t0, n, int(options[_STORM_EVENTS]), options[_STORM_WINDOW])
    if not ok or stormy:
        return -1.0, 0
    _set_mode(modes, mode[0], mode[1], mode[2], mode[3])
    if y.shape[0] > N:
        for i in range(4):
            y[N + 5 * i] = 0.0 if i % 2 == 1 and modes[i // 2] == 0 else 1.0
    restart(w, modes, c, t0, y)
    return float(filled), n


@njit(cache=True, error_model="numpy")
def land_compiled(
    c: Vector,
    t0: float,
    period: float,
    start: Vector,
    w: Vector,
    options: Vector,
    settings: tuple[bool, int, int, float, int],
    points: np.ndarray,
    window_rows: np.ndarray,
) -> tuple[int, int, int, int]:  # pragma: no cover - compiled
    """Land one start (see the module's docstring); ``settings`` is ``(settle, transient, record,
    tolerance, max_period)``.  Writes the window's section points with the velocity signs there
    (``points``: up to ``record + 1`` rows ``x1, v1, x2, v2, s1, s2``) and its event rows
    (``window_rows``); returns the status, the forcing periods run before the window, the
    periods recorded (:func:`recorded`) and how many event rows."""
    settle, transient, record, tolerance, max_period = settings
    modes = np.zeros(4 + R, np.int64)
    buffers = (np.empty((2 * MAX_ROWS, window_rows.shape[1])), np.empty(int(options[_STORM_EVENTS]) + 1), window_rows)
    ring = np.empty((max(8, 3 * max_period), 4))
    ordered = np.empty_like(ring)
    tally = np.zeros(6)
    tally[_FILLED] = _start(w, modes, c, t0, period, start, options, buffers, np.zeros(N))[0]
    if tally[_FILLED] < 0.0:
        return FAILED, 0, 0, 0
    ring[0, :] = start
    count, k, ran, last = 1, 0, -1 if settle else transient, transient + record
    tally[_LAST_ROOT], tally[_WINDOW_FROM] = -math.inf, math.inf if settle else t0 + period * transient
    checkpoint, chunk = min(SETTLE_CHUNK, transient), SETTLE_CHUNK
    while True:
        kind, fired = advance(w, modes, c, t0 + period * (k + 1), t0 + period * (transient + record), False)
        if kind < 0:
            return FAILED, 0, 0, 0
        if kind == ROOT:
            status, switched = resolved(w, modes, c, period, options, fired, buffers, tally)
            if status != OK:
                return status, 0, 0, 0
            if switched:
                restart(w, modes, c, w[T_REF] + w[T_CUR], w[Y_OUT : Y_OUT + N])
            continue
        k += 1
        y = w[Y_OUT : Y_OUT + N]
        if not _finite(y):
            return FAILED, 0, 0, 0
        if ran < 0:  # settling: the points so far, checked at the chunks' ends
            ring[count % ring.shape[0], :] = y[:4]
            count += 1
            if k == checkpoint:
                n = settled_compiled(ordered, _ordered(ring, count, ordered), tolerance, max_period)
                if k >= transient or n > 0:
                    ran, last, tally[_WINDOW_FROM] = k, k + recorded(record, n, k), t0 + period * k
                else:
                    chunk = chunk if k < 2 * SETTLE_CHUNK else 2 * chunk
                    checkpoint = min(k + chunk, transient)
        if ran >= 0 and k >= ran:
            points[k - ran, :4] = y[:4]
            points[k - ran, 4], points[k - ran, 5] = modes[0], modes[1]
            if k == last:
                return OK, ran, last - ran, int(tally[_KEPT])


@njit(cache=True, error_model="numpy")
def _changed(changes: np.ndarray, count: int, t: float, modes: np.ndarray) -> int:  # pragma: no cover - compiled
    """The mode from ``t`` on as the next row ``(t, s1, s2, left, right)`` of ``changes``; how many
    rows (-1: no room)."""
    if count >= changes.shape[0]:
        return -1
    changes[count, 0] = t
    for k in range(4):
        changes[count, 1 + k] = modes[k]
    return count + 1


@njit(cache=True, error_model="numpy")
def run_compiled(
    c: Vector,
    t0: float,
    period: float,
    start: Vector,
    w: Vector,
    options: Vector,
    grid: Vector,
    buffers: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[int, int, int, int]:  # pragma: no cover - compiled
    """One run from ``t0`` (``grid[0]``) to ``grid[-1]`` as the supervisor makes it with the
    ``"dop853"`` engine, recorded (for the explorer: :func:`oscillator.exploring.scene.scene_of`):
    the trajectory at each time of ``grid`` (rows ``t, x1, v1, x2, v2``), every event row from the
    start's on, and each mode from the time it holds (rows ``t, s1, s2, left, right``), into
    ``buffers = (trajectory, events, modes)``.  The status (:data:`OK`, :data:`FAILED`, or
    :data:`WINDOW_FULL` where the events or modes outgrew their buffers) and the rows written of
    each: a run stopped short of the grid's end writes fewer rows than the grid's times."""
    trajectory, events, changes = buffers
    t_end = grid[grid.shape[0] - 1]
    modes = np.zeros(4 + R, np.int64)
    rows = np.empty((2 * MAX_ROWS, events.shape[1]))
    recent = np.empty(int(options[_STORM_EVENTS]) + 1)
    y = np.zeros(N)
    y[:4] = start
    w[STARTED] = 0.0
    mode, n, ok = initial_compiled(t0, start.copy(), c, period, rows)  # the start as given, as simulate's
    filled, stormy = _storm(recent, 0, t0, n, int(options[_STORM_EVENTS]), options[_STORM_WINDOW])
    if not ok or stormy or n > events.shape[0]:
        return FAILED, 0, 0, 0
    events[:n, :] = rows[:n, :]
    _set_mode(modes, mode[0], mode[1], mode[2], mode[3])
    restart(w, modes, c, t0, y)
    tally = np.zeros(6)
    tally[_FILLED], tally[_TOTAL], tally[_KEPT] = filled, n, n
    tally[_LAST_ROOT], tally[_WINDOW_FROM] = -math.inf, -math.inf  # every event kept
    count = _changed(changes, 0, t0, modes)
    last = np.zeros(N)
    trajectory[0, 0] = t0  # the grid's first time: the start, as given (the engine is not advanced to it)
    trajectory[0, 1:] = start
    done = 1
    while done < grid.shape[0]:
        kind, fired, n, t = grid_returns(w, modes, c, grid[done:], t_end, trajectory[done:], last)
        done += n
        if kind < 0 or not _finite(last):
            return FAILED, done, int(tally[_KEPT]), count
        if kind != ROOT:
            if t >= t_end or n == 0:  # the end, or no grid time reached (the caller sees the rows short)
                break
            continue
        before = (modes[0], modes[1], modes[2], modes[3])
        status, switched = resolved(w, modes, c, period, options, fired, (rows, recent, events), tally)
        if status != OK:
            return status, done, int(tally[_KEPT]), count
        if switched:
            restart(w, modes, c, w[T_REF] + w[T_CUR], w[Y_OUT : Y_OUT + N])
        if (modes[0], modes[1], modes[2], modes[3]) != before:
            count = _changed(changes, count, t, modes)
            if count < 0:
                return WINDOW_FULL, done, int(tally[_KEPT]), 0
    return OK, done, int(tally[_KEPT]), count


#: The columns of :func:`map_compiled`'s switches: the time, the mode after (``s1, s2, left,
#: right``), the state the flow reached and the state the switch left, the event rows kept before
#: the piece it begins (the start is the first row, and its piece begins with no rows kept).
SWITCH_COLUMNS = 14


@njit(cache=True, error_model="numpy")
def _map_start(
    w: Vector,
    modes: np.ndarray,
    c: Vector,
    t0: float,
    period: float,
    start: Vector,
    options: Vector,
    buffers: tuple[np.ndarray, Vector, np.ndarray],
    switches: np.ndarray,
    y: Vector,
    tally: Vector,
) -> bool:  # pragma: no cover - compiled
    """:func:`map_compiled`'s start: the mode there, its events, the first row of ``switches``,
    ``Phi`` (the rest projection, where ``y`` has room for it) and the engine started; False if
    the start fails."""
    events = buffers[2]
    filled, n = _start(w, modes, c, t0, period, start, options, buffers, y)
    if filled < 0.0 or n > events.shape[0]:
        return False
    events[:n, :] = buffers[0][:n, :]
    row = switches[0]  # the start, as the first switch's row: the first piece's mode
    row[0], row[1:5], row[5:9], row[9:13], row[13] = t0, modes[:4], start, start, 0.0
    tally[_FILLED], tally[_TOTAL], tally[_KEPT] = filled, n, n
    tally[_LAST_ROOT], tally[_WINDOW_FROM] = -math.inf, -math.inf  # every event kept
    return True


@njit(cache=True, error_model="numpy")
def map_compiled(
    c: Vector,
    t0: float,
    t1: float,
    period: float,
    start: Vector,
    w: Vector,
    options: Vector,
    buffers: tuple[np.ndarray, np.ndarray, Vector],
) -> tuple[int, int, int, int]:  # pragma: no cover - compiled
    """One period map from ``(t0, start)`` to ``t1`` as the supervisor makes it with the
    ``"dop853"`` engine, and where ``w`` carries it (:func:`~oscillator.engines.dop853.new_work`'s
    ``tangent``) the derivative of the flow through every switch
    (:func:`~oscillator.model.saltation.carry_compiled`).  Into ``buffers = (events, switches,
    end)``: every event row, a row of :data:`SWITCH_COLUMNS` for the start and each switch, the
    state (and ``Phi``) at ``t1``.  The status (:data:`OK`; :data:`FAILED` for an engine's failure,
    a guard or a grazing; :data:`WINDOW_FULL` where a buffer is too small), the event rows, the
    switches and the engine's returns."""
    events, switches, end = buffers
    tangent = end.shape[0] > N
    rows = np.empty((2 * MAX_ROWS, events.shape[1]))
    recent = np.empty(int(options[_STORM_EVENTS]) + 1)
    modes = np.zeros(4 + R, np.int64)
    y = np.zeros(end.shape[0])
    tally = np.zeros(TALLY)
    if not _map_start(w, modes, c, t0, period, start, options, (rows, recent, events), switches, y, tally):
        return FAILED, 0, 0, 0
    count, returns, before, phi = 1, 0, np.zeros(4, np.int64), np.empty(M)
    while True:
        kind, fired = advance(w, modes, c, t1, t1, False)
        returns += 1
        if kind < 0 or not _finite(w[Y_OUT : Y_OUT + N]):
            return FAILED, int(tally[_KEPT]), count, returns
        if kind != ROOT:
            end[:N] = w[Y_OUT : Y_OUT + N]
            if tangent:
                end[N:] = w[PHI_OUT : PHI_OUT + M]
            return OK, int(tally[_KEPT]), count, returns
        t, reached = w[T_REF] + w[T_CUR], w[Y_OUT : Y_OUT + 4].copy()
        before[:] = modes[:4]
        status, switched = resolved(w, modes, c, period, options, fired, (rows, recent, events), tally)
        if status != OK:
            return status, int(tally[_KEPT]), count, returns
        if not switched:
            continue
        if count >= switches.shape[0]:
            return WINDOW_FULL, int(tally[_KEPT]), count, returns
        row = switches[count]
        row[0], row[1:5], row[5:9], row[9:13], row[13] = t, modes[:4], reached, w[Y_OUT : Y_OUT + 4], tally[_KEPT]
        count += 1
        y[:N] = w[Y_OUT : Y_OUT + N]
        if tangent and carry_compiled(w[PHI_OUT : PHI_OUT + M], t, reached, y[:4], c, before, modes[:4], phi) != 0:
            return FAILED, int(tally[_KEPT]), count, returns  # a grazing: no derivative here
        if tangent:
            y[N:] = phi
        restart(w, modes, c, t, y)
