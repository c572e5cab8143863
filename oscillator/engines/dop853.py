"""DOP853 with its dense output and CVODE's root finding on it, all compiled: the ``"dop853"`` engine's kernels.

The method is SciPy's ``DOP853`` (Hairer, Norsett & Wanner's explicit Runge-Kutta pair of order
8(5,3) with a 7th-order dense output), its coefficients taken from
``scipy.integrate._ivp.dop853_coefficients`` and its step control as SciPy's (error norm,
safety 0.9, step factors 0.2-10, the first step by Hairer's rule), the steps capped at
``max_step_fraction`` of a forcing period as CVODE's are.  The root functions of
:mod:`oscillator.model.roots` are evaluated at each step's end; where one changes sign (in its
mode's direction) the root is located on the dense output by CVODE's own search (``cvRootfind``:
the secant method with the Illinois modification, to ``100 eps (|t| + |h|)``), so that both
engines put an event at the same time to the accuracy of their solutions.  A root function that
is exactly zero where a search starts takes its sign a rounding step later, as CVODE's does.

Everything from one return to the next runs in compiled code (:func:`advance`), on one float
vector that holds the integrator's state (its layout: the offsets below): the supervisor's loop in Python
(``simulate(case, engine="dop853")``) and the compiled one of the many-start analyses
(:mod:`oscillator.hybrid.batch`) drive the same functions.  A root that switches nothing leaves the
step it was found in to be searched on; a switch restarts the method from the root with the new
mode's field and the step size reached so far.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _coefficients

from oscillator.compiled import hot
from oscillator.model.kernels import jacobian, rates
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.roots import NUM_ROOTS, root_directions, root_values_at
from oscillator.model.types import Vector

__all__ = ["FAILURES", "advance", "grid_returns", "mode_vector", "new_work", "restart"]

_STAGES = int(_coefficients.N_STAGES)  # 12
_A = np.ascontiguousarray(_coefficients.A[:_STAGES, :_STAGES])
_B = np.ascontiguousarray(_coefficients.B)
_C = np.ascontiguousarray(_coefficients.C[:_STAGES])
_E3 = np.ascontiguousarray(_coefficients.E3)
_E5 = np.ascontiguousarray(_coefficients.E5)
_D = np.ascontiguousarray(_coefficients.D)
_A_EXTRA = np.ascontiguousarray(_coefficients.A[_STAGES + 1 :])
_C_EXTRA = np.ascontiguousarray(_coefficients.C[_STAGES + 1 :])
_POWER = int(_coefficients.INTERPOLATOR_POWER)  # 7
_EXTENDED = int(_coefficients.N_STAGES_EXTENDED)  # 16

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
#: SciPy's error exponent: the error estimator is of order 7.
_EXPONENT = -1.0 / 8.0
#: CVODE's root tolerance: ``100 eps (|t| + |h|)``.
_ROOT_TOLERANCE = 100.0 * float(np.finfo(float).eps)
#: SciPy's smallest step is ten spacings of the time; ``eps |t|`` bounds one spacing.
_ULP, _TINY = float(np.finfo(float).eps), float(np.finfo(float).tiny)

N = 8  # x1, v1, x2, v2 and the four works
R = NUM_ROOTS

# The work vector: scalars, then the arrays (offsets).
(
    T_OLD,
    T_NEW,
    H_NEXT,
    T_CUR,
    DENSE,
    STEPPED,
    EVALS,
    H_MAX,
    RTOL,
    ATOL,
    CAP,
    NEAR,
    MAX_STEPS,
    STARTED,
    T_REF,
    TANGENT,
) = range(16)
Y_OLD = 16
Y_NEW = Y_OLD + N
F_NEW = Y_NEW + N
Y_TMP = F_NEW + N
Y_OUT = Y_TMP + N
G_CUR = Y_OUT + N
G_NEW = G_CUR + R
G_LO = G_NEW + R
G_HI = G_LO + R
G_MID = G_HI + R
K_AT = G_MID + R
F_AT = K_AT + _EXTENDED * N
# The derivative of the flow, ``Phi`` (16, row by row), where ``w[TANGENT]`` is set: its values at
# the step's two ends, its field ``J Phi`` at the new end, a stage's, the step's attempt, the output,
# its stages, its dense output's coefficients and the Jacobian ``J`` itself.
M = 16
PHI_OLD = F_AT + _POWER * N
PHI_NEW = PHI_OLD + M
PF_NEW = PHI_NEW + M
PHI_TMP = PF_NEW + M
PHI_STEP = PHI_TMP + M
PHI_OUT = PHI_STEP + M
PK_AT = PHI_OUT + M
PF_AT = PK_AT + _EXTENDED * M
JAC = PF_AT + _POWER * M
SIZE = JAC + M

#: What :func:`advance` returns: a root, the target (or the stop time), one step, or a failure.
ROOT, TARGET, STEPPED_ONE, TOO_MUCH_WORK, TOO_SMALL = 0, 1, 2, -1, -3
#: The failures' codes and what they say.
FAILURES = {
    TOO_MUCH_WORK: "more than max_num_steps steps before the next output",
    TOO_SMALL: "the step size fell below the time's resolution (the field is not finite or not smooth there)",
}

# The modes vector: the signs and contact flags, then the root directions.
DIRECTIONS = 4


@hot(inline=True)
def _field(
    w: Vector, modes: np.ndarray, c: Vector, tau: float, at: int, out: int
) -> None:  # pragma: no cover - compiled
    """``w[out:out + 8]`` = the mode's field and powers (:func:`~oscillator.model.kernels.rates`)
    at ``(t_ref + tau, w[at:at + 8])``: offsets into the one work vector, no array made or counted."""
    x1, v1, x2, v2 = w[at], w[at + 1], w[at + 2], w[at + 3]
    r = rates(w[T_REF] + tau, x1, v1, x2, v2, c, modes[0], modes[1], modes[2] != 0, modes[3] != 0)
    w[out], w[out + 1], w[out + 2], w[out + 3] = r[0], r[1], r[2], r[3]
    w[out + 4], w[out + 5], w[out + 6], w[out + 7] = r[4], r[5], r[6], r[7]
    w[EVALS] += 1.0


@hot(inline=True)
def _tangent(w: Vector, modes: np.ndarray, c: Vector, at: int, phi: int, out: int) -> None:  # pragma: no cover
    """``w[out:out + 16]`` = ``J Phi``: the variational field (:func:`~oscillator.model.kernels.jacobian`)
    at the state ``w[at:]`` applied to ``Phi = w[phi:phi + 16]``.  The same stages as the state's
    carry it, so ``Phi`` is the derivative of the step the method took (internal differentiation)."""
    x1, v1, x2, v2 = w[at], w[at + 1], w[at + 2], w[at + 3]
    jacobian(x1, v1, x2, v2, c, modes[0], modes[1], modes[2] != 0, modes[3] != 0, w[JAC : JAC + M])
    for row in range(4):
        for col in range(4):
            total = 0.0
            for k in range(4):
                total += w[JAC + 4 * row + k] * w[phi + 4 * k + col]
            w[out + 4 * row + col] = total


@hot
def _roots(w: Vector, modes: np.ndarray, c: Vector, tau: float, y: int, g: int) -> None:  # pragma: no cover
    """``w[g:g + 11]`` = the root functions (:func:`~oscillator.model.roots.root_values_at`) at
    ``(t_ref + tau, w[y:])``."""
    x1, v1, x2, v2 = w[y], w[y + 1], w[y + 2], w[y + 3]
    left, right = modes[2] != 0, modes[3] != 0
    root_values_at(w[T_REF] + tau, x1, v1, x2, v2, c, modes[0], modes[1], left, right, w[CAP], w[NEAR], w, g)


def new_work(params: Parameters, options: SolverOptions, *, tangent: bool = False) -> np.ndarray:
    """A work vector for :func:`advance` with the options' tolerances and step cap; with
    ``tangent``, the derivative of the flow ``Phi`` is carried with the state."""
    w = np.zeros(SIZE)
    w[TANGENT] = float(tangent)
    w[RTOL], w[ATOL] = options.rtol, options.atol
    w[H_MAX] = w[CAP] = options.max_step_fraction * params.period
    w[NEAR] = options.grazing_displacement_tolerance
    w[MAX_STEPS] = options.max_num_steps
    return w


def mode_vector(mode: Mode) -> np.ndarray:
    """The signs, contact flags and root directions of ``mode`` as :func:`advance` takes them."""
    return np.array([mode.sign(1), mode.sign(2), int(mode.left), int(mode.right), *root_directions(mode)], np.int64)


@hot
def _first_step(w: Vector, modes: np.ndarray, c: Vector) -> float:  # pragma: no cover - compiled
    """Hairer's rule for the first step (SciPy's ``select_initial_step``, order 7)."""
    d0, d1 = 0.0, 0.0
    for i in range(N):
        scale = w[ATOL] + abs(w[Y_NEW + i]) * w[RTOL]
        d0 += (w[Y_NEW + i] / scale) ** 2
        d1 += (w[F_NEW + i] / scale) ** 2
    d0, d1 = math.sqrt(d0 / N), math.sqrt(d1 / N)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, w[H_MAX])
    for i in range(N):
        w[Y_TMP + i] = w[Y_NEW + i] + h0 * w[F_NEW + i]
    _field(w, modes, c, h0, Y_TMP, Y_OUT)
    d2 = 0.0
    for i in range(N):
        d2 += ((w[Y_OUT + i] - w[F_NEW + i]) / (w[ATOL] + abs(w[Y_NEW + i]) * w[RTOL])) ** 2
    d2 = math.sqrt(d2 / N) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return float(min(100.0 * h0, h1, w[H_MAX]))


@hot
def restart(w: Vector, modes: np.ndarray, c: Vector, t: float, y: Vector) -> None:  # pragma: no cover - compiled
    """Integrate ``modes``' field from ``(t, y)`` on: the step size reached so far is kept.  The
    time is measured from here on, as CVODE's is from its restarts: a root is located to
    ``100 eps`` of the time since the restart, not of the time since the run's start.  Where the
    work carries ``Phi``, ``y`` is 24 long: the state, the works and ``Phi``."""
    for i in range(N):
        w[Y_NEW + i] = y[i]
    if w[TANGENT] != 0.0:
        for i in range(M):
            w[PHI_NEW + i] = y[N + i]
        _tangent(w, modes, c, Y_NEW, PHI_NEW, PF_NEW)
    w[T_REF] = t
    w[T_NEW] = w[T_CUR] = 0.0
    w[STEPPED] = 0.0
    w[DENSE] = 0.0
    _field(w, modes, c, 0.0, Y_NEW, F_NEW)
    _roots(w, modes, c, 0.0, Y_NEW, G_CUR)
    if w[STARTED] == 0.0:
        w[H_NEXT] = _first_step(w, modes, c)
        w[STARTED] = 1.0
    w[H_NEXT] = min(w[H_NEXT], w[H_MAX])


@hot(inline=True)
def _stage(
    w: Vector, modes: np.ndarray, c: Vector, a: np.ndarray, row: int, s: int, start: int, phi: int, tau: float, h: float
) -> None:  # pragma: no cover - compiled
    """Stage ``s``: ``K[s]`` = the field at ``(tau, y + h sum_j a[row, j] K[j])``, ``j < s``, with
    ``y`` at ``w[start:]`` (and ``Phi``'s stage likewise from ``w[phi:]``, where it is carried)."""
    for i in range(N):
        total = 0.0
        for j in range(s):
            total += a[row, j] * w[K_AT + N * j + i]
        w[Y_TMP + i] = w[start + i] + h * total
    _field(w, modes, c, tau, Y_TMP, K_AT + N * s)
    if w[TANGENT] != 0.0:
        for i in range(M):
            total = 0.0
            for j in range(s):
                total += a[row, j] * w[PK_AT + M * j + i]
            w[PHI_TMP + i] = w[phi + i] + h * total
        _tangent(w, modes, c, Y_TMP, PHI_TMP, PK_AT + M * s)


@hot
def _stages(w: Vector, modes: np.ndarray, c: Vector, t: float, h: float) -> None:  # pragma: no cover - compiled
    """One attempt of the Runge-Kutta step from ``(t, y_new)`` by ``h``: the stages in ``K`` and
    the new state in ``Y_OUT`` (SciPy's ``rk_step``)."""
    for i in range(N):
        w[K_AT + i] = w[F_NEW + i]
    tangent = w[TANGENT] != 0.0
    if tangent:
        _copy(w, PF_NEW, PK_AT, M)
    for s in range(1, _STAGES):
        _stage(w, modes, c, _A, s, s, Y_NEW, PHI_NEW, t + _C[s] * h, h)
    for i in range(N):
        total = 0.0
        for j in range(_STAGES):
            total += _B[j] * w[K_AT + N * j + i]
        w[Y_OUT + i] = w[Y_NEW + i] + h * total
    _field(w, modes, c, t + h, Y_OUT, K_AT + N * _STAGES)
    if tangent:
        for i in range(M):
            total = 0.0
            for j in range(_STAGES):
                total += _B[j] * w[PK_AT + M * j + i]
            w[PHI_STEP + i] = w[PHI_NEW + i] + h * total
        _tangent(w, modes, c, Y_OUT, PHI_STEP, PK_AT + M * _STAGES)


@hot
def _error_norm(w: Vector, h: float) -> float:  # pragma: no cover - compiled
    """SciPy's DOP853 error norm of the attempt in ``K`` (``Y_NEW`` to ``Y_OUT``)."""
    err5, err3 = 0.0, 0.0
    for i in range(N):
        scale = w[ATOL] + max(abs(w[Y_NEW + i]), abs(w[Y_OUT + i])) * w[RTOL]
        e5, e3 = 0.0, 0.0
        for j in range(_STAGES + 1):
            e5 += _E5[j] * w[K_AT + N * j + i]
            e3 += _E3[j] * w[K_AT + N * j + i]
        err5 += (e5 / scale) ** 2
        err3 += (e3 / scale) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * N)


