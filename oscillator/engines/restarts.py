"""What both CVODE engines keep alike (``cvode`` through the C API, ``sksundae`` through
scikit-sundae): CVODE's time measured from the last restart, the restarts counted, CVODE's
refusal right after a root, and a return turned into a :class:`~oscillator.engines.Step`."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from oscillator.engines import Step, StepKind
from oscillator.engines.sundials import CV_ROOT_RETURN, CV_TSTOP_RETURN

__all__ = ["CLOSE_ROOTS", "Restarts"]

#: CVODE's CV_ILL_INPUT, returned as "root found at and very near t" when a root function is
#: exactly 0.0 at the root it just returned and still 0.0 a rounding step later (a difference of
#: two O(1) velocities that change by less than an ulp); a restart at the root clears it.
CLOSE_ROOTS = -22


class Restarts:
    """An engine's clock and count of restarts.

    CVODE integrates in a local time ``tau = t - t_ref`` from its last restart, so that a
    restart late in a long run keeps the time's resolution; :meth:`step` reads a return in the
    run's time.
    """

    def __init__(self) -> None:
        self.t_ref = 0.0
        self.count = 0
        self.after_root = False

    def restarted(self, t: float) -> None:
        """CVODE was (re-)initialised at ``t``."""
        self.t_ref, self.after_root = t, False
        self.count += 1

    def refused_at_root(self, flag: int) -> bool:
        """Whether ``flag`` is CVODE's close-roots refusal right after a root return: the engine
        then restarts at the root it returned and calls again."""
        return flag == CLOSE_ROOTS and self.after_root

    def step(
        self,
        flag: int,
        tau: float,
        y: np.ndarray,
        *,
        target: float,
        t_stop: float,
        one_step: bool,
        fired: Callable[[], tuple[int, ...]],
    ) -> Step:
        """The return of a successful call (``flag >= 0``, CVODE's time ``tau``, state ``y``)."""
        if flag == CV_ROOT_RETURN:
            step = Step(self.t_ref + tau, y, StepKind.ROOT, fired())
        elif flag == CV_TSTOP_RETURN:
            step = Step(t_stop, y, StepKind.TARGET)
        elif one_step:
            step = Step(self.t_ref + tau, y, StepKind.STEP)
        else:
            step = Step(target, y, StepKind.TARGET)
        self.after_root = step.kind is StepKind.ROOT
        return step
