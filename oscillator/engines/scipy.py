"""SciPy's ``solve_ivp`` (DOP853 by default) with its events: the engine of the benchmarks' baseline.

What a SciPy user writes: one ``solve_ivp`` call per mode (and per time the supervisor asks to
reach, e.g. a grid time), one event function per root function
(memoised per ``(t, y)``, so SciPy pays one evaluation of the root vector per point it asks
about).  The extrema of a velocity and the relative velocity are watched, not terminal: SciPy
would stop at them and, restarted at a zero of the same function, stop there again.  The calls'
outputs are handed to the supervisor one return at a time: the watched roots, the steps when
asked for, and the terminal root or the end.
"""

from __future__ import annotations

import collections
from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

from oscillator.engines import EngineFailure, Step, StepKind
from oscillator.model.fields import coefficients
from oscillator.model.kernels import derivative
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.roots import NUM_ROOTS, Root, root_directions, root_values
from oscillator.model.types import StateLike, Vector

__all__ = ["WATCH_ONLY", "ScipyEngine"]

#: Root functions that are watched, not terminal.
WATCH_ONLY = (Root.EXTREMUM_1, Root.EXTREMUM_2, Root.RELATIVE_VELOCITY)

Field = Callable[[float, Vector, Mode], StateLike]

#: SciPy's explicit Runge-Kutta methods raise a smaller ``rtol`` to this, with a warning.
SCIPY_MIN_RTOL = 100 * float(np.finfo(float).eps)
#: Below this ``atol``, SciPy's error norm (``err / (atol + rtol |y|)``, squared) overflows where a
#: state component is zero (a mass at rest).
SCIPY_MIN_ATOL = 1e-100


def _check_tolerances(options: SolverOptions) -> None:
    """Refuse tolerances that SciPy would change behind the caller's back, or overflow on."""
    from oscillator.errors import InputError

    if options.rtol < SCIPY_MIN_RTOL:
        raise InputError(
            f"rtol = {options.rtol:g} is below what SciPy's solve_ivp accepts ({SCIPY_MIN_RTOL:.3g}: it "
            "would raise it to that); give a larger rtol, or the cvode engine",
            field="rtol",
        )
    if options.atol < SCIPY_MIN_ATOL:
        raise InputError(
            f"atol = {options.atol:g} is too small for SciPy's error norm (it overflows at a state "
            f"component of 0); give atol >= {SCIPY_MIN_ATOL:g}, or the cvode engine",
            field="atol",
        )


class ScipyEngine:
    """``solve_ivp`` with events, behind the :class:`~oscillator.engines.Engine` interface.

    Parameters
    ----------
    params, options : Parameters, SolverOptions
    method : str
        ``solve_ivp``'s method.
    field : callable, optional
        ``field(t, y, mode) -> dy/dt`` for the 8-vector ``y`` (state and work quadratures); the
        package's compiled field by default.
    roots : callable, optional
        ``roots(t, y, mode) -> g`` in the layout of :mod:`oscillator.model.roots`; the package's
        compiled root functions by default.
    quadratures : bool
        Integrate the four work quadratures of the energy audit with the state (the default).
        With ``False``, ``field`` returns the state's four rates only, SciPy's error norm is the
        state's, and the audit's works stay zero: what a SciPy user's script integrates.
    """

    name = "scipy"
    size = 8

    def __init__(
        self,
        params: Parameters,
        options: SolverOptions,
        *,
        method: str = "DOP853",
        field: Field | None = None,
        roots: Field | None = None,
        quadratures: bool = True,
    ) -> None:
        _check_tolerances(options)
        self._params, self._options, self._method = params, options, method
        self._max_step = options.max_step_fraction * params.period
        c, near = coefficients(params), options.grazing_displacement_tolerance

        def compiled_field(t: float, y: np.ndarray, mode: Mode) -> np.ndarray:
            rates = np.empty(8)
            derivative(t, y, rates, c, mode.sign(1), mode.sign(2), mode.left, mode.right)
            return rates

        def compiled_roots(t: float, y: np.ndarray, mode: Mode) -> np.ndarray:
            return root_values(t, y, params, mode, step=self._max_step, near=near)

        self._size = 8 if quadratures else 4
        self._field = field or compiled_field
        self._root_values = roots or compiled_roots
        self._mode: Mode | None = None
        self._t, self._y = 0.0, np.zeros(8)
        self._pending: collections.deque[Step] | None = None
        self._evaluations = 0
        self._restarts = 0

    @property
    def rhs_evaluations(self) -> int:
        return self._evaluations

    @property
    def restarts(self) -> int:
        return self._restarts

    def close(self) -> None:
        """Nothing to free."""
        self._pending = None

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        self._mode, self._t, self._y = mode, t, np.array(y, dtype=float)
        self._pending = None

    def _events(self, mode: Mode) -> list[Callable[..., float]]:
        cache: dict[tuple[float, bytes], StateLike] = {}

        def values(t: float, y: Vector) -> StateLike:
            key = (t, y.tobytes())
            if key not in cache:
                cache.clear()
                cache[key] = self._root_values(t, y, mode)
            return cache[key]

        watchers: list[Callable[..., float]] = []
        for index, direction in enumerate(root_directions(mode)):

            def watcher(t: float, y: np.ndarray, index: int = index) -> float:
                return float(values(t, y)[index])

            watcher.terminal = Root(index) not in WATCH_ONLY  # type: ignore[attr-defined]
            watcher.direction = direction  # type: ignore[attr-defined]
            watchers.append(watcher)
        return watchers

    def _solve(self, end: float, one_step: bool) -> None:
        """One ``solve_ivp`` call from the current point to ``end``; its returns queued in time order."""
        mode = self._mode
        assert mode is not None
        self._restarts += 1
        n = self._size
        solution = solve_ivp(
            lambda t, y: self._field(t, y, mode),
            (self._t, end),
            self._y[:n],
            method=self._method,
            rtol=self._options.rtol,
            atol=self._options.atol,
            events=self._events(mode),
            max_step=self._max_step,
        )
        self._evaluations += solution.nfev
        if solution.status == -1:
            raise EngineFailure(solution.message, "solve_ivp")
        reached = float(solution.t[-1])
        returns: list[tuple[float, int, Step]] = []
        for k in WATCH_ONLY:
            for tk, yk in zip(solution.t_events[k], solution.y_events[k], strict=True):
                if tk < reached:
                    returns.append((float(tk), 0, Step(float(tk), self._full(yk), StepKind.ROOT, (int(k),))))
        if one_step:
            returns += [
                (float(tk), 1, Step(float(tk), self._full(solution.y[:, i]), StepKind.STEP))
                for i, tk in enumerate(solution.t[1:-1], start=1)
            ]
        last = self._full(solution.y[:, -1])
        if solution.status == 1:  # a terminal root
            fired = tuple(
                k for k in range(NUM_ROOTS) if solution.t_events[k].size and solution.t_events[k][-1] == reached
            )
            returns.append((reached, 2, Step(reached, last, StepKind.ROOT, fired)))
        else:
            returns.append((end, 2, Step(end, last, StepKind.TARGET)))
        returns.sort(key=lambda item: (item[0], item[1]))
        self._pending = collections.deque(step for _, _, step in returns)

    def _full(self, y: Vector) -> Vector:
        """The 8-vector of a state SciPy returned (the quadratures zero when not integrated)."""
        full = np.zeros(8)
        full[: self._size] = y
        return full

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        if not self._pending:
            self._solve(t_stop if one_step else target, one_step)
        assert self._pending
        step = self._pending.popleft()
        self._t, self._y = step.t, step.y
        return step
