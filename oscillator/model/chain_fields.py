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

import functools
import math
from dataclasses import dataclass

import numpy as np

from oscillator.compiled import njit
from oscillator.model.chains import FrictionChain
from oscillator.model.types import Vector

__all__ = [
    "CODES",
    "HEADER",
    "LAYOUT",
    "ChainArrays",
    "arrays_of",
    "chain_derivative",
    "chain_jacobian",
    "element_force",
    "element_gradient",
    "element_rate",
    "forces_on",
    "pack",
    "root_gradient",
    "root_values",
    "state_of",
]

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

    @functools.cached_property
    def size(self) -> int:
        """The state's length: two values a mass, one a slider."""
        return 2 * len(self.mass) + int((self.slider >= 0).sum())

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """:func:`pack`'s vector with every element's mode 0 (read only: :func:`pack` copies it)."""
        n, e = len(self.mass), len(self.kind)
        head = [0.0, float(n), float(e), float(self.size), self.Omega]
        parts = [head, np.zeros(e), self.mass, self.friction, self.kind, self.on, self.other, self.slider]
        scratch = np.zeros(n)
        vector = np.concatenate([np.asarray(part, dtype=float).ravel() for part in (*parts, self.value, scratch)])
        vector.flags.writeable = False
        return vector


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


#: The data vector's head (:func:`pack`): CVODE's time origin, the counts, the state's length
#: (masses and sliders: the works of the elements follow it), ``Omega``.
HEADER = ("t_ref", "masses", "elements", "size", "Omega")


def pack(arrays: ChainArrays, mode: np.ndarray | list[int]) -> np.ndarray:
    """The chain in ``mode`` as one vector of floats, what the compiled field reads (and CVODE's
    user data): :data:`HEADER`, then the mode, the masses, each mass's friction element, each
    element's code, ends, slider and values, and room for the forces on the masses (the compiled
    functions' scratch: they allocate nothing).  Its length is :func:`data_length`; a new vector
    each call, from the one :attr:`ChainArrays.packed` holds."""
    vector = arrays.packed.copy()
    vector[len(HEADER) : len(HEADER) + len(arrays.kind)] = mode
    return vector


#: Where each part of the data vector starts (:func:`_offsets`).
Offsets = tuple[int, int, int, int, int, int, int, int, int, int]


@njit(cache=True)
def data_length(masses: int, elements: int) -> int:  # pragma: no cover - compiled
    """The length of :func:`pack`'s vector."""
    return len(HEADER) + 3 * masses + 10 * elements


@njit(cache=True)
def _offsets(d: Vector) -> Offsets:  # pragma: no cover - compiled
    """``(n, e, mode, mass, friction, kind, on, other, slider, value)``: the counts and where each
    part of the data vector starts (computed once a call: the element loops take them)."""
    n, e = int(d[1]), int(d[2])
    mode = len(HEADER)
    mass = mode + e
    friction = mass + n
    kind = friction + n
    return n, e, mode, mass, friction, kind, kind + e, kind + 2 * e, kind + 3 * e, kind + 4 * e


