"""A friction chain's field in a mode, compiled once for the class (issue 51).

A chain becomes arrays (:func:`arrays_of`): one row per element with its type's code, the masses
it acts on and with (``-1``: the ground) and its values in a fixed layout (:data:`LAYOUT`), so that
one compiled function serves every chain (a new system runs without compiling).

The state is ``(x_1, v_1, ..., x_n, v_n, z_1, ..., z_J)``: each mass's position and velocity, then
each Jenkins slider's position.  The mode is one integer per element: a friction element's slip
sign ``s`` (``0``: stuck to its floor or belt), a stop's or contact's ``1`` when closed, a Jenkins
slider's slip sign (``0``: stuck), ``0`` for the others.  In a mode the field is smooth:

* a mass whose friction sticks moves with its belt: ``x' = w``, ``v' = 0``;
* any other mass: ``x' = v``, ``m v' = F - s (mu_k N + P)``, ``F`` the sum of the forces of its
  springs (``k u + k3 u^3`` of the stretch ``u = x_on - x_with``), dampers (``c u' + c3 u'^3``),
  forcing (``Q sin(Omega t + phi)``), closed stops (``K (x - at) + C v``) and contacts
  (``K (u + gap) + C u'`` on the left side, ``K (u - gap) + C u'`` on the right) and Jenkins
  elements (``kt (u - z)`` stuck, ``s F`` slipping), each acting on ``on`` and, opposite, on ``with``;
* a stuck slider stays: ``z' = 0``; a slipping one follows: ``z' = u'`` (its force stays ``s F``).

The article's system is the chain :func:`~oscillator.model.chains.article_chain` builds; its field
here equals :func:`oscillator.model.kernels.rates`' in every mode (tests/test_chains.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from oscillator.compiled import njit
from oscillator.model.chains import FrictionChain
from oscillator.model.types import Vector

__all__ = ["CODES", "LAYOUT", "ChainArrays", "arrays_of", "chain_derivative", "state_of"]

SPRING, DAMPER, FORCE, FRICTION, STOP, CONTACT, JENKINS = range(7)
#: Each type's code in the arrays.
CODES = {
    "spring": SPRING,
    "damper": DAMPER,
    "force": FORCE,
    "friction": FRICTION,
    "stop": STOP,
    "contact": CONTACT,
    "jenkins": JENKINS,
}
#: Each type's values in the row's columns (``side``: +1 right, -1 left; ``N``: the weight given).
LAYOUT = {
    "spring": ("k", "k3"),
    "damper": ("c", "c3"),
    "force": ("Q", "phi"),
    "friction": ("mu_s", "mu_k", "N", "P", "w"),
    "stop": ("side", "at", "K", "C"),
    "contact": ("side", "gap", "K", "C"),
    "jenkins": ("kt", "F"),
}
WIDTH = 5


@dataclass(frozen=True)
class ChainArrays:
    """A chain as the compiled field reads it: ``mass`` (kg), ``kind``, ``on``, ``other`` (-1 the
    ground), ``value`` (rows of :data:`LAYOUT`), ``slider`` (each element's index in the state, -1
    for none: a Jenkins slider's position), ``friction`` (each mass's friction element, -1 none),
    and ``Omega``."""

    mass: np.ndarray
    kind: np.ndarray
    on: np.ndarray
    other: np.ndarray
    value: np.ndarray
    slider: np.ndarray
    friction: np.ndarray
    Omega: float

    @property
    def size(self) -> int:
        """The state's length: two values a mass, one a slider."""
        return 2 * len(self.mass) + int((self.slider >= 0).sum())


def arrays_of(chain: FrictionChain) -> ChainArrays:
    """The chain's arrays (module docstring)."""
    index = {mass.name: k for k, mass in enumerate(chain.masses)}
    count = len(chain.elements)
    kind, on, other = (np.full(count, -1, dtype=np.int64) for _ in range(3))
    value = np.zeros((count, WIDTH))
    slider = np.full(count, -1, dtype=np.int64)
    friction = np.full(len(chain.masses), -1, dtype=np.int64)
    sliders = 2 * len(chain.masses)
    for row, element in enumerate(chain.elements):
        kind[row], on[row] = CODES[element.type], index[element.on]
        other[row] = -1 if element.with_ is None else index[element.with_]
        for column, name in enumerate(LAYOUT[element.type]):
            if name == "side":
                value[row, column] = 1.0 if element.values["side"] == "right" else -1.0
            elif name == "N":
                value[row, column] = chain.normal_force(element)
            else:
                value[row, column] = float(element.values[name])
        if element.type == "jenkins":
            slider[row], sliders = sliders, sliders + 1
        if element.type == "friction":
            friction[index[element.on]] = row
    masses = np.array([mass.m for mass in chain.masses], dtype=float)
    return ChainArrays(masses, kind, on, other, value, slider, friction, float(chain.Omega))