@hot
def _step(w: Vector, modes: np.ndarray, c: Vector, t_stop: float) -> bool:  # pragma: no cover - compiled
    """One accepted step from ``T_NEW`` (never past ``t_stop``): the old end becomes ``T_OLD``.
    False if the step size fell below the time's resolution."""
    t = w[T_NEW]
    h_abs = min(w[H_NEXT], w[H_MAX])
    rejected = False
    while True:
        min_step = 10.0 * _ULP * max(abs(t), _TINY)
        if h_abs < min_step or not math.isfinite(h_abs):
            return False
        t_new = min(t + h_abs, t_stop)
        h = t_new - t
        _stages(w, modes, c, t, h)
        error = _error_norm(w, h)
        if error < 1.0:
            factor = MAX_FACTOR if error == 0.0 else min(MAX_FACTOR, SAFETY * error**_EXPONENT)
            if rejected:
                factor = min(1.0, factor)
            w[H_NEXT] = h * factor
            break
        h_abs = h * (max(MIN_FACTOR, SAFETY * error**_EXPONENT) if math.isfinite(error) else MIN_FACTOR)
        rejected = True
    w[T_OLD], w[T_NEW] = t, t_new
    for i in range(N):
        w[Y_OLD + i] = w[Y_NEW + i]
        w[Y_NEW + i] = w[Y_OUT + i]
        w[F_NEW + i] = w[K_AT + N * _STAGES + i]
    if w[TANGENT] != 0.0:
        _copy(w, PHI_NEW, PHI_OLD, M)
        _copy(w, PHI_STEP, PHI_NEW, M)
        _copy(w, PK_AT + M * _STAGES, PF_NEW, M)
    w[STEPPED] = 1.0
    w[DENSE] = 0.0
    _roots(w, modes, c, t_new, Y_NEW, G_NEW)
    return True