@njit(cache=True)
def _stretch(y: Vector, on: int, other: int) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(u, u')``: how far ``on`` is from ``other`` (or the ground) and how fast."""
    if other < 0:
        return y[2 * on], y[2 * on + 1]
    return y[2 * on] - y[2 * other], y[2 * on + 1] - y[2 * other + 1]


@njit(cache=True)
def _force(t: float, y: Vector, d: Vector, row: int, at: Offsets) -> float:  # pragma: no cover - compiled
    """:func:`element_force` with the data's offsets ``at`` (:func:`_offsets`) given; the values
    read in place."""
    _, _, mode, _, _, kind, on_at, other_at, slider_at, value_at = at
    code, on, s = int(d[kind + row]), int(d[on_at + row]), d[mode + row]
    v = value_at + WIDTH * row
    u, w = _stretch(y, on, int(d[other_at + row]))
    force: float = 0.0
    if code == SPRING:
        force = -(d[v] * u + d[v + 1] * (u * u * u))
    elif code == DAMPER:
        force = -(d[v] * w + d[v + 1] * (w * w * w))
    elif code == FORCE:
        force = d[v] * math.sin(d[4] * t + d[v + 1])
    elif code == STOP and s != 0.0:
        force = -(d[v + 2] * (y[2 * on] - d[v + 1]) + d[v + 3] * y[2 * on + 1])
    elif code == CONTACT and s != 0.0:
        force = -(d[v + 2] * (u + d[v + 1] if d[v] < 0 else u - d[v + 1]) + d[v + 3] * w)
    elif code == JENKINS:
        force = -(d[v] * (u - y[int(d[slider_at + row])])) if s == 0.0 else -s * d[v + 1]
    return force


@njit(cache=True)
def element_force(t: float, y: Vector, d: Vector, row: int) -> float:  # pragma: no cover - compiled
    """The force element ``row`` puts on its ``on`` mass in the data's mode (N; the ``with`` mass
    takes it with the other sign); friction's is not here (it is the field's)."""
    return _force(t, y, d, row, _offsets(d))


@njit(cache=True)
def _forces(t: float, y: Vector, d: Vector, out: Vector, at: Offsets) -> None:  # pragma: no cover - compiled
    n, e, _, _, _, _, on_at, other_at, _, _ = at
    for i in range(n):
        out[i] = 0.0
    for row in range(e):
        f = _force(t, y, d, row, at)
        out[int(d[on_at + row])] += f
        other = int(d[other_at + row])
        if other >= 0:
            out[other] -= f


@njit(cache=True)
def forces_on(t: float, y: Vector, d: Vector, out: Vector) -> None:  # pragma: no cover - compiled
    """``out[i]``: the force every element but friction puts on mass ``i`` (N)."""
    _forces(t, y, d, out, _offsets(d))


@njit(cache=True)
def _friction_force(d: Vector, i: int, force: float, at: Offsets) -> float:  # pragma: no cover - compiled
    """The friction force on mass ``i`` (N) under the other forces' sum ``force``: kinetic
    ``-s (mu_k N + P)`` slipping, ``-force`` (what holds it to its floor or belt) stuck."""
    _, _, mode, _, friction, _, _, _, _, value_at = at
    row = int(d[friction + i])
    if row < 0:
        return 0.0
    s = d[mode + row]
    v = value_at + WIDTH * row
    return -force if s == 0.0 else -s * (d[v + 1] * d[v + 2] + d[v + 3])


@njit(cache=True)
def chain_derivative(t: float, y: Vector, yp: Vector, d: Vector) -> None:  # pragma: no cover - compiled
    """Fill ``yp`` with the chain's field in the data's mode (module docstring), and, when ``y``
    is longer than the state (``d[3]``), the power of each element on the masses (W): the rates
    of the elements' works."""
    at = _offsets(d)
    n, e, mode, mass, friction, _, on_at, other_at, slider_at, value_at = at
    size, scratch = int(d[3]), value_at + WIDTH * e
    for i in range(n):
        d[scratch + i] = 0.0
    for row in range(e):  # the forces on the masses, in the data's scratch (no allocation)
        f = _force(t, y, d, row, at)
        d[scratch + int(d[on_at + row])] += f
        if d[other_at + row] >= 0:
            d[scratch + int(d[other_at + row])] -= f
    for i in range(n):
        row, force = int(d[friction + i]), d[scratch + i]
        if row >= 0 and d[mode + row] == 0.0:  # stuck to its floor or belt
            yp[2 * i], yp[2 * i + 1] = d[value_at + WIDTH * row + 4], 0.0
        else:
            yp[2 * i] = y[2 * i + 1]
            yp[2 * i + 1] = (force + _friction_force(d, i, force, at)) / d[mass + i]
    for row in range(e):
        if d[slider_at + row] >= 0:
            _, rate = _stretch(y, int(d[on_at + row]), int(d[other_at + row]))
            yp[int(d[slider_at + row])] = 0.0 if d[mode + row] == 0.0 else rate
    if y.shape[0] > size:
        for row in range(e):
            on = int(d[on_at + row])
            if row == int(d[friction + on]):
                yp[size + row] = _friction_force(d, on, d[scratch + on], at) * y[2 * on + 1]
            else:
                _, rate = _stretch(y, on, int(d[other_at + row]))
                yp[size + row] = _force(t, y, d, row, at) * rate


@njit(cache=True)
def root_values(t: float, y: Vector, d: Vector, g: Vector) -> None:  # pragma: no cover - compiled
    """Two root functions per element in the data's mode (docs/systems.md, "Events"), ``1``
    where an element has none:

    * friction slipping: the velocity against the floor or belt ``v - w`` and the acceleration
      (a velocity extremum: grazing, Thm 5.5); stuck: the flow barrier ``F -+ (mu_s N + P)``
      (Thm 5.4), ``F`` the other forces' sum;
    * stop: ``x - at``; contact: ``u + gap`` (left) or ``u - gap`` (right); while open, also the
      gap's rate ``x'`` (``u'``): at its turn toward the stop CVODE looks inside the step, so that a
      shallow contact that opens again within one step is not missed (a grazing contact);
    * Jenkins slider stuck: ``kt (u - z) -+ F``; slipping: the stretch's rate ``u'`` (it sticks
      where the motion turns); with ``F = 0`` none (it never holds).
    """
    at = _offsets(d)
    n, e, mode, mass, _, kind, on_at, other_at, slider_at, value_at = at
    scratch = value_at + WIDTH * e
    _forces(t, y, d, d[scratch : scratch + n], at)
    for row in range(e):
        g[2 * row], g[2 * row + 1] = 1.0, 1.0
        code, on, s = int(d[kind + row]), int(d[on_at + row]), d[mode + row]
        v = value_at + WIDTH * row
        if code == FRICTION and s != 0.0:
            g[2 * row] = y[2 * on + 1] - d[v + 4]
            g[2 * row + 1] = (d[scratch + on] - s * (d[v + 1] * d[v + 2] + d[v + 3])) / d[mass + on]
        elif code == FRICTION:
            static = d[v] * d[v + 2] + d[v + 3]
            g[2 * row], g[2 * row + 1] = d[scratch + on] - static, d[scratch + on] + static
        elif code == STOP:
            g[2 * row] = y[2 * on] - d[v + 1]
            if s == 0.0:
                g[2 * row + 1] = y[2 * on + 1]
        elif code == CONTACT:
            u, w = _stretch(y, on, int(d[other_at + row]))
            g[2 * row] = u + d[v + 1] if d[v] < 0 else u - d[v + 1]
            if s == 0.0:
                g[2 * row + 1] = w
        elif code == JENKINS and d[v + 1] > 0.0:
            u, w = _stretch(y, on, int(d[other_at + row]))
            if s == 0.0:
                f = d[v] * (u - y[int(d[slider_at + row])])
                g[2 * row], g[2 * row + 1] = f - d[v + 1], f + d[v + 1]
            else:
                g[2 * row] = w


# -- the field's derivatives: the tangent equations and the saltation matrices (issue 52) -----------


@njit(cache=True)
def _gradient(
    t: float, y: Vector, d: Vector, row: int, at: Offsets, sign: float, grad: Vector
) -> float:  # pragma: no cover - compiled
    """Add ``sign`` times the gradient in ``y`` of :func:`_force` of element ``row`` to ``grad``;
    return ``sign`` times its derivative in ``t``."""
    _, _, mode, _, _, kind, on_at, other_at, slider_at, value_at = at
    code, on, other, s = int(d[kind + row]), int(d[on_at + row]), int(d[other_at + row]), d[mode + row]
    v = value_at + WIDTH * row
    u, w = _stretch(y, on, other)
    along, rate = 0.0, 0.0  # the force's derivatives in the stretch u and its rate u'
    if code == SPRING:
        along = -(d[v] + 3.0 * d[v + 1] * u * u)
    elif code == DAMPER:
        rate = -(d[v] + 3.0 * d[v + 1] * w * w)
    elif code == FORCE:
        return float(sign * d[v] * d[4] * math.cos(d[4] * t + d[v + 1]))
    elif code == STOP and s != 0.0:
        grad[2 * on] -= sign * d[v + 2]
        grad[2 * on + 1] -= sign * d[v + 3]
        return 0.0
    elif code == CONTACT and s != 0.0:
        along, rate = -d[v + 2], -d[v + 3]
    elif code == JENKINS and s == 0.0:
        along = -d[v]
        grad[int(d[slider_at + row])] += sign * d[v]
    grad[2 * on] += sign * along
    grad[2 * on + 1] += sign * rate
    if other >= 0:
        grad[2 * other] -= sign * along
        grad[2 * other + 1] -= sign * rate
    return 0.0


@njit(cache=True)
def element_gradient(t: float, y: Vector, d: Vector, row: int, grad: Vector) -> float:  # pragma: no cover
    """Fill ``grad`` with the gradient in the state of :func:`element_force` of element ``row``
    in the data's mode; return its derivative in ``t``."""
    for k in range(grad.shape[0]):
        grad[k] = 0.0
    return _gradient(t, y, d, row, _offsets(d), 1.0, grad)


@njit(cache=True)
def element_rate(t: float, y: Vector, yp: Vector, d: Vector, row: int) -> float:  # pragma: no cover - compiled
    """The rate of :func:`element_force` of element ``row`` (N/s) along the motion ``y' = yp``, in
    the data's mode: its gradient in the state times ``yp``, and its derivative in ``t``."""
    grad = np.zeros(y.shape[0])
    rate = element_gradient(t, y, d, row, grad)
    for k in range(y.shape[0]):
        rate += grad[k] * yp[k]
    return rate


@njit(cache=True)
def _force_gradient(t: float, y: Vector, d: Vector, i: int, at: Offsets, grad: Vector) -> float:  # pragma: no cover
    """Fill ``grad`` with the gradient in ``y`` of :func:`forces_on`'s ``i``-th force; return its
    derivative in ``t``."""
    _, e, _, _, _, _, on_at, other_at, _, _ = at
    for k in range(grad.shape[0]):
        grad[k] = 0.0
    rate = 0.0
    for row in range(e):
        if int(d[on_at + row]) == i:
            rate += _gradient(t, y, d, row, at, 1.0, grad)
        elif int(d[other_at + row]) == i:
            rate += _gradient(t, y, d, row, at, -1.0, grad)
    return rate


@njit(cache=True)
def chain_jacobian(t: float, y: Vector, d: Vector, jacobian: np.ndarray, rate: Vector) -> None:  # pragma: no cover
    """Fill ``jacobian`` with the derivative of :func:`chain_derivative`'s field in the state
    (square, the state's size) and ``rate`` with its derivative in ``t``, in the data's mode:
    a stuck mass's rows are zero (``x' = w``, ``v' = 0``), a moving mass's ``x`` row is ``e_v``
    and its ``v`` row the gradient of the forces on it over its mass (kinetic friction is
    constant in a mode), a stuck slider's row zero and a slipping one's the stretch's rate's."""
    at = _offsets(d)
    n, e, mode, mass, friction, _, on_at, other_at, slider_at, _ = at
    size = jacobian.shape[0]
    grad = np.zeros(size)
    jacobian[:, :] = 0.0
    rate[:] = 0.0
    for i in range(n):
        row = int(d[friction + i])
        if row >= 0 and d[mode + row] == 0.0:
            continue
        jacobian[2 * i, 2 * i + 1] = 1.0
        rate[2 * i + 1] = _force_gradient(t, y, d, i, at, grad) / d[mass + i]
        jacobian[2 * i + 1, :] = grad / d[mass + i]
    for row in range(e):
        z = int(d[slider_at + row])
        if z >= 0 and d[mode + row] != 0.0:
            jacobian[z, 2 * int(d[on_at + row]) + 1] = 1.0
            if d[other_at + row] >= 0:
                jacobian[z, 2 * int(d[other_at + row]) + 1] = -1.0


@njit(cache=True)
def root_gradient(t: float, y: Vector, d: Vector, index: int, grad: Vector) -> float:  # pragma: no cover
    """Fill ``grad`` with the gradient in ``y`` of :func:`root_values`' function ``index`` in the
    data's mode; return its derivative in ``t``."""
    at = _offsets(d)
    _, _, mode, mass, _, kind, on_at, other_at, slider_at, value_at = at
    row, slot = index // 2, index % 2
    code, on, other, s = int(d[kind + row]), int(d[on_at + row]), int(d[other_at + row]), d[mode + row]
    v = value_at + WIDTH * row
    for k in range(grad.shape[0]):
        grad[k] = 0.0
    if code == FRICTION and s != 0.0 and slot == 0:
        grad[2 * on + 1] = 1.0
        return 0.0
    if code == FRICTION:  # the forces on the mass, or over its mass (its acceleration)
        scale = 1.0 if s == 0.0 else 1.0 / d[mass + on]
        rate = _force_gradient(t, y, d, on, at, grad)
        for k in range(grad.shape[0]):
            grad[k] *= scale
        return rate * scale
    if code < STOP or (code != JENKINS and slot == 1) or (code == JENKINS and (d[v + 1] <= 0.0 or (s != 0.0 and slot))):
        return 0.0  # a constant: no root function here
    position = 0 if code != JENKINS or s == 0.0 else 1
    grad[2 * on + position] = 1.0
    if other >= 0 and code != STOP:
        grad[2 * other + position] = -1.0
    if code == JENKINS and s == 0.0:
        grad[int(d[slider_at + row])] = -1.0
        for k in range(grad.shape[0]):
            grad[k] *= d[v]
    return 0.0