def state_of(chain: FrictionChain) -> np.ndarray:
    """The chain's initial state: each mass's ``x, v``, each slider at rest where its spring is
    unstretched (``z = x_on - x_with``)."""
    arrays = arrays_of(chain)
    y = np.zeros(arrays.size)
    for k, mass in enumerate(chain.masses):
        y[2 * k], y[2 * k + 1] = mass.x, mass.v
    for row in np.flatnonzero(arrays.slider >= 0):
        far = y[2 * arrays.other[row]] if arrays.other[row] >= 0 else 0.0
        y[arrays.slider[row]] = y[2 * arrays.on[row]] - far
    return y


@njit(cache=True)
def _stretch(y: Vector, on: int, other: int) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(u, u')``: how far ``on`` is from ``other`` (or the ground) and how fast."""
    if other < 0:
        return y[2 * on], y[2 * on + 1]
    return y[2 * on] - y[2 * other], y[2 * on + 1] - y[2 * other + 1]


@njit(cache=True)
def element_force(
    t: float,
    y: Vector,
    mode: np.ndarray,
    row: int,
    kind: np.ndarray,
    on: np.ndarray,
    other: np.ndarray,
    value: np.ndarray,
    slider: np.ndarray,
    omega: float,
) -> float:  # pragma: no cover - compiled
    """The force element ``row`` puts on its ``on`` mass in ``mode`` (N; the ``with`` mass takes
    it with the other sign); friction's is not here (it is the field's)."""
    code, v = kind[row], value[row]
    u, w = _stretch(y, on[row], other[row])
    force: float = 0.0
    if code == SPRING:
        force = -(v[0] * u + v[1] * (u * u * u))
    elif code == DAMPER:
        force = -(v[0] * w + v[1] * (w * w * w))
    elif code == FORCE:
        force = v[0] * math.sin(omega * t + v[1])
    elif code == STOP and mode[row] != 0:
        force = -(v[2] * (y[2 * on[row]] - v[1]) + v[3] * y[2 * on[row] + 1])
    elif code == CONTACT and mode[row] != 0:
        force = -(v[2] * (u + v[1] if v[0] < 0 else u - v[1]) + v[3] * w)
    elif code == JENKINS:
        force = -(v[0] * (u - y[slider[row]])) if mode[row] == 0 else -mode[row] * v[1]
    return force


@njit(cache=True)
def chain_derivative(
    t: float,
    y: Vector,
    yp: Vector,
    mode: np.ndarray,
    mass: Vector,
    kind: np.ndarray,
    on: np.ndarray,
    other: np.ndarray,
    value: np.ndarray,
    slider: np.ndarray,
    friction: np.ndarray,
    omega: float,
) -> None:  # pragma: no cover - compiled
    """Fill ``yp`` with the chain's field in ``mode`` (module docstring)."""
    n = mass.shape[0]
    forces = np.zeros(n)
    for row in range(kind.shape[0]):
        f = element_force(t, y, mode, row, kind, on, other, value, slider, omega)
        forces[on[row]] += f
        if other[row] >= 0:
            forces[other[row]] -= f
    for i in range(n):
        row = friction[i]
        if row >= 0 and mode[row] == 0:  # stuck to its floor or belt
            yp[2 * i], yp[2 * i + 1] = value[row, 4], 0.0
            continue
        yp[2 * i] = y[2 * i + 1]
        kinetic = 0.0 if row < 0 else mode[row] * (value[row, 1] * value[row, 2] + value[row, 3])
        yp[2 * i + 1] = (forces[i] - kinetic) / mass[i]
    for row in range(kind.shape[0]):
        if slider[row] >= 0:
            _, rate = _stretch(y, on[row], other[row])
            yp[slider[row]] = 0.0 if mode[row] == 0 else rate