@hot
def _dense(w: Vector, modes: np.ndarray, c: Vector) -> None:  # pragma: no cover - compiled
    """The step's dense output (SciPy's ``_dense_output_impl``): three more stages and ``F``."""
    if w[DENSE] != 0.0:
        return
    t_old, h = w[T_OLD], w[T_NEW] - w[T_OLD]
    for e in range(_A_EXTRA.shape[0]):
        _stage(w, modes, c, _A_EXTRA, e, _STAGES + 1 + e, Y_OLD, PHI_OLD, t_old + _C_EXTRA[e] * h, h)
    _coefficients_of(w, h, Y_OLD, Y_NEW, F_NEW, K_AT, F_AT, N)
    if w[TANGENT] != 0.0:
        _coefficients_of(w, h, PHI_OLD, PHI_NEW, PF_NEW, PK_AT, PF_AT, M)
    w[DENSE] = 1.0


@hot(inline=True)
def _coefficients_of(
    w: Vector, h: float, old: int, new: int, f_new: int, k: int, f: int, n: int
) -> None:  # pragma: no cover - compiled
    """The dense output's coefficients ``w[f:]`` of ``n`` values from ``w[old:]`` to ``w[new:]``
    with their stages at ``w[k:]`` (SciPy's ``_dense_output_impl``)."""
    for i in range(n):
        delta = w[new + i] - w[old + i]
        w[f + i] = delta
        w[f + n + i] = h * w[k + i] - delta
        w[f + 2 * n + i] = 2.0 * delta - h * (w[f_new + i] + w[k + i])
        for r in range(_POWER - 3):
            total = 0.0
            for j in range(_EXTENDED):
                total += _D[r, j] * w[k + n * j + i]
            w[f + n * (3 + r) + i] = h * total


