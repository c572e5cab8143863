"""The corrector of pseudo-arclength continuation: a branch's state as it is traced
(:class:`Continuer`: the case, the scaling, the tangent predictor's Newton corrector), each
corrected point with its multipliers and cycle of switches (:class:`OrbitPoint`), and the natural
continuation that the bisections use (:func:`natural`)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from oscillator.errors import OscillatorError, Reason
from oscillator.io.cases import Case, resolve_case
from oscillator.orbits.branch import Bifurcation, Skipped, skipped
from oscillator.orbits.multipliers import moving_multipliers, multipliers_of, verdict_of
from oscillator.orbits.sensitivity import map_gradient
from oscillator.orbits.shooting import newton
from oscillator.orbits.signature import Signature, cyclic_signature
from oscillator.orbits.stroboscopic import ORBIT_ENGINE, PeriodMap, fixed_point_system, period_map, pinned_rows

__all__ = ["Continuer", "Located", "OrbitPoint", "critical_multiplier", "kind_of_change", "natural", "slope"]


@dataclass(frozen=True)
class OrbitPoint:
    """One corrected point of the branch (its multipliers and signature computed once: the
    bisections ask for them again and again)."""

    y: np.ndarray
    lam: float
    image: PeriodMap
    tangent: np.ndarray  # in (y, lam / sigma)
    iterations: int
    #: ``sigma dP/dlam`` here, where it was computed (the corrector's next steps reuse it).
    column: np.ndarray | None = None

    @cached_property
    def multipliers(self) -> np.ndarray:
        assert self.image.monodromy is not None
        return multipliers_of(self.image.monodromy)

    @cached_property
    def signature(self) -> Signature:
        return cyclic_signature(self.image)

    @cached_property
    def rest_positions(self) -> tuple[tuple[int, float], ...]:
        """``(mass, x_i)`` of each mass at rest all period: where it stuck."""
        return tuple((mass, float(self.y[2 * mass - 2])) for mass in self.image.resting)

    def same_kind(self, other: OrbitPoint) -> bool:
        """The same cycle of switches, and every mass at rest all period resting at the same place
        (a family of such orbits is followed at that place; where static friction cannot hold
        the mass there any more, the orbit ends even if the signature does not change)."""
        if self.signature != other.signature or self.image.resting != other.image.resting:
            return False
        return all(
            abs(x - y) <= 1e-9 * max(1.0, abs(x))
            for (_, x), (_, y) in zip(self.rest_positions, other.rest_positions, strict=True)
        )

    @cached_property
    def unstable(self) -> int:
        """Multipliers outside the unit circle (a mass at rest all period adds none: its 1 is neutral)."""
        assert self.image.monodromy is not None
        return int(np.sum(np.abs(moving_multipliers(self.image.monodromy, self.image.resting)) > 1.0))

    @cached_property
    def stable(self) -> bool:
        assert self.image.monodromy is not None
        return verdict_of(self.image.monodromy, self.image.resting)


@dataclass(frozen=True)
class Located:
    """A located bifurcation: its row, and the orbits on either side (None across a gap)."""

    row: dict[str, Any]
    left: OrbitPoint | None
    right: OrbitPoint | None


class Continuer:
    """The branch's state as it is traced: the case, the scaling and the corrector."""

    def __init__(
        self, case: Case, param: str, t0: float, period: int, sigma: float, tol: float, engine: str = ORBIT_ENGINE
    ) -> None:
        self.case, self.param, self.t0, self.period = case, param, t0, period
        self.sigma, self.tol = sigma, tol
        #: The period maps' engine (:data:`~oscillator.orbits.stroboscopic.ORBIT_ENGINES`).
        self.engine = engine
        self.scale = max(1.0, abs(case.parameters.d), abs(case.parameters.d1))

    def at(self, lam: float) -> Case:
        return resolve_case(self.case, **{self.param: lam})

    def first(self, guess: np.ndarray, lam: float, direction: float) -> OrbitPoint:
        """The orbit at ``lam`` from ``guess``, with its tangent pointing ``direction`` in ``lam``."""
        y, image, _ = newton(
            self.at(lam), self.t0, guess, self.period, tol=self.tol, max_iterations=20, engine=self.engine
        )
        jacobian = self.jacobian(y, lam, image)
        return OrbitPoint(y, lam, image, self.tangent(jacobian, None, direction), 0, jacobian[:, 4])

    def residual(self, y: np.ndarray, lam: float) -> tuple[np.ndarray, PeriodMap]:
        """``P(y) - y`` (zero in the displacement of a mass at rest all period) and the map."""
        image = period_map(self.at(lam), self.t0, y, self.period, engine=self.engine)
        return fixed_point_system(image)[1], image

    def jacobian(self, y: np.ndarray, lam: float, image: PeriodMap, column: np.ndarray | None = None) -> np.ndarray:
        """``[M - I, sigma dP/dlam]`` (4 x 5); a mass at rest all period keeps its displacement:
        its row is ``[e_(x_i), 0]`` (:func:`~oscillator.orbits.shooting.fixed_point_system`).

        ``dP/dlam`` is exact, carried through every switch along the map's own pieces
        (:func:`~oscillator.orbits.sensitivity.map_gradient`: a difference quotient would straddle
        a switch's change as soon as the branch comes within its step of one), unless ``column``
        is given (the corrector's steps between two points reuse the last point's: a chord
        method in ``lam``, exact in ``y``)."""
        if column is None:
            p = image.result.case.parameters
            dt_end = np.array([-(image.t1 - image.t0) / p.Omega if self.param == "Omega" else 0.0])
            gradient = map_gradient(image.segments, p, (self.param,), image.t1, dt_end)
            column = self.sigma * gradient[:, 0]
        column = column.copy()
        column[pinned_rows(image.settled)] = 0.0
        return np.column_stack([fixed_point_system(image)[0], column])

    def tangent(self, jacobian: np.ndarray, previous: np.ndarray | None, direction: float) -> np.ndarray:
        """The unit null vector of ``jacobian``, oriented along ``previous`` (or ``direction`` in lam)."""
        t: np.ndarray = np.linalg.svd(jacobian)[2][-1]
        reference = previous @ t if previous is not None else direction * t[4]
        return -t if reference < 0 else t

    def correct(
        self,
        guess: np.ndarray,
        tangent: np.ndarray,
        anchor: np.ndarray,
        max_iterations: int = 8,
        column: np.ndarray | None = None,
    ) -> OrbitPoint | Skipped:
        """Newton on ``F = 0`` and ``tangent . (u - anchor) = 0`` from ``guess``; why not, if it fails.

        Each step takes ``M`` where it stands (the run that gives ``F`` carries it) and
        ``dP/dlam`` from ``column`` when given (the last point's); the point found gets its own,
        computed there, and its tangent from it."""
        u = guess.copy()
        for iteration in range(max_iterations + 1):
            y, lam = u[:4], u[4] * self.sigma
            try:
                residual, image = self.residual(y, lam)
                converged = np.max(np.abs(residual)) <= self.tol * self.scale
                constraint = float(tangent @ (u - anchor))
                jacobian = self.jacobian(y, lam, image, None if converged else column)
            except OscillatorError as error:
                return skipped(lam, error)
            if converged and abs(constraint) <= 1e-9:
                return OrbitPoint(y.copy(), lam, image, self.tangent(jacobian, tangent, 1.0), iteration, jacobian[:, 4])
            if iteration == max_iterations:
                break
            try:
                step = np.linalg.solve(np.vstack([jacobian, tangent]), -np.append(residual, constraint))
            except np.linalg.LinAlgError:
                return Skipped(lam, Reason.SINGULAR, "the corrector's system is singular")
            u = u + step
            if not np.isfinite(u).all():
                return Skipped(lam, Reason.SINGULAR, "the corrector's step is not finite")
        return Skipped(
            float(u[4] * self.sigma), Reason.NO_CONVERGENCE, f"the corrector did not converge in {max_iterations} steps"
        )

    def along(self, a: OrbitPoint, s: float) -> OrbitPoint | Skipped:
        """The point at arclength ``s`` from ``a`` along its tangent (corrected)."""
        u_a = np.append(a.y, a.lam / self.sigma)
        anchor = u_a + s * a.tangent
        return self.correct(anchor, a.tangent, anchor, column=a.column)


