"""CVODE driven at C level: SUNDIALS' C API through ctypes, the callbacks compiled by numba.

The same integrator, settings and root functions as the scikit-sundae engine
(:mod:`oscillator.engines.sksundae`), without a Python call per field or root evaluation: CVODE
calls the compiled callbacks of :mod:`oscillator.engines.callbacks` directly.  One CVODE
problem serves every mode: at each restart the mode's flags go into the user data, and
``CVodeReInit`` and ``CVodeSetRootDirection`` restart it.  CVODE integrates in a local time
``tau = t - t_ref`` (see :mod:`oscillator.engines.sksundae` for why).

Every SUNDIALS object is freed by :meth:`CCvodeEngine.close` (also called when the engine is
garbage-collected); SUNDIALS' error messages go to the engine's failure, not to stderr.
"""

from __future__ import annotations

import ctypes
import math
import weakref
from typing import Any

import numpy as np

from oscillator.engines import EngineFailure, Step
from oscillator.engines import callbacks as cb
from oscillator.engines.restarts import Restarts
from oscillator.engines.stepping import cvode_returns
from oscillator.engines.sundials import (
    CV_ADAMS,
    CV_NORMAL,
    CV_ONE_STEP,
    CV_SUCCESS,
    ERROR_HANDLER,
    describe,
    flag_name,
    load,
)
from oscillator.model.fields import coefficients
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.roots import NUM_ROOTS, root_directions

__all__ = ["CCvodeEngine", "CvodeObjects", "check"]

#: The stepping loop's grid when it takes CVODE's steps (no grid).
_NO_GRID = np.empty(0)


def check(flag: int, call: str) -> None:
    """Raise :class:`EngineFailure` when a SUNDIALS call returned an error flag."""
    if flag < 0:
        raise EngineFailure(f"{call} failed ({flag_name(flag)})", flag)


class CvodeObjects:
    """The SUNDIALS objects of one CVODE problem of ``size`` equations (a serial vector for the
    state and one for the output, a dense matrix and solver, CVODE's memory), and their freeing
    (idempotent)."""

    def __init__(self, size: int = cb.SIZE) -> None:
        self.api = load().api
        self.context = ctypes.c_void_p()
        check(self.api.SUNContext_Create(0, ctypes.byref(self.context)), "SUNContext_Create")
        self.y = self.api.N_VNew_Serial(size, self.context)
        self.out = self.api.N_VNew_Serial(size, self.context)
        self.matrix = self.api.SUNDenseMatrix(size, size, self.context)
        self.solver = self.api.SUNLinSol_Dense(self.y, self.matrix, self.context) if self.matrix else None
        self.memory = self.api.CVodeCreate(CV_ADAMS, self.context)
        if not (self.y and self.out and self.matrix and self.solver and self.memory):
            self.free()
            raise MemoryError("SUNDIALS could not allocate the CVODE problem")

    def free(self) -> None:
        api = self.api
        if getattr(self, "memory", None):
            api.CVodeFree(ctypes.byref(ctypes.c_void_p(self.memory)))
            self.memory = None
        if getattr(self, "solver", None):
            api.SUNLinSolFree(self.solver)
            self.solver = None
        if getattr(self, "matrix", None):
            api.SUNMatDestroy(self.matrix)
            self.matrix = None
        for name in ("y", "out"):
            if getattr(self, name, None):
                api.N_VDestroy(getattr(self, name))
                setattr(self, name, None)
        if self.context:
            api.SUNContext_Free(ctypes.byref(self.context))
            self.context = ctypes.c_void_p()


