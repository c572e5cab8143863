"""CVODE for friction chains: one compiled field and one compiled set of root functions for every
chain (:mod:`oscillator.model.chain_fields`), called by CVODE through its C API.

The chain travels to the callbacks as CVODE's user data: the vector
:func:`~oscillator.model.chain_fields.pack` makes (counts, mode, masses, elements), whose length
the callbacks read from its head.  A new chain, or a new mode, is new data, not new code: nothing
is compiled after the first use of the class (numba caches the callbacks on disk).  The state is
the chain's (masses, sliders) followed by each element's work on the masses.
"""

from __future__ import annotations

import ctypes
import math
import weakref
from typing import Any

import numpy as np
from numba import types
from numba.np.numpy_support import carray

from oscillator.compiled import cfunc
from oscillator.engines import EngineFailure, Step, StepKind
from oscillator.engines.callbacks import DATA_OFFSET, _load_pointer
from oscillator.engines.cvode_c import CvodeObjects, check
from oscillator.engines.restarts import Restarts
from oscillator.engines.stepping import cvode_returns
from oscillator.engines.sundials import CV_SUCCESS, ERROR_HANDLER, describe
from oscillator.model.chain_fields import HEADER, ChainArrays, chain_derivative, data_length, pack, root_values
from oscillator.model.chain_rules import root_directions
from oscillator.model.parameters import SolverOptions

__all__ = ["ChainEngine"]

#: The stepping loop's grid when it takes CVODE's steps (no grid).
_NO_GRID = np.empty(0)

_SIGNATURE = types.int32(types.float64, types.voidptr, types.voidptr, types.voidptr)


