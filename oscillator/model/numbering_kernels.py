"""The phase space's numbering (:mod:`oscillator.model.numbering`) compiled for the switching
rules and the theorems: the same functions, one compiled version each."""

from __future__ import annotations

from numba import types

from oscillator.compiled import njit
from oscillator.model import numbering

__all__ = [
    "displacement_boundary_code",
    "domain_code",
    "state_code",
    "velocity_boundary_code",
    "velocity_sign_code",
]

_i = types.int64

domain_code = njit(_i(_i, _i, _i, _i), cache=True)(numbering.domain_code)
velocity_sign_code = njit(_i(_i, _i), cache=True)(numbering.velocity_sign_code)
velocity_boundary_code = njit(_i(_i, _i, _i), cache=True)(numbering.velocity_boundary_code)
displacement_boundary_code = njit(_i(_i, _i, _i), cache=True)(numbering.displacement_boundary_code)
state_code = njit(_i(_i, _i, _i, _i), cache=True)(numbering.state_code)