class CCvodeEngine:
    """CVODE (Adams, dense Newton) with its rootfinding, called through its C API."""

    name = "cvode"

    def __init__(self, params: Parameters, options: SolverOptions, *, variational: bool = False) -> None:
        #: The state's length: 8, or 24 with the derivative of the flow (:mod:`oscillator.model.kernels`).
        self.size = cb.VARIATIONAL_SIZE if variational else cb.SIZE
        self._rhs = cb.variational_rhs() if variational else cb.rhs
        self._objects = CvodeObjects(self.size)
        self._api = self._objects.api
        self._messages: list[str] = []
        self._handler = ERROR_HANDLER(self._error)
        self._data = np.zeros(cb.USER_DATA_SIZE)
        self._data[cb.COEFFICIENTS :] = coefficients(params)
        self._data[cb.LAYOUT["step"]] = options.max_step_fraction * params.period
        self._data[cb.LAYOUT["near"]] = options.grazing_displacement_tolerance
        self._y = np.ctypeslib.as_array(self._api.N_VGetArrayPointer(self._objects.y), (self.size,))
        self._out = np.ctypeslib.as_array(self._api.N_VGetArrayPointer(self._objects.out), (self.size,))
        self._found = (ctypes.c_int * NUM_ROOTS)()
        self._directions: dict[Mode, Any] = {}  # mode -> its root directions as a C array
        self._tret = ctypes.c_double()
        self._evaluations = ctypes.c_long()
        self._finalizer = weakref.finalize(self, self._objects.free)
        self._setup(options)
        self._t, self._t_stop, self._clock = 0.0, math.nan, Restarts()
        # what the compiled stepping loop takes: CVODE's address, the objects' addresses
        self._addresses = (
            ctypes.cast(self._api.CVode, ctypes.c_void_p).value or 0,
            self._objects.memory or 0,
            self._objects.out or 0,
        )
        self._tau, self._last = np.zeros(1), np.zeros(self.size)
        self._tau_address = self._tau.ctypes.data
        self._failure: EngineFailure | None = None  # met by the stepping loop after some steps: raised next
        self._out_at_root: np.ndarray = np.zeros(self.size)
        self._done_evaluations = 0

    def _setup(self, options: SolverOptions) -> None:
        api, memory = self._api, self._objects.memory
        api.SUNContext_ClearErrHandlers(self._objects.context)
        api.SUNContext_PushErrHandler(self._objects.context, self._handler, None)
        check(api.CVodeInit(memory, ctypes.c_void_p(self._rhs.address), 0.0, self._objects.y), "CVodeInit")
        check(api.CVodeSStolerances(memory, options.rtol, options.atol), "CVodeSStolerances")
        check(api.CVodeSetLinearSolver(memory, self._objects.solver, self._objects.matrix), "CVodeSetLinearSolver")
        check(api.CVodeSetUserData(memory, self._data.ctypes.data), "CVodeSetUserData")
        check(api.CVodeSetMaxNonlinIters(memory, 3), "CVodeSetMaxNonlinIters")
        check(api.CVodeSetMaxConvFails(memory, 10), "CVodeSetMaxConvFails")
        check(api.CVodeRootInit(memory, NUM_ROOTS, ctypes.c_void_p(cb.roots.address)), "CVodeRootInit")
        # a root function identically zero at a restart (a mass at rest under no force at all) is
        # watched no more by CVODE until it moves: nothing to warn about (SUNDIALS' logger printed
        # a warning on stdout at each restart, into the command's output)
        check(api.CVodeSetNoInactiveRootWarn(memory), "CVodeSetNoInactiveRootWarn")
        check(api.CVodeSetInitStep(memory, 0.0), "CVodeSetInitStep")
        check(api.CVodeSetMinStep(memory, 0.0), "CVodeSetMinStep")
        check(api.CVodeSetMaxStep(memory, float(self._data[cb.LAYOUT["step"]])), "CVodeSetMaxStep")
        check(api.CVodeSetMaxOrd(memory, 12), "CVodeSetMaxOrd")
        check(api.CVodeSetMaxNumSteps(memory, options.max_num_steps), "CVodeSetMaxNumSteps")

    def _error(self, line: int, function: bytes, file: bytes, message: bytes, code: int, *_: Any) -> None:
        """SUNDIALS' error handler: keep the message for the failure (nothing is printed)."""
        said = " ".join((message or b"").decode("utf-8", "replace").replace(", ,", ",").split())
        self._messages.append(f"[{(function or b'').decode('ascii', 'replace')}, Error: {code}] {said}")

    @property
    def rhs_evaluations(self) -> int:
        if self._objects.memory:
            self._api.CVodeGetNumRhsEvals(self._objects.memory, ctypes.byref(self._evaluations))
        return self._done_evaluations + self._evaluations.value

    @property
    def restarts(self) -> int:
        return self._clock.count

    def close(self) -> None:
        """Free every SUNDIALS object of the engine (it cannot be used afterwards)."""
        self._finalizer()

    def _initialise(self) -> None:
        memory = self._objects.memory
        self._api.CVodeGetNumRhsEvals(memory, ctypes.byref(self._evaluations))  # the counts restart
        self._done_evaluations += self._evaluations.value
        self._evaluations.value = 0
        self._data[cb.LAYOUT["t_ref"]] = self._t
        self._clock.restarted(self._t)
        self._messages.clear()
        check(self._api.CVodeReInit(memory, 0.0, self._objects.y), "CVodeReInit")
        self._t_stop = math.nan  # set again before the next step

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        data = self._data
        data[cb.LAYOUT["s1"]], data[cb.LAYOUT["s2"]] = mode.sign(1), mode.sign(2)
        data[cb.LAYOUT["left"]], data[cb.LAYOUT["right"]] = float(mode.left), float(mode.right)
        directions = self._directions.get(mode)
        if directions is None:
            directions = self._directions[mode] = (ctypes.c_int * NUM_ROOTS)(*root_directions(mode))
        check(self._api.CVodeSetRootDirection(self._objects.memory, directions), "CVodeSetRootDirection")
        self._t = t
        self._y[:] = y
        self._failure = None
        self._initialise()

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        api, memory, clock = self._api, self._objects.memory, self._clock
        while True:
            if t_stop != self._t_stop:  # once per restart: CVODE keeps it until it is reached
                check(api.CVodeSetStopTime(memory, t_stop - clock.t_ref), "CVodeSetStopTime")
                self._t_stop = t_stop
            mode = CV_ONE_STEP if one_step else CV_NORMAL
            flag = api.CVode(memory, target - clock.t_ref, self._objects.out, ctypes.byref(self._tret), mode)
            if clock.refused_at_root(flag):
                self._y[:] = self._out_at_root
                self._initialise()  # at the root just returned
                continue
            if flag < 0:
                said = " ".join(self._messages)
                raise EngineFailure(f"{describe(flag)}; CVODE: {said}" if said else describe(flag), flag)
            break
        step = clock.step(
            flag, self._tret.value, self._out.copy(), target=target, t_stop=t_stop, one_step=one_step, fired=self._fired
        )
        self._t, self._out_at_root = step.t, step.y
        return step

    def advance_steps(self, target: float, *, t_stop: float, rows: np.ndarray) -> tuple[Step, int]:
        """:meth:`advance` with ``one_step`` repeated in compiled code (:mod:`oscillator.engines.stepping`)
        until a root, ``t_stop`` or ``target``, or ``len(rows)`` returns: each return written as
        a row ``(t, x1, v1, x2, v2)`` of ``rows``.  The last return as a :class:`Step`, and how
        many rows were written (the last one its row)."""
        flag, n = self._returns(_NO_GRID, target, t_stop, rows)
        clock = self._clock
        reached = float(self._tau[0]) if self._failure is None else float(rows[n - 1, 0]) - clock.t_ref
        step = clock.step(
            flag, reached, self._last.copy(), target=target, t_stop=t_stop, one_step=True, fired=self._fired
        )
        self._t, self._out_at_root = step.t, step.y
        return step, n

    def advance_grid(self, grid: np.ndarray, *, t_stop: float, rows: np.ndarray) -> tuple[Step, int]:
        """:meth:`advance` to each time of ``grid`` in turn, in compiled code
        (:mod:`oscillator.engines.stepping`), until a root or ``t_stop``, at most ``len(rows)``
        times: each time reached written as a row ``(t, x1, v1, x2, v2)``.  The last return as a
        :class:`Step`, and how many rows were written."""
        flag, n = self._returns(grid, float(grid[0]), t_stop, rows)
        clock = self._clock
        if flag == CV_SUCCESS:  # the last grid time reached (or the state before a failure)
            y, target = self._last.copy(), float(grid[n - 1])
        else:  # a root before grid[n], or the stop time
            y, target = self._out.copy(), float(grid[min(n, len(grid) - 1)])
        step = clock.step(flag, float(self._tau[0]), y, target=target, t_stop=t_stop, one_step=False, fired=self._fired)
        self._t, self._out_at_root = step.t, step.y
        return step, n

    def _returns(self, grid: np.ndarray, target: float, t_stop: float, rows: np.ndarray) -> tuple[int, int]:
        """CVODE's returns in compiled code (:func:`~oscillator.engines.stepping.cvode_returns`):
        the stop time set, a close-roots refusal after a root cleared by a restart there, a
        failure raised (or kept for the next call when returns preceded it)."""
        api, memory, clock = self._api, self._objects.memory, self._clock
        cvode, address, out = self._addresses
        self._raise_pending()
        while True:
            if t_stop != self._t_stop:  # once per restart: CVODE keeps it until it is reached
                check(api.CVodeSetStopTime(memory, t_stop - clock.t_ref), "CVodeSetStopTime")
                self._t_stop = t_stop
            tau = self._tau
            flag, n = cvode_returns(
                cvode,
                address,
                clock.t_ref,
                t_stop,
                target - clock.t_ref,
                out,
                self._tau_address,
                tau,
                self._out,
                grid,
                rows,
                self._last,
            )
            if n == 0 and clock.refused_at_root(flag):
                self._y[:] = self._out_at_root
                self._initialise()  # at the root just returned
                continue
            return self._failed(flag, n), n

    def _raise_pending(self) -> None:
        if self._failure is not None:
            failure, self._failure = self._failure, None
            raise failure

    def _failed(self, flag: int, n: int) -> int:
        """A failure of CVODE inside a compiled loop: raised at once when no return preceded it,
        else kept for the next call (the returns before it first, as one call each would have
        told them) and the flag read as a success."""
        if flag >= 0:
            return flag
        said = " ".join(self._messages)
        failure = EngineFailure(f"{describe(flag)}; CVODE: {said}" if said else describe(flag), flag)
        if n == 0:
            raise failure
        self._failure = failure
        return CV_SUCCESS

    def _fired(self) -> tuple[int, ...]:
        """The roots of the last return (CVODE's root information)."""
        found = self._found
        self._api.CVodeGetRootInfo(self._objects.memory, found)
        return tuple(i for i in range(NUM_ROOTS) if found[i])
