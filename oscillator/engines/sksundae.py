"""SUNDIALS CVODE through scikit-sundae's Python API: every scikit-sundae specific of the package is here.

The fallback of the C-level engine (:mod:`oscillator.engines.cvode_c`) where SUNDIALS' libraries
cannot be loaded directly; the same integrator and settings, a Python call per evaluation.

One CVODE problem per mode (both masses' domains and the contact flags), created on first use and
re-initialised at every restart; its root functions and their directions are those of
:mod:`oscillator.model.roots`, all of them terminal, so that CVODE returns at each root and the
supervisor decides.

CVODE integrates in a local time ``tau = t - t_ref`` with ``t_ref`` moved to the current time at
every restart.  CVODE locates a root to about ``100 eps max(|tau|, |h|)``; in absolute time that
would grow with ``t``, and with it the G-functions' values at their roots (1e-9 m/s in a velocity
after 940 s of Instance 1).  The fields themselves are evaluated at ``t_ref + tau``.
"""

from __future__ import annotations

import contextlib
import io
from typing import Any

import numpy as np
from sksundae.cvode import CVODE

from oscillator.engines import EngineFailure, Step, StepKind
from oscillator.model.fields import coefficients
from oscillator.model.kernels import derivative
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.roots import NUM_ROOTS, root_directions, root_kernel

__all__ = ["SksundaeEngine"]

#: CVODE's return flags (scikit-sundae ``status``) for a root and for reaching ``tstop``.
_ROOT_RETURN = 2
_TSTOP_RETURN = 1
#: CVODE's CV_ILL_INPUT, returned as "root found at and very near t" when a root function is
#: exactly 0.0 at the root it just returned and still 0.0 a rounding step later (a difference of
#: two O(1) velocities that change by less than an ulp); a restart at the root clears it.
_CLOSE_ROOTS = -22


class SksundaeEngine:
    """CVODE (Adams, dense Newton) with its rootfinding, through scikit-sundae's Python API."""

    name = "sksundae"
    size = 8

    def __init__(self, params: Parameters, options: SolverOptions) -> None:
        self._params = params
        self._options = options
        self._coefficients = coefficients(params)
        self._problems: dict[Mode, tuple[CVODE, Any]] = {}
        self._solver: CVODE | None = None
        self._roots: Any = None
        self._t_ref = 0.0  # CVODE's time is tau = t - _t_ref
        self._t = 0.0
        self._y = np.zeros(8)
        self._after_root = False
        self._done_evaluations = 0  # of the problems left behind
        self._evaluations = 0  # of the current problem since its last initialisation
        self._restarts = 0
        # scikit-sundae prints CVODE's error messages to stdout; they are caught here and told
        # in the engine's failure.
        self._output = io.StringIO()

    @property
    def rhs_evaluations(self) -> int:
        return self._done_evaluations + self._evaluations

    @property
    def restarts(self) -> int:
        return self._restarts

    def close(self) -> None:
        """Nothing to free by hand: scikit-sundae frees its objects with the solvers."""
        self._problems.clear()

    def _problem(self, mode: Mode) -> tuple[CVODE, Any]:
        """The CVODE problem of a mode, created on first use."""
        if mode in self._problems:
            return self._problems[mode]
        c = self._coefficients
        s1, s2, left, right = mode.sign(1), mode.sign(2), mode.left, mode.right
        step = self._options.max_step_fraction * self._params.period
        near = self._options.grazing_displacement_tolerance

        def rhs(tau: float, y: np.ndarray, yp: np.ndarray) -> None:
            derivative(self._t_ref + tau, y, yp, c, s1, s2, left, right)

        def roots(tau: float, y: np.ndarray, g: np.ndarray) -> None:
            root_kernel(self._t_ref + tau, y, g, c, s1, s2, left, right, step, near)

        roots.direction = root_directions(mode)  # type: ignore[attr-defined]
        roots.terminal = [True] * NUM_ROOTS  # type: ignore[attr-defined]
        solver = CVODE(
            rhs,
            method="Adams",
            rtol=self._options.rtol,
            atol=self._options.atol,
            max_step=step,
            max_num_steps=self._options.max_num_steps,
            eventsfn=roots,
            num_events=NUM_ROOTS,
        )
        self._problems[mode] = (solver, roots)
        return solver, roots

    def _initialise(self) -> None:
        assert self._solver is not None
        self._done_evaluations += self._evaluations
        self._evaluations = 0
        self._t_ref = self._t
        self._output.seek(0)
        self._output.truncate()
        self._solver.init_step(0.0, self._y)
        self._restarts += 1
        self._after_root = False

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        self._solver, self._roots = self._problem(mode)
        self._t, self._y = t, np.array(y, dtype=float)
        self._initialise()

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        assert self._solver is not None
        method = "onestep" if one_step else "normal"
        while True:
            with contextlib.redirect_stdout(self._output):
                out = self._solver.step(target - self._t_ref, method=method, tstop=t_stop - self._t_ref)
            if out.status == _CLOSE_ROOTS and self._after_root:
                self._initialise()  # at the root just returned
                continue
            self._evaluations = out.nfev
            if out.status < 0:
                said = " ".join(self._output.getvalue().split())
                raise EngineFailure(f"{out.message}; CVODE: {said}" if said else out.message, out.status)
            break
        y = np.array(out.y, dtype=float)
        if out.status == _ROOT_RETURN:
            t = self._t_ref + float(out.t)
            fired = tuple(int(i) for i in np.flatnonzero(out.i_events[-1]))
            # scikit-sundae keeps every root in Python lists for the solver's lifetime; empty
            # them so that memory stays flat in the length of the run.
            self._roots._i.clear()
            self._roots._t.clear()
            self._roots._y.clear()
            step = Step(t, y, StepKind.ROOT, fired)
        elif out.status == _TSTOP_RETURN:
            step = Step(t_stop, y, StepKind.TARGET)
        elif one_step:
            step = Step(self._t_ref + float(out.t), y, StepKind.STEP)
        else:
            step = Step(target, y, StepKind.TARGET)
        self._t, self._y = step.t, y
        self._after_root = step.kind is StepKind.ROOT
        return step
