"""CVODE's steps taken in compiled code: the loop that records the trajectory at every step.

With the trajectory kept at the solver's steps, CVODE returns after each internal step
(``CV_ONE_STEP``); a return to Python for each (a few microseconds of the interpreter, two array
copies, a row object) costs more than the step.  :func:`cvode_returns` calls CVODE in a compiled
loop instead, through its C function pointer (an address passed as an integer, so that the
loop is compiled once and cached like the callbacks), writes each return as a row
``(t, x1, v1, x2, v2)`` into a preallocated buffer, and comes back to Python only at a root, at
the stop time or the target, on a failure, or when the buffer is full.
"""

from __future__ import annotations

from typing import Any

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from oscillator.compiled import njit
from oscillator.engines.sundials import CV_NORMAL, CV_ONE_STEP, CV_ROOT_RETURN, CV_SUCCESS

__all__ = ["cvode_returns"]


def _call_cvode_typing(
    typingctx: Any, function: Any, memory: Any, tout: Any, yout: Any, tret: Any, itask: Any
) -> Any:  # pragma: no cover - compiled
    """``CVode(memory, tout, yout, &tret, itask)`` through the function's address: every pointer an
    integer (``int CVode(void*, sunrealtype, N_Vector, sunrealtype*, int)``, cvode.h)."""
    signature = types.int32(types.intp, types.intp, types.float64, types.intp, types.intp, types.int32)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        function_, memory_, tout_, yout_, tret_, itask_ = args
        pointer = ir.IntType(8).as_pointer()
        double_pointer = ir.DoubleType().as_pointer()
        prototype = ir.FunctionType(ir.IntType(32), [pointer, ir.DoubleType(), pointer, double_pointer, ir.IntType(32)])
        callee = builder.inttoptr(function_, prototype.as_pointer())
        arguments = [
            builder.inttoptr(memory_, pointer),
            tout_,
            builder.inttoptr(yout_, pointer),
            builder.inttoptr(tret_, double_pointer),
            itask_,
        ]
        return builder.call(callee, arguments)

    return signature, codegen


_call_cvode: Any = intrinsic(_call_cvode_typing)

_ROWS = types.Array(types.float64, 2, "C")
_VECTOR = types.Array(types.float64, 1, "C")


@njit(
    types.Tuple((types.int32, types.int64))(
        types.intp,
        types.intp,
        types.float64,
        types.float64,
        types.float64,
        types.intp,
        types.intp,
        _VECTOR,
        _VECTOR,
        _VECTOR,
        _ROWS,
        _VECTOR,
    ),
    cache=True,
)
def cvode_returns(  # pragma: no cover - compiled
    cvode: int,
    memory: int,
    t_ref: float,
    t_stop: float,
    tau_target: float,
    yout: int,
    tret_address: int,
    tret: Any,
    out: Any,
    grid: Any,
    rows: Any,
    last: Any,
) -> tuple[int, int]:
    """CVODE's returns, each written as a row ``(t, x1, v1, x2, v2)`` of ``rows`` (the time and
    the state's first ``rows.shape[1] - 1`` values: a friction chain's masses and sliders), at most
    ``len(rows)``, until a root, the stop time or a failure:

    * with an empty ``grid``, its steps (``CV_ONE_STEP``) up to ``tau_target``: every return a
      row, at ``t_ref + tau``;
    * else, in turn to each time of ``grid`` (``CV_NORMAL``): a row for each time reached (the
      stop time's only when it is the grid's time; a root's return writes none).

    ``tret`` is the one-element array at ``tret_address`` where CVODE writes the time it reached,
    ``out`` the data of the output vector ``yout``; ``last`` receives the whole output (state,
    works and any variational entries) of the last return that wrote a row.  Returns CVODE's
    last flag (a failure's, negative, with no row for it) and the number of rows written.
    """
    on_grid = grid.shape[0] > 0
    most = min(rows.shape[0], grid.shape[0]) if on_grid else rows.shape[0]
    n = 0
    flag = CV_SUCCESS
    while n < most:
        if on_grid:
            flag = _call_cvode(cvode, memory, grid[n] - t_ref, yout, tret_address, CV_NORMAL)
            if flag < 0 or flag == CV_ROOT_RETURN:
                break
            t = grid[n] if flag == CV_SUCCESS else t_stop
            if t != grid[n]:
                break
        else:
            flag = _call_cvode(cvode, memory, tau_target, yout, tret_address, CV_ONE_STEP)
            if flag < 0:
                break
            t = t_ref + tret[0]
        rows[n, 0] = t
        for k in range(rows.shape[1] - 1):
            rows[n, 1 + k] = out[k]
        for k in range(out.shape[0]):  # not last[:] = out: its shape check compiles numba's string formatting (2.5 s)
            last[k] = out[k]
        n += 1
        if flag != CV_SUCCESS or (not on_grid and tret[0] >= tau_target):
            break
    return flag, n