@hot
def interpolate(w: Vector, t: float, out: int) -> None:  # pragma: no cover - compiled
    """``w[out:out + 8]`` = the state at ``t`` inside the last step, from its dense output
    (computed before)."""
    _interpolated(w, t, Y_OLD, Y_NEW, F_AT, out, N)


@hot(inline=True)
def _interpolated(
    w: Vector, t: float, old: int, new: int, f: int, out: int, n: int
) -> None:  # pragma: no cover - compiled
    """``w[out:out + n]`` at ``t`` from the dense output's coefficients ``w[f:]`` of the values at
    ``w[old:]`` and ``w[new:]``."""
    if t == w[T_NEW]:
        for i in range(n):
            w[out + i] = w[new + i]
        return
    x = (t - w[T_OLD]) / (w[T_NEW] - w[T_OLD])
    for i in range(n):
        total = 0.0
        for r in range(_POWER - 1, -1, -1):
            total += w[f + n * r + i]
            total *= x if (_POWER - 1 - r) % 2 == 0 else 1.0 - x
        w[out + i] = total + w[old + i]


@hot
def _output(w: Vector, t: float) -> None:  # pragma: no cover - compiled
    """The state at ``t`` inside the last step into ``Y_OUT``, and ``Phi`` into ``PHI_OUT`` where
    it is carried (the dense output computed before, unless ``t`` is the step's end)."""
    interpolate(w, t, Y_OUT)
    if w[TANGENT] != 0.0:
        _interpolated(w, t, PHI_OLD, PHI_NEW, PF_AT, PHI_OUT, M)


