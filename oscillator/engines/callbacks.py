"""CVODE's callbacks compiled to C (numba ``@cfunc``): the field and the root functions of a mode.

They call the package's compiled kernels, inlined (:func:`oscillator.model.kernels.rates`,
:func:`oscillator.model.roots.root_values_at`) on the data of CVODE's serial vectors; what changes
from mode to mode travels in the user-data vector (:data:`LAYOUT`).  numba caches the compiled
callbacks on disk (``cache=True``), so the compile cost is paid once per install.

A serial ``N_Vector`` is ``struct {void* content; ...}`` with ``content`` a
``struct {sunindextype length; sunbooleantype own_data; sunrealtype* data; ...}``
(nvector_serial.h); :func:`data_offset` finds ``data``'s offset and the engine checks it against
``N_VGetArrayPointer`` once per process.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.np.numpy_support import carray

from oscillator.compiled import cfunc
from oscillator.model.kernels import rates, variational_derivative
from oscillator.model.parameters import Parameters
from oscillator.model.roots import NUM_ROOTS, root_values_at
from oscillator.model.types import VARIATIONAL

__all__ = [
    "COEFFICIENTS",
    "LAYOUT",
    "USER_DATA_SIZE",
    "VARIATIONAL_SIZE",
    "data_offset",
    "rhs",
    "roots",
    "variational_rhs",
]

#: Positions in the user-data vector.
LAYOUT = {"t_ref": 0, "s1": 1, "s2": 2, "left": 3, "right": 4, "step": 5, "near": 6}
#: Where the parameter vector starts in the user data: after the layout.
COEFFICIENTS = len(LAYOUT)
#: The user data's length: the layout and the parameters (:func:`~oscillator.model.fields.coefficients`).
USER_DATA_SIZE = COEFFICIENTS + len(Parameters.names())
#: The state's length: x1, v1, x2, v2 and the four work quadratures.
SIZE = 8
#: With the derivative of the flow carried along: and ``Phi``'s 16 entries (:mod:`oscillator.model.kernels`).
VARIATIONAL_SIZE = VARIATIONAL + 16
#: Byte offset of ``data`` in the serial vector's content: ``sunindextype`` (int32) and
#: ``sunbooleantype`` (int) before it.
DATA_OFFSET = 8


def _load_pointer_typing(typingctx: Any, address: Any, offset: Any) -> Any:  # pragma: no cover - compiled
    """The pointer stored at ``address + offset`` bytes (a ``void*`` read from C memory)."""
    signature = types.voidptr(types.voidptr, types.intp)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        base = builder.ptrtoint(args[0], ir.IntType(64))
        where = builder.inttoptr(builder.add(base, args[1]), cgutils.voidptr_t.as_pointer())
        return builder.load(where)

    return signature, codegen


_load_pointer: Any = intrinsic(_load_pointer_typing)


def data_offset() -> int:
    """Byte offset of the data pointer in a serial vector's content (see the module's docstring)."""
    return DATA_OFFSET


_SIGNATURE = types.int32(types.float64, types.voidptr, types.voidptr, types.voidptr)


@cfunc(_SIGNATURE, cache=True)
def rhs(tau: float, y: Any, ydot: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRhsFn``: the mode's field at ``t = t_ref + tau`` (CVODE's time is local)."""
    d = carray(user_data, (USER_DATA_SIZE,), dtype=np.float64)
    state = carray(_load_pointer(_load_pointer(y, 0), DATA_OFFSET), (SIZE,), dtype=np.float64)
    out = carray(_load_pointer(_load_pointer(ydot, 0), DATA_OFFSET), (SIZE,), dtype=np.float64)
    r = rates(
        d[0] + tau,
        state[0],
        state[1],
        state[2],
        state[3],
        d[COEFFICIENTS:],
        int(d[1]),
        int(d[2]),
        d[3] != 0.0,
        d[4] != 0.0,
    )
    out[0], out[1], out[2], out[3] = r[0], r[1], r[2], r[3]
    out[4], out[5], out[6], out[7] = r[4], r[5], r[6], r[7]
    return 0


def _variational_rhs(tau: float, y: Any, ydot: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRhsFn`` of the state, the works and the derivative of the flow (24 equations)."""
    d = carray(user_data, (USER_DATA_SIZE,), dtype=np.float64)
    state = carray(_load_pointer(_load_pointer(y, 0), DATA_OFFSET), (VARIATIONAL_SIZE,), dtype=np.float64)
    out = carray(_load_pointer(_load_pointer(ydot, 0), DATA_OFFSET), (VARIATIONAL_SIZE,), dtype=np.float64)
    variational_derivative(d[0] + tau, state, out, d[COEFFICIENTS:], int(d[1]), int(d[2]), d[3] != 0.0, d[4] != 0.0)
    return 0


@functools.cache
def variational_rhs() -> Any:
    """The compiled callback of the 24 equations, compiled (or loaded) when first asked for: only
    the orbit code needs it, and a plain run's first start does not wait for it."""
    return cfunc(_SIGNATURE, cache=True)(_variational_rhs)


@cfunc(_SIGNATURE, cache=True)
def roots(tau: float, y: Any, gout: Any, user_data: Any) -> int:  # pragma: no cover - compiled
    """``CVRootFn``: the mode's root functions (:mod:`oscillator.model.roots`)."""
    d = carray(user_data, (USER_DATA_SIZE,), dtype=np.float64)
    state = carray(_load_pointer(_load_pointer(y, 0), DATA_OFFSET), (SIZE,), dtype=np.float64)
    g = carray(gout, (NUM_ROOTS,), dtype=np.float64)
    c, t = d[COEFFICIENTS:], d[0] + tau
    x1, v1, x2, v2 = state[0], state[1], state[2], state[3]
    root_values_at(t, x1, v1, x2, v2, c, int(d[1]), int(d[2]), d[3] != 0.0, d[4] != 0.0, d[5], d[6], g, 0)
    return 0
