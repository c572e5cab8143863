"""A continued branch of periodic orbits and its vocabulary: the kinds of bifurcation
(:class:`Bifurcation`), a point the corrector skipped (:class:`Skipped`) and the
:class:`Branch` that :func:`~oscillator.orbits.continuation.continue_orbit` returns."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.io.cases import Case
from oscillator.io.files import as_folder
from oscillator.model.system import ARTICLE
from oscillator.orbits.shooting import STATE
from oscillator.presenting import presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = [
    "BIFURCATION_KINDS",
    "MULTIPLIERS",
    "Bifurcation",
    "Branch",
    "Skipped",
    "check_coordinate",
    "point_columns",
    "points_from_disk",
    "points_on_disk",
    "skipped",
]


class Bifurcation(enum.StrEnum):
    """The kinds of bifurcation a branch locates, named as the parameter increases (the values
    are the ``kind`` column's text)."""

    SLIDING_ONSET = "sliding_onset"
    """A rest interval appears (a mass's cycle of switches gains a sliding onset)."""
    SLIDING_VANISH = "sliding_vanish"
    """A rest interval vanishes, or a mass at rest all period can no longer be held where it stuck."""
    GRAZING = "grazing"
    """The cycle of switches changes with as many rests: a pair of switches appears or vanishes
    where the orbit touches a boundary."""
    FOLD = "fold"
    """The branch turns back in the parameter: a multiplier crosses the unit circle at +1."""
    PERIOD_DOUBLING = "period_doubling"
    """A real multiplier crosses the unit circle at -1."""
    TORUS = "torus"
    """A complex pair of multipliers crosses the unit circle (Neimark-Sacker)."""

    @property
    def nonsmooth(self) -> bool:
        """Located where the cycle of switches changes (the map is not smooth there), not where a
        multiplier crosses the unit circle; the branch may jump across it."""
        return self in (Bifurcation.SLIDING_ONSET, Bifurcation.SLIDING_VANISH, Bifurcation.GRAZING)

    @classmethod
    def of_rests(cls, appears: bool) -> Bifurcation:
        """A rest interval appearing or vanishing as the parameter increases."""
        return cls.SLIDING_ONSET if appears else cls.SLIDING_VANISH

    @classmethod
    def of_multiplier(cls, mu: complex) -> Bifurcation:
        """The smooth bifurcation of a multiplier ``mu`` on the unit circle."""
        if abs(mu.imag) > 1e-6 * abs(mu):
            return cls.TORUS
        return cls.PERIOD_DOUBLING if mu.real < 0 else cls.FOLD


#: The kinds' text, as the ``kind`` column holds them.
BIFURCATION_KINDS = tuple(kind.value for kind in Bifurcation)


@dataclass(frozen=True)
class Skipped:
    """A point the corrector could not compute, and why (in place of a :class:`OrbitPoint`)."""

    lam: float
    reason: Reason
    message: str


def skipped(lam: float, error: OscillatorError) -> Skipped:
    reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
    return Skipped(lam, reason, str(error))


@dataclass(frozen=True)
class Branch:
    """A continued branch of periodic orbits.

    Attributes
    ----------
    param : str
        The continued parameter.
    points : DataFrame
        One row per point, in the order of the branch (including the orbits on either side of each
        located bifurcation): the parameter under its own name, ``x1, v1, x2, v2`` at the section,
        ``mu1..mu4`` (the multipliers, complex, largest modulus first: a real one near -1
        is a period doubling, a complex pair leaving the unit circle a torus), ``stable``, ``signature`` (the
        event kinds over one period as a cycle:
        :func:`~oscillator.orbits.signature.cyclic_signature`), ``piece`` (the branch's
        continuous pieces, numbered from 0: a new one begins after a jump or a gap) and
        ``iterations`` (the corrector's Newton steps; 0 for an orbit found at a bifurcation's
        side).
    bifurcations : DataFrame
        The parameter under its own name, ``kind`` (:data:`BIFURCATION_KINDS`), the state at the
        bifurcation (on the side the branch came from), ``jump`` (how far the orbit on the other
        side is, at the section: zero for a continuous bifurcation, finite where a rest interval
        appears with a finite length), ``before`` and ``after`` (the signatures on either side,
        along the branch).  Where no period-N orbit lies between the end of one kind and the
        start of the next (a gap), each end is a row of its own, with ``jump`` NaN and an empty
        ``after`` (the gap's first end) or ``before`` (its last), and the state of the orbit
        that ends there.
    section : float
        The section's time.
    period : int
        Forcing periods per return.
    complete : bool
        Whether the branch reached ``stop`` (else ``message`` says why it ended).
    message : str
    reason : Reason or None
        Why it ended early, for a program (:class:`~oscillator.errors.Reason`); None when complete.
    """

    param: str
    points: pd.DataFrame
    bifurcations: pd.DataFrame
    section: float
    period: int
    complete: bool = True
    message: str = ""
    reason: Reason | None = None
    case: Case | None = field(default=None, repr=False, compare=False)

    @cached_property
    def columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The points' parameter values, states at the section and pieces, as arrays (read once:
        the frequency response asks whether an orbit is on a branch thousands of times)."""
        points = self.points
        return points[self.param].to_numpy(float), points[list(STATE)].to_numpy(float), points["piece"].to_numpy()

    @property
    def coordinate(self) -> str:
        """The coordinate drawn by default: ``x2`` (as Fig. 14), unless it does not change along
        the branch (m2 parked): then the first of ``x1, v2, v1`` that does."""
        system = ARTICLE if self.case is None else self.case.system
        masses = system.masses[::-1]  # the last mass first: Fig. 14 draws x2
        order = [*(system.position(m) for m in masses), *(system.velocity(m) for m in masses)]
        for name in order:
            values = self.points[name].to_numpy(float)
            if len(values) and np.ptp(values) > 1e-9 * max(1.0, float(np.max(np.abs(values)))):
                return name
        return order[0]

    def plot(self, coordinate: str | None = None, *, sweep_points: pd.DataFrame | None = None) -> Figure:
        """The branch as ``oscillator continue`` draws it (``figures/branch.png``): ``coordinate``
        at the section (default :attr:`coordinate`) against the parameter, stable solid,
        unstable dashed, bifurcations marked; over ``sweep_points`` (columns the parameter and
        ``coordinate``), if given."""
        return presenter().plot_branch(self, check_coordinate(coordinate or self.coordinate), sweep_points)

    def responses(self, cutoff: float = 0.0) -> pd.DataFrame:
        """The response measures at every point (:func:`oscillator.orbits.response.branch_responses`):
        against ``Omega``, the branch's frequency response; ``force_above`` and ``a_above`` above
        ``cutoff`` Hz."""
        from oscillator.orbits.response import branch_responses

        return branch_responses(self, cutoff)

    def noise(self, harmonics: int = 200, cutoff: float = 0.0) -> pd.DataFrame:
        """The noise measures at every point (:func:`oscillator.orbits.noise.branch_noise`; levels
        above ``cutoff`` Hz): against ``Omega``, the branch's noise response."""
        from oscillator.orbits.noise import branch_noise

        return branch_noise(self, harmonics, cutoff)

    def plot_multipliers(self) -> Figure:
        """The multipliers' moduli against the parameter (``figures/multipliers.png``)."""
        return presenter().plot_multipliers(self)

    def save(self, folder: str | Path, *, coordinate: str | None = None) -> Path:
        """Write the branch as ``oscillator continue`` does (tables, ``case.toml``, ``run.json``,
        figures, report) into ``folder``, a new one; :func:`oscillator.read_run` reads it back."""
        return presenter().save_branch(
            self, as_folder(folder), coordinate=check_coordinate(coordinate or self.coordinate)
        )

    def _repr_html_(self) -> str:
        return presenter().branch_html(self)


