"""The flow of one mode and its derivative: the state and the variational equations together.

In a mode the field ``f(t, y) = (v1, F1, v2, F2)`` (4.9)-(4.14) is smooth, and the derivative of
its flow ``Phi = d y(t) / d y(t_a)`` solves ``Phi' = J(t, y) Phi``, ``Phi(t_a) = I`` with
``J = df/dy`` (:func:`jacobian`).  CVODE integrates the 4 + 16 equations at C level, with the
Jacobian compiled as a C callback like the engine's field (:mod:`oscillator.engines.callbacks`),
between switching times that the simulation has already found: no root finding here.
"""

from __future__ import annotations

import ctypes
import weakref
from typing import Any

import numpy as np
from numba.np.numpy_support import carray

from oscillator.compiled import cfunc, njit
from oscillator.engines import EngineFailure
from oscillator.engines import callbacks as cb
from oscillator.engines.cvode_c import CvodeObjects, check
from oscillator.engines.sundials import CV_NORMAL, ERROR_HANDLER, describe
from oscillator.model.fields import C1, C2, C3, C4, C5, K1, K2, K3, K4, K5, K6, M1, M2, coefficients
from oscillator.model.kernels import state_field
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.types import Vector

__all__ = ["SIZE", "ModeFlow", "field_jacobian", "jacobian"]

#: The state and the 4 x 4 derivative of the flow, row by row.
SIZE = 20


