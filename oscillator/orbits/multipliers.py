"""The Floquet multipliers of a periodic orbit: the eigenvalues of its monodromy matrix ``M``, those
of the masses that move, and the verdict whether no disturbance grows."""

from __future__ import annotations

import numpy as np

__all__ = ["moving_multipliers", "multipliers_of", "verdict_of"]


def multipliers_of(monodromy: np.ndarray) -> np.ndarray:
    """The eigenvalues of the monodromy matrix, largest modulus first."""
    values = np.linalg.eigvals(monodromy)
    return values[np.argsort(-np.abs(values), kind="stable")]


def moving_multipliers(monodromy: np.ndarray, resting: tuple[int, ...]) -> np.ndarray:
    """The multipliers of the coordinates of the masses that move.

    A mass at rest all period contributes the exact multipliers 1 (in ``x_i``, neutral) and 0
    (in ``v_i``): its row ``x_i`` of ``M`` is ``e_(x_i)``, its row and column ``v_i`` are zero, so
    ``M`` is block triangular and its other multipliers are those of the block left.
    """
    free = [k for k in range(4) if (k // 2 + 1) not in resting]
    return np.linalg.eigvals(monodromy[np.ix_(free, free)]) if free else np.empty(0, dtype=complex)


def verdict_of(monodromy: np.ndarray, resting: tuple[int, ...]) -> bool:
    """Whether no disturbance grows: every multiplier of the moving masses inside the unit circle."""
    return bool(np.all(np.abs(moving_multipliers(monodromy, resting)) < 1.0))
