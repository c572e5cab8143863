"""The ``"dop853"`` engine: the compiled DOP853 of :mod:`oscillator.engines.dop853` behind the
:class:`~oscillator.engines.Engine` interface that the supervisor drives, with the derivative of
the flow carried along where asked (the period maps of :mod:`oscillator.orbits.shooting`)."""

from __future__ import annotations

import numpy as np

from oscillator.engines import EngineFailure, Step, StepKind
from oscillator.engines.dop853 import (
    DIRECTIONS,
    EVALS,
    FAILURES,
    PHI_OUT,
    ROOT,
    STEPPED_ONE,
    T_CUR,
    T_REF,
    TARGET,
    Y_OUT,
    M,
    N,
    R,
    advance,
    grid_returns,
    mode_vector,
    new_work,
    restart,
)
from oscillator.model.fields import coefficients
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode

__all__ = ["Dop853Engine"]

_KINDS = {ROOT: StepKind.ROOT, TARGET: StepKind.TARGET, STEPPED_ONE: StepKind.STEP}


class Dop853Engine:
    """The compiled DOP853 of this module behind the :class:`~oscillator.engines.Engine` interface;
    with ``variational``, the derivative of the flow is carried with the state (24 values)."""

    name = "dop853"

    def __init__(self, params: Parameters, options: SolverOptions, *, variational: bool = False) -> None:
        self._c = coefficients(params)
        self._w = new_work(params, options, tangent=variational)
        #: The state's length: 8, or 24 with the derivative of the flow.
        self.size = N + M if variational else N
        self._modes: dict[Mode, np.ndarray] = {}
        self._mode = np.zeros(DIRECTIONS + R, np.int64)
        self._restarts = 0
        self._last = np.zeros(self.size)
        self._pending: EngineFailure | None = None  # met by the grid loop after some rows: raised next

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        vector = self._modes.get(mode)
        if vector is None:
            vector = self._modes[mode] = mode_vector(mode)
        self._mode = vector
        restart(self._w, vector, self._c, float(t), np.ascontiguousarray(y[: self.size], dtype=np.float64))
        self._restarts += 1

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        w = self._w
        self._raise_pending()
        kind, fired = advance(w, self._mode, self._c, float(target), float(t_stop), one_step)
        if kind < 0:
            raise EngineFailure(FAILURES[kind], kind)
        roots = tuple(i for i in range(R) if fired >> i & 1)
        # a target is returned at its own time, as CVODE's engines do (t_ref + tau may differ by an ulp)
        t = min(float(target), float(t_stop)) if kind == TARGET else float(w[T_REF] + w[T_CUR])
        return Step(t, self._out(), _KINDS[kind], roots)

    def _out(self) -> np.ndarray:
        """The state returned (with ``Phi`` where it is carried), a fresh array."""
        w = self._w
        if self.size == N:
            return w[Y_OUT : Y_OUT + N].copy()
        return np.concatenate((w[Y_OUT : Y_OUT + N], w[PHI_OUT : PHI_OUT + M]))

    def advance_grid(self, grid: np.ndarray, *, t_stop: float, rows: np.ndarray) -> tuple[Step, int]:
        """:meth:`advance` to each time of ``grid`` in turn, in compiled code (:func:`grid_returns`),
        until a root or ``t_stop``, at most ``len(rows)`` times: each time reached written as a
        row ``(t, x1, v1, x2, v2)``.  The last return as a :class:`Step`, and how many rows were
        written (a failure after some rows is raised at the next call, as CVODE's engine does)."""
        self._raise_pending()
        w = self._w
        kind, fired, n, t = grid_returns(w, self._mode, self._c, grid, float(t_stop), rows, self._last)
        if kind < 0:
            failure = EngineFailure(FAILURES[kind], kind)
            if n == 0:
                raise failure
            self._pending = failure
            return Step(float(rows[n - 1, 0]), self._last.copy(), StepKind.TARGET, ()), n
        roots = tuple(i for i in range(R) if fired >> i & 1)
        return Step(float(t), self._out(), _KINDS[kind], roots), n

    def _raise_pending(self) -> None:
        failure, self._pending = self._pending, None
        if failure is not None:
            raise failure

    @property
    def rhs_evaluations(self) -> int:
        return int(self._w[EVALS])

    @property
    def restarts(self) -> int:
        return self._restarts

    def close(self) -> None:
        """Nothing to free: the engine's state is one array."""