@njit(cache=True)
def jacobian(  # pragma: no cover - compiled
    x1: float, v1: float, x2: float, v2: float, c: Vector, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:
    """Fill ``out`` (16, row by row) with ``df/dy`` of the mode's field.

    For a moving mass, row ``x_i`` is ``dx_i'/dy = e_(v_i)`` and row ``v_i`` is ``dA_i/dy`` (the
    friction term ``s_i (mu_k g + p_i)`` is constant in a mode).  A resting mass's field is
    ``(0, 0)`` whatever the state (4.12): both its rows are zero, so a displacement of a resting
    mass stays as it is (it rests where it was put) and nothing moves it.  Its velocity
    perturbation is removed where the rest begins (:func:`oscillator.orbits.saltation.rest_projection`).
    """
    for k in range(16):
        out[k] = 0.0
    if s1 != 0:
        out[1] = 1.0
        out[4] = (-c[K1] - 3.0 * c[K2] * x1 * x1 - (c[K3] if left else 0.0) - (c[K6] if right else 0.0)) / c[M1]
        out[5] = (-c[C1] - 3.0 * c[C2] * v1 * v1 - (c[C3] if left else 0.0)) / c[M1]
        if left:
            out[6] = c[K3] / c[M1]
            out[7] = c[C3] / c[M1]
    if s2 != 0:
        out[11] = 1.0
        out[14] = (-c[K4] - 3.0 * c[K5] * x2 * x2 - (c[K3] if left else 0.0)) / c[M2]
        out[15] = (-c[C4] - 3.0 * c[C5] * v2 * v2 - (c[C3] if left else 0.0)) / c[M2]
        if left:
            out[12] = c[K3] / c[M2]
            out[13] = c[C3] / c[M2]


@njit(cache=True)
def variational_derivative(  # pragma: no cover - compiled
    t: float, y: Vector, yp: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> None:
    """``(f(t, y), J(t, y) Phi)`` for the 20-vector ``(y, Phi)``."""
    state_field(t, y, yp, c, s1, s2, left, right)
    j = np.empty(16)
    jacobian(y[0], y[1], y[2], y[3], c, s1, s2, left, right, j)
    for row in range(4):
        for col in range(4):
            total = 0.0
            for k in range(4):
                total += j[4 * row + k] * y[4 + 4 * k + col]
            yp[4 + 4 * row + col] = total


@cfunc(cb._SIGNATURE, cache=True)
def variational_rhs(tau: float, y: Any, ydot: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRhsFn`` of the 20 equations at ``t = t_ref + tau`` (the engine's user-data layout)."""
    d = carray(user_data, (cb.USER_DATA_SIZE,), dtype=np.float64)
    state = carray(cb._load_pointer(cb._load_pointer(y, 0), cb.DATA_OFFSET), (SIZE,), dtype=np.float64)
    rates = carray(cb._load_pointer(cb._load_pointer(ydot, 0), cb.DATA_OFFSET), (SIZE,), dtype=np.float64)
    variational_derivative(
        d[0] + tau, state, rates, d[cb.COEFFICIENTS :], int(d[1]), int(d[2]), d[3] != 0.0, d[4] != 0.0
    )
    return 0


def field_jacobian(y: np.ndarray, p: Parameters, mode: Mode) -> np.ndarray:
    """``df/dy`` (4 x 4) of ``mode``'s field at ``y`` (it does not depend on ``t``)."""
    out = np.empty(16)
    jacobian(
        float(y[0]),
        float(y[1]),
        float(y[2]),
        float(y[3]),
        coefficients(p),
        mode.sign(1),
        mode.sign(2),
        mode.left,
        mode.right,
        out,
    )
    return out.reshape(4, 4)


class ModeFlow:
    """The flow of one mode and its derivative over ``[t_a, t_b]``, by CVODE at C level.

    One object serves every mode and segment of a run; :meth:`close` frees its SUNDIALS objects
    (also done when it is garbage-collected).

    Parameters
    ----------
    params : Parameters
    rtol, atol : float
        CVODE's tolerances for the state and the derivative together.
    max_steps : int
        CVODE's step limit per segment.
    """

    def __init__(self, params: Parameters, *, rtol: float = 1e-11, atol: float = 1e-11, max_steps: int = 200_000):
        self._objects = CvodeObjects(SIZE)
        self._api = api = self._objects.api
        self._messages: list[str] = []
        self._handler = ERROR_HANDLER(self._error)
        self._data = np.zeros(cb.USER_DATA_SIZE)
        self._data[cb.COEFFICIENTS :] = coefficients(params)
        self._y = np.ctypeslib.as_array(api.N_VGetArrayPointer(self._objects.y), (SIZE,))
        self._out = np.ctypeslib.as_array(api.N_VGetArrayPointer(self._objects.out), (SIZE,))
        self._tret = ctypes.c_double()
        self._finalizer = weakref.finalize(self, self._objects.free)
        memory = self._objects.memory
        api.SUNContext_ClearErrHandlers(self._objects.context)
        api.SUNContext_PushErrHandler(self._objects.context, self._handler, None)
        check(api.CVodeInit(memory, ctypes.c_void_p(variational_rhs.address), 0.0, self._objects.y), "CVodeInit")
        check(api.CVodeSStolerances(memory, rtol, atol), "CVodeSStolerances")
        check(api.CVodeSetLinearSolver(memory, self._objects.solver, self._objects.matrix), "CVodeSetLinearSolver")
        check(api.CVodeSetUserData(memory, self._data.ctypes.data), "CVodeSetUserData")
        check(api.CVodeSetMaxStep(memory, 0.05 * params.period), "CVodeSetMaxStep")
        check(api.CVodeSetMaxNumSteps(memory, max_steps), "CVodeSetMaxNumSteps")
        self.restarts = 0

    def _error(self, line: int, function: bytes, file: bytes, message: bytes, code: int, *_: Any) -> None:
        self._messages.append(" ".join((message or b"").decode("utf-8", "replace").split()))

    def close(self) -> None:
        """Free the SUNDIALS objects."""
        self._finalizer()

    def __call__(self, mode: Mode, t_a: float, y_a: np.ndarray, t_b: float) -> tuple[np.ndarray, np.ndarray]:
        """``(y(t_b), Phi(t_b, t_a))`` of ``mode``'s flow from ``y(t_a) = y_a``."""
        y_a = np.asarray(y_a, dtype=float)[:4]
        if t_b <= t_a:
            return y_a.copy(), np.eye(4)
        data, api, memory = self._data, self._api, self._objects.memory
        data[cb.LAYOUT["t_ref"]] = t_a
        data[cb.LAYOUT["s1"]], data[cb.LAYOUT["s2"]] = mode.sign(1), mode.sign(2)
        data[cb.LAYOUT["left"]], data[cb.LAYOUT["right"]] = float(mode.left), float(mode.right)
        self._y[:4] = y_a
        self._y[4:] = np.eye(4).ravel()
        self._messages.clear()
        check(api.CVodeReInit(memory, 0.0, self._objects.y), "CVodeReInit")
        check(api.CVodeSetStopTime(memory, t_b - t_a), "CVodeSetStopTime")
        self.restarts += 1
        flag = api.CVode(memory, t_b - t_a, self._objects.out, ctypes.byref(self._tret), CV_NORMAL)
        if flag < 0:
            said = " ".join(self._messages)
            raise EngineFailure(f"{describe(flag)}; CVODE: {said}" if said else describe(flag), flag)
        return self._out[:4].copy(), self._out[4:].reshape(4, 4).copy()