@hot
def _roots_at(w: Vector, modes: np.ndarray, c: Vector, t: float, g: int) -> None:  # pragma: no cover - compiled
    """``w[g:g + 11]`` = the root functions at ``t`` inside the last step."""
    interpolate(w, t, Y_TMP)
    _roots(w, modes, c, t, Y_TMP, g)


@hot
def _crossing(w: Vector, modes: np.ndarray, lo: int, hi: int) -> tuple[int, bool]:  # pragma: no cover - compiled
    """CVODE's test of a bracket (root values at ``w[lo:]`` and ``w[hi:]``): the root function
    whose sign change comes first (its linear estimate), or -1, and whether one is exactly zero
    at the upper end."""
    best, largest, zero = -1, 0.0, False
    for i in range(R):
        low, high = w[lo + i], w[hi + i]
        if modes[DIRECTIONS + i] * low > 0.0:
            continue
        if high == 0.0:
            zero = True
        elif low * high < 0.0:
            fraction = abs(high / (high - low))
            if fraction > largest:
                best, largest = i, fraction
    return best, zero


@hot
def _copy(w: Vector, source: int, target: int, n: int) -> None:  # pragma: no cover - compiled
    for i in range(n):
        w[target + i] = w[source + i]


@hot
def _locate(
    w: Vector, modes: np.ndarray, c: Vector, t_lo: float, t_hi: float, first: int
) -> tuple[float, int]:  # pragma: no cover - compiled
    """CVODE's ``cvRootfind`` between ``t_lo`` (values in ``G_LO``) and ``t_hi`` (``G_HI``): the
    first root's time and the roots there as bits (their values at it left in ``G_HI``)."""
    tolerance = _ROOT_TOLERANCE * (abs(w[T_NEW]) + abs(w[T_NEW] - w[T_OLD]))
    imax, side, previous, alpha = first, 0, -1, 1.0
    while imax >= 0 and abs(t_hi - t_lo) > tolerance:
        alpha = (alpha * 2.0 if side == 2 else alpha * 0.5) if previous == side else 1.0
        t_mid = t_hi - (t_hi - t_lo) * w[G_HI + imax] / (w[G_HI + imax] - alpha * w[G_LO + imax])
        span = abs(t_hi - t_lo)
        if abs(t_mid - t_lo) < 0.5 * tolerance:
            t_mid = t_lo + (0.1 if span / tolerance > 5.0 else 0.5 * tolerance / span) * (t_hi - t_lo)
        if abs(t_hi - t_mid) < 0.5 * tolerance:
            t_mid = t_hi - (0.1 if span / tolerance > 5.0 else 0.5 * tolerance / span) * (t_hi - t_lo)
        _roots_at(w, modes, c, t_mid, G_MID)
        previous = side
        found, zero = _crossing(w, modes, G_LO, G_MID)
        if found >= 0 or zero:
            t_hi = t_mid
            _copy(w, G_MID, G_HI, R)
            side = 1
            if found < 0:
                break
            imax = found
        else:
            t_lo = t_mid
            _copy(w, G_MID, G_LO, R)
            side = 2
    fired = 0
    for i in range(R):
        low, high = w[G_LO + i], w[G_HI + i]
        if modes[DIRECTIONS + i] * low > 0.0:
            continue
        if high == 0.0 or low * high < 0.0:
            fired |= 1 << i
    return t_hi, fired


