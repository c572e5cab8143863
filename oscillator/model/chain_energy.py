"""A friction chain's energy audit: the work-energy theorem element by element.

Over a run the kinetic energy changes by the work of every element on the masses,
``T1 - T0 = sum_e W_e`` (the works are integrated with the motion).  An elastic part stores
energy ``V_e`` (a spring ``k u^2/2 + k3 u^4/4``, a closed stop or contact ``K e^2/2`` of its
overlap ``e``, a Jenkins spring ``kt (u - z)^2/2``); the rest of an element's work is what it
dissipated (``-(W_e + dV_e)``: dampers, friction, a slipping slider, a stop's damper) or put in
(a force, a belt).  ``residual = T1 - T0 - sum W`` is zero up to the solver's tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from oscillator.model.chain_fields import CONTACT, JENKINS, SPRING, STOP, ChainArrays, arrays_of
from oscillator.model.chains import FrictionChain

__all__ = ["ChainEnergy", "audit", "stored_energy"]


@dataclass(frozen=True)
class ChainEnergy:
    """The audit: per element (``element``, ``type``, ``work`` on the masses, ``stored``: its
    elastic energy's change, ``dissipated``), the kinetic energy's change and the residual (J)."""

    table: pd.DataFrame
    kinetic_change: float
    residual: float

    @property
    def scale(self) -> float:
        """The energy the audit is measured against: the largest term."""
        terms = np.abs(self.table[["work", "stored"]].to_numpy()).max(initial=0.0)
        return float(max(terms, abs(self.kinetic_change), 1e-300))


def _overlap(arrays: ChainArrays, row: int, y: np.ndarray) -> float:
    """How far a stop or contact is pressed in (0 when open)."""
    side, at = arrays.value[row, :2]
    on, other = arrays.on[row], arrays.other[row]
    u = y[2 * on] - (y[2 * other] if other >= 0 else 0.0)
    edge = at if arrays.kind[row] == STOP else side * at
    return float(max(0.0, side * (u - edge)))


def stored_energy(arrays: ChainArrays, row: int, y: np.ndarray) -> float:
    """Element ``row``'s elastic energy in state ``y`` (J; 0 for an element that stores none)."""
    code, value = arrays.kind[row], arrays.value[row]
    on, other = arrays.on[row], arrays.other[row]
    u = y[2 * on] - (y[2 * other] if other >= 0 else 0.0)
    if code == SPRING:
        return float(0.5 * value[0] * u * u + 0.25 * value[1] * u**4)
    if code in (STOP, CONTACT):
        return float(0.5 * value[2] * _overlap(arrays, row, y) ** 2)
    if code == JENKINS:
        return float(0.5 * value[0] * (u - y[arrays.slider[row]]) ** 2)
    return 0.0


def audit(chain: FrictionChain, start: np.ndarray, end: np.ndarray, work: dict[str, float]) -> ChainEnergy:
    """The audit between the states ``start`` and ``end`` given each element's ``work`` (J)."""
    arrays = arrays_of(chain)
    rows = []
    for row, element in enumerate(chain.elements):
        stored = stored_energy(arrays, row, end) - stored_energy(arrays, row, start)
        rows.append((element.name, element.type, work[element.name], stored, -(work[element.name] + stored)))
    table = pd.DataFrame(rows, columns=["element", "type", "work", "stored", "dissipated"])

    def kinetic(y: np.ndarray) -> float:
        return float(sum(0.5 * m * y[2 * k + 1] ** 2 for k, m in enumerate(arrays.mass)))

    change = kinetic(end) - kinetic(start)
    return ChainEnergy(table, change, change - float(table["work"].sum()))