def kind_of_change(before: Signature, after: Signature, increasing: bool) -> Bifurcation:
    """The kind of a change of the orbit's cycle of switches, named as the parameter increases;
    with the cycle unchanged, a mass at rest all period could no longer be held where it stuck."""
    if before == after:
        return Bifurcation.of_rests(appears=not increasing)
    if before.rests == after.rests:
        return Bifurcation.GRAZING
    return Bifurcation.of_rests(appears=(after.rests > before.rests) == increasing)


def critical_multiplier(point: OrbitPoint) -> complex:
    values = point.multipliers
    return complex(values[np.argmin(np.abs(np.abs(values) - 1.0))])


def natural(cont: Continuer, lam: float, guess: np.ndarray) -> OrbitPoint | Skipped:
    """The orbit at ``lam`` by Newton from ``guess`` (no arclength condition); why not, if it fails."""
    try:
        y, image, _ = newton(
            cont.at(lam), cont.t0, guess, cont.period, tol=cont.tol, max_iterations=8, engine=cont.engine
        )
    except OscillatorError as error:
        return skipped(lam, error)
    return OrbitPoint(y, lam, image, np.zeros(5), 0)


def slope(p: OrbitPoint, sigma: float) -> np.ndarray:
    """``dy/dlam`` along the branch at ``p`` (zero where unknown or at a fold)."""
    return p.tangent[:4] / (p.tangent[4] * sigma) if p.tangent[4] != 0 else np.zeros(4)