@hot
def _lower_end(w: Vector, modes: np.ndarray, c: Vector) -> None:  # pragma: no cover - compiled
    """``G_LO`` from the values at the cursor; one exactly zero there takes its value a rounding
    step later (CVODE's ``cvRcheck2``), or is left out of this search."""
    zero = False
    for i in range(R):
        w[G_LO + i] = w[G_CUR + i]
        zero = zero or w[G_CUR + i] == 0.0
    if not zero:
        return
    t = w[T_CUR]
    later = t + _ROOT_TOLERANCE * (abs(t) + abs(w[T_NEW] - w[T_OLD]))
    if later >= w[T_NEW]:
        return
    _dense(w, modes, c)
    _roots_at(w, modes, c, later, G_MID)
    for i in range(R):
        if w[G_LO + i] == 0.0:
            # left out where it stays zero: the direction's own sign cannot cross
            w[G_LO + i] = w[G_MID + i] if w[G_MID + i] != 0.0 else float(modes[DIRECTIONS + i])


@hot
def advance(
    w: Vector, modes: np.ndarray, c: Vector, target: float, t_stop: float, one_step: bool
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Go on to the first root, ``target`` (``t_stop``) or, with ``one_step``, the end of one step.

    Returns what was reached (:data:`ROOT`, :data:`TARGET`, :data:`STEPPED_ONE`, or a failure's
    code) and the roots that fired as bits; the time is ``w[T_REF] + w[T_CUR]``, the state
    ``w[Y_OUT:]``."""
    target, t_stop = target - w[T_REF], t_stop - w[T_REF]
    steps = 0
    while True:
        if w[STEPPED] == 0.0 or w[T_CUR] >= w[T_NEW]:
            if w[T_CUR] >= t_stop:
                _output(w, w[T_NEW])
                return TARGET, 0
            steps += 1
            if steps > w[MAX_STEPS]:
                return TOO_MUCH_WORK, 0
            if not _step(w, modes, c, t_stop):
                return TOO_SMALL, 0
        t_hi = min(w[T_NEW], target)
        _lower_end(w, modes, c)
        if t_hi == w[T_NEW]:
            _copy(w, G_NEW, G_HI, R)
        else:
            _dense(w, modes, c)
            _roots_at(w, modes, c, t_hi, G_HI)
        first, zero = _crossing(w, modes, G_LO, G_HI)
        if first >= 0 or zero:
            _dense(w, modes, c)
            t_root, fired = _locate(w, modes, c, w[T_CUR], t_hi, first)
            _output(w, t_root)
            w[T_CUR] = t_root
            _copy(w, G_HI, G_CUR, R)
            return ROOT, fired
        w[T_CUR] = t_hi
        _copy(w, G_HI, G_CUR, R)
        if t_hi == target or t_hi >= t_stop:
            if t_hi < w[T_NEW]:
                _dense(w, modes, c)
            _output(w, t_hi)
            return TARGET, 0
        if one_step:
            _output(w, w[T_NEW])
            return STEPPED_ONE, 0


@hot
def grid_returns(
    w: Vector, modes: np.ndarray, c: Vector, grid: Vector, t_stop: float, rows: np.ndarray, last: Vector
) -> tuple[int, int, int, float]:  # pragma: no cover - compiled
    """:func:`advance` to each time of ``grid`` in turn, until a root, ``t_stop`` or a failure,
    at most ``len(rows)`` times: each grid time reached written as a row ``(t, x1, v1, x2, v2)``
    and its whole state into ``last``.  Returns the last return's kind and roots, the number of
    rows written and the time reached (the grid's own time for a row).  ``last`` is 24 long
    where the work carries ``Phi``."""
    most = min(rows.shape[0], grid.shape[0])
    n, kind, fired, t = 0, TARGET, 0, w[T_REF] + w[T_CUR]
    while n < most:
        kind, fired = advance(w, modes, c, grid[n], t_stop, False)
        if kind != TARGET:
            if kind == ROOT:
                t = w[T_REF] + w[T_CUR]
            break
        t = min(grid[n], t_stop)
        if t != grid[n]:  # the stop time, before the grid's next time
            break
        rows[n, 0] = t
        for k in range(4):
            rows[n, 1 + k] = w[Y_OUT + k]
        for k in range(N):
            last[k] = w[Y_OUT + k]
        if w[TANGENT] != 0.0:
            for k in range(M):
                last[N + k] = w[PHI_OUT + k]
        n += 1
    return kind, fired, n, t
