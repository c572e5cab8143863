"""Type aliases for the state and the compiled formulas' vectors."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

__all__ = ["VARIATIONAL", "StateLike", "Vector"]

#: A float64 vector: the parameter vector, the 8-vector of the state and the work quadratures,
#: the root functions' values.
Vector: TypeAlias = npt.NDArray[np.float64]
#: ``(x1, v1, x2, v2)`` (or the 8-vector, whose first four entries are the state).
StateLike: TypeAlias = Sequence[float] | Vector
#: The integrated vector's layout: ``x1, v1, x2, v2``, the four works (:mod:`oscillator.model.energy`),
#: then, when the derivative of the flow is carried, its 16 entries row by row from here.
VARIATIONAL = 8