def check_coordinate(name: str) -> str:
    if name not in STATE:
        raise InputError(f"coordinate must be one of {', '.join(STATE)}, got {name!r}", field="coordinate")
    return name


#: The multipliers' columns of a branch's points.
MULTIPLIERS = tuple(f"mu{k}" for k in range(1, 5))


def point_columns(param: str) -> list[str]:
    """The columns of a branch's points (:attr:`Branch.points`), in order."""
    return [param, *STATE, *MULTIPLIERS, "stable", "signature", "piece", "iterations"]


def points_on_disk(points: pd.DataFrame) -> pd.DataFrame:
    """The points with each complex multiplier ``muK`` as two columns ``muK_re``, ``muK_im``
    (Parquet has no complex numbers)."""
    frame = points.copy()
    for name in MULTIPLIERS:
        values = frame.pop(name).to_numpy(complex)
        frame[f"{name}_re"], frame[f"{name}_im"] = values.real, values.imag
    return frame


def points_from_disk(frame: pd.DataFrame) -> pd.DataFrame:
    """:func:`points_on_disk` undone; the multipliers' columns back where they were."""
    points = frame.copy()
    for name in MULTIPLIERS:
        points[name] = points.pop(f"{name}_re").to_numpy(float) + 1j * points.pop(f"{name}_im").to_numpy(float)
    order = [c for c in frame.columns if not c.endswith(("_re", "_im"))]
    at = order.index("stable") if "stable" in order else len(order)
    return points[[*order[:at], *MULTIPLIERS, *order[at:]]]