@cfunc(_SIGNATURE, cache=True)
def chain_rhs(tau: float, y: Any, ydot: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRhsFn``: the chain's field and its elements' powers at ``t = t_ref + tau``."""
    head = carray(user_data, (len(HEADER),), dtype=np.float64)
    n, e = int(head[1]), int(head[2])
    d = carray(user_data, (data_length(n, e),), dtype=np.float64)
    size = int(head[3]) + e
    state = carray(_load_pointer(_load_pointer(y, 0), DATA_OFFSET), (size,), dtype=np.float64)
    out = carray(_load_pointer(_load_pointer(ydot, 0), DATA_OFFSET), (size,), dtype=np.float64)
    chain_derivative(d[0] + tau, state, out, d)
    return 0


@cfunc(_SIGNATURE, cache=True)
def chain_roots(tau: float, y: Any, gout: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRootFn``: two root functions per element (:func:`~oscillator.model.chain_fields.root_values`)."""
    head = carray(user_data, (len(HEADER),), dtype=np.float64)
    n, e = int(head[1]), int(head[2])
    d = carray(user_data, (data_length(n, e),), dtype=np.float64)
    size = int(head[3]) + e
    state = carray(_load_pointer(_load_pointer(y, 0), DATA_OFFSET), (size,), dtype=np.float64)
    g = carray(gout, (2 * e,), dtype=np.float64)
    root_values(d[0] + tau, state, d, g)
    return 0


class ChainEngine:
    """CVODE (Adams, dense Newton, rootfinding) on a chain's modes, its steps taken in compiled code."""

    name = "cvode"

    def __init__(self, arrays: ChainArrays, options: SolverOptions, *, max_step: float) -> None:
        self.arrays = arrays
        count = len(arrays.kind)
        #: The state's length: the chain's and the elements' works.
        self.size = arrays.size + count
        self._objects = CvodeObjects(self.size)
        self._api = api = self._objects.api
        self._messages: list[str] = []
        self._handler = ERROR_HANDLER(self._error)
        self._data = pack(arrays, np.zeros(count, dtype=np.int64))
        self._y = np.ctypeslib.as_array(api.N_VGetArrayPointer(self._objects.y), (self.size,))
        self._out = np.ctypeslib.as_array(api.N_VGetArrayPointer(self._objects.out), (self.size,))
        self._roots = 2 * count
        self._found = (ctypes.c_int * max(self._roots, 1))()
        self._tret = ctypes.c_double()
        self._finalizer = weakref.finalize(self, self._objects.free)
        self._clock = Restarts()
        self._t_stop = math.nan
        memory = self._objects.memory
        api.SUNContext_ClearErrHandlers(self._objects.context)
        api.SUNContext_PushErrHandler(self._objects.context, self._handler, None)
        check(api.CVodeInit(memory, ctypes.c_void_p(chain_rhs.address), 0.0, self._objects.y), "CVodeInit")
        check(api.CVodeSStolerances(memory, options.rtol, options.atol), "CVodeSStolerances")
        check(api.CVodeSetLinearSolver(memory, self._objects.solver, self._objects.matrix), "CVodeSetLinearSolver")
        check(api.CVodeSetUserData(memory, self._data.ctypes.data), "CVodeSetUserData")
        check(api.CVodeSetMaxNonlinIters(memory, 3), "CVodeSetMaxNonlinIters")
        check(api.CVodeSetMaxConvFails(memory, 10), "CVodeSetMaxConvFails")
        if self._roots:
            check(api.CVodeRootInit(memory, self._roots, ctypes.c_void_p(chain_roots.address)), "CVodeRootInit")
            check(api.CVodeSetNoInactiveRootWarn(memory), "CVodeSetNoInactiveRootWarn")
        check(api.CVodeSetMaxStep(memory, max_step), "CVodeSetMaxStep")
        check(api.CVodeSetMaxOrd(memory, 12), "CVodeSetMaxOrd")
        check(api.CVodeSetMaxNumSteps(memory, options.max_num_steps), "CVodeSetMaxNumSteps")
        self._directions: dict[tuple[int, ...], Any] = {}
        self._at_root = Step(0.0, self._y.copy(), StepKind.TARGET)
        self._addresses = (ctypes.cast(api.CVode, ctypes.c_void_p).value or 0, memory or 0)
        self._out_address = self._objects.out or 0
        self._tau, self._last = np.zeros(1), np.zeros(self.size)
        self._tau_address = self._tau.ctypes.data

    def _error(self, line: int, function: bytes, file: bytes, message: bytes, code: int, *_: Any) -> None:
        said = " ".join((message or b"").decode("utf-8", "replace").split())
        self._messages.append(f"[{(function or b'').decode('ascii', 'replace')}, Error: {code}] {said}")

    @property
    def restarts(self) -> int:
        return self._clock.count

    def close(self) -> None:
        """Free every SUNDIALS object of the engine."""
        self._finalizer()

    def reset(self, mode: np.ndarray, t: float, y: np.ndarray) -> None:
        """Integrate ``mode``'s field from ``(t, y)`` from now on."""
        key = tuple(int(s) for s in mode)
        self._data[len(HEADER) : len(HEADER) + len(key)] = key
        if self._roots:
            directions = self._directions.get(key)
            if directions is None:
                wanted = root_directions(self.arrays, mode)
                directions = self._directions[key] = (ctypes.c_int * self._roots)(*wanted)
            check(self._api.CVodeSetRootDirection(self._objects.memory, directions), "CVodeSetRootDirection")
        self._y[:] = y
        self._initialise(t)

    def _initialise(self, t: float) -> None:
        self._data[0] = t
        self._clock.restarted(t)
        self._messages.clear()
        check(self._api.CVodeReInit(self._objects.memory, 0.0, self._objects.y), "CVodeReInit")
        self._t_stop = math.nan

    def advance_steps(self, t_stop: float, rows: np.ndarray) -> tuple[Step, int]:
        """CVODE's steps taken in compiled code (:func:`~oscillator.engines.stepping.cvode_returns`)
        up to the first root or ``t_stop``, or until ``rows`` is full: each step a row (the time and
        the chain's state).  The last return as a :class:`Step`, and how many rows were written."""
        clock = self._clock
        flag, n = self._returns(t_stop, rows)
        reached = float(self._tau[0])
        if flag < 0:  # a failure after some steps: the steps first, the failure at the next call
            flag, reached = CV_SUCCESS, float(rows[n - 1, 0]) - clock.t_ref
        step = clock.step(
            flag, reached, self._last.copy(), target=t_stop, t_stop=t_stop, one_step=True, fired=self._fired
        )
        self._at_root = step
        return step, n

    def _returns(self, t_stop: float, rows: np.ndarray) -> tuple[int, int]:
        """The compiled loop's flag and rows: after a restart at a root CVODE refused, again; a
        failure before any step raised."""
        api, memory, clock = self._api, self._objects.memory, self._clock
        while True:
            if t_stop != self._t_stop:
                check(api.CVodeSetStopTime(memory, t_stop - clock.t_ref), "CVodeSetStopTime")
                self._t_stop = t_stop
            cvode, address = self._addresses
            where = (self._out_address, self._tau_address, self._tau, self._out, _NO_GRID, rows, self._last)
            flag, n = cvode_returns(cvode, address, clock.t_ref, t_stop, t_stop - clock.t_ref, *where)
            if n == 0 and clock.refused_at_root(flag):  # restart at the root just returned
                self._y[:] = self._at_root.y
                self._initialise(self._at_root.t)
                continue
            if flag < 0 and n == 0:
                said = " ".join(self._messages)
                raise EngineFailure(f"{describe(flag)}; CVODE: {said}" if said else describe(flag), flag)
            return int(flag), int(n)

    def _fired(self) -> tuple[int, ...]:
        self._api.CVodeGetRootInfo(self._objects.memory, self._found)
        return tuple(i for i in range(self._roots) if self._found[i])
