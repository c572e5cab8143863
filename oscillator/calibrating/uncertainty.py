"""The uncertainty of a least-squares estimate, from the Jacobian at the optimum.

With the residuals ``r_i = (model_i - value_i) / sigma_i`` and their Jacobian ``J`` in the
parameters, the estimate's covariance is ``s^2 (J^T J)^-1`` (the Gauss-Newton approximation of
the inverse Hessian): ``s = 1`` where the measurements' standard deviations were given
(``sigma``), else the residuals' own scale ``s^2 = sum r_i^2 / (n - p)``, as SciPy's
``curve_fit`` does.  The intervals are ``estimate +- q stderr`` with ``q`` the normal quantile
(known sigma) or Student's t with ``n - p`` degrees of freedom (estimated).

``J^T J`` is inverted through the singular values of ``J`` with each column scaled by its
parameter's value (relative sensitivities, so that a stiffness in the thousands and a
coefficient of 0.1 compare).  A direction whose singular value is below :data:`IDENTIFIABLE`
times the largest moves no fitted value: the data cannot tell those parameters apart (two that
enter the model only as their product, or one the measured responses do not depend on).  Their
standard errors are infinite and the combination is named; pairs correlated beyond
:data:`CORRELATED` are named too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

__all__ = ["CORRELATED", "IDENTIFIABLE", "Uncertainty", "uncertainty"]

#: A direction of the (relative) parameters is unidentifiable where its singular value is below
#: this share of the largest: the exact derivatives are good to about 1e-9.
IDENTIFIABLE = 1e-7
#: Pairs of parameters correlated beyond this are named.
CORRELATED = 0.99
#: A parameter takes part in an unidentifiable direction where its weight there exceeds this.
_PART = 1e-3


@dataclass(frozen=True)
class Uncertainty:
    """Module docstring: ``covariance`` and ``correlation`` (DataFrames over the parameters),
    ``stderr`` (Series), ``intervals`` (``low``, ``high`` at ``level``), ``warnings`` (the
    combinations the data cannot separate, and strong correlations), ``scale`` (``s``), ``dof``
    (``n - p``)."""

    covariance: pd.DataFrame
    correlation: pd.DataFrame
    stderr: pd.Series
    intervals: pd.DataFrame
    warnings: tuple[str, ...]
    scale: float
    dof: int
    level: float


def _quantile(level: float, dof: int, known_sigma: bool) -> float:
    from scipy import stats

    if known_sigma:
        return float(stats.norm.ppf(0.5 + level / 2))
    return float(stats.t.ppf(0.5 + level / 2, dof))


def _combination(direction: np.ndarray, names: list[str]) -> str:
    """``+1 % of mu_k and -1 % of g``: a direction of the relative parameters, in words."""
    weights = direction / np.abs(direction).max()
    if weights[np.flatnonzero(np.abs(weights) >= 0.01)[0]] < 0:  # the first parameter named moves up
        weights = -weights
    parts = [f"{w:+.3g} % of {name}" for w, name in zip(weights, names, strict=True) if abs(w) >= 0.01]
    return " and ".join(parts)


def _unidentifiable(null: np.ndarray, names: list[str]) -> list[str]:
    said = []
    for direction in null:
        involved = [name for w, name in zip(direction, names, strict=True) if abs(w) > _PART]
        if len(involved) == 1:
            said.append(
                f"{involved[0]} is not identifiable from these data: no fitted value depends on it; fix it, or "
                "measure a response it changes"
            )
        else:
            said.append(
                f"{', '.join(involved[:-1])} and {involved[-1]} are not identifiable from these data, only a "
                f"combination of them: moving them together by {_combination(direction, names)} changes no fitted "
                "value; fix all but one, or measure a response that separates them"
            )
    return said


def uncertainty(
    jacobian: np.ndarray, residuals: np.ndarray, estimate: pd.Series, *, known_sigma: bool, level: float
) -> Uncertainty:
    """The uncertainty of ``estimate`` (module docstring) from the weighted residuals and their
    Jacobian (rows: measurements, columns: the parameters in ``estimate``'s order)."""
    names = [str(n) for n in estimate.index]
    n, p = jacobian.shape
    dof = n - p
    scale = 1.0 if known_sigma else float(np.sqrt(residuals @ residuals / dof)) if dof > 0 else float("nan")
    values = estimate.to_numpy(dtype=float)
    columns = np.where(values != 0, np.abs(values), 1.0)
    _, singular, vt = np.linalg.svd(jacobian * columns, full_matrices=True)
    singular = np.concatenate([singular, np.zeros(p - len(singular))])  # fewer rows than parameters
    largest = singular[0] if p and singular[0] > 0 else 0.0
    kept = singular > IDENTIFIABLE * largest if largest > 0 else np.zeros(p, bool)
    null = vt[~kept]
    relative = vt[kept].T @ np.diag(1 / singular[kept] ** 2) @ vt[kept] if kept.any() else np.zeros((p, p))
    covariance = relative * np.outer(columns, columns) * scale**2
    lost = (np.abs(null) > _PART).any(axis=0) if len(null) else np.zeros(p, bool)
    covariance[lost, :] = np.nan
    covariance[:, lost] = np.nan
    covariance[lost, lost] = np.inf
    stderr = np.sqrt(np.diag(covariance))
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = covariance / np.outer(stderr, stderr)
    q = _quantile(level, dof, known_sigma)
    warnings = _unidentifiable(null, names)
    for i in range(p):
        for j in range(i + 1, p):
            if not (lost[i] or lost[j]) and abs(correlation[i, j]) > CORRELATED:
                warnings.append(
                    f"{names[i]} and {names[j]} are correlated at {correlation[i, j]:.4f}: the data fix a combination "
                    "of them better than each"
                )
    frame = pd.DataFrame
    return Uncertainty(
        covariance=frame(covariance, index=names, columns=names),
        correlation=frame(correlation, index=names, columns=names),
        stderr=pd.Series(stderr, index=names, name="stderr"),
        intervals=frame({"low": values - q * stderr, "high": values + q * stderr}, index=names),
        warnings=tuple(warnings),
        scale=scale,
        dof=dof,
        level=level,
    )
