"""The period of a sequence of section points: the smallest ``n`` with which they repeat."""

from __future__ import annotations

import numpy as np

__all__ = ["detect_period"]


def detect_period(points: np.ndarray, tolerance: float, max_period: int) -> int:
    """The smallest ``n <= max_period`` with ``P_(k+n) = P_k`` for every recorded ``k``, else 0.

    ``points`` are the Poincaré points in order, one row each; two points are equal when their
    distance is at most ``tolerance (1 + |P|)``.
    """
    scale = tolerance * (1.0 + np.max(np.abs(points))) if points.size else tolerance
    for n in range(1, min(max_period, len(points) - 1) + 1):
        if np.max(np.linalg.norm(points[n:] - points[:-n], axis=1)) <= scale:
            return n
    return 0
