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

from oscillator.engines import EngineFailure, Step
from oscillator.engines.restarts import Restarts
from oscillator.model.fields import coefficients
from oscillator.model.kernels import derivative
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.roots import NUM_ROOTS, root_directions, root_kernel

__all__ = ["SksundaeEngine"]


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
        self._clock = Restarts()  # CVODE's time is tau = t - t_ref
        self._t = 0.0
        self._y = np.zeros(8)
        self._done_evaluations = 0  # of the problems left behind
        self._evaluations = 0  # of the current problem since its last initialisation
        # scikit-sundae prints CVODE's error messages to stdout; they are caught here and told
        # in the engine's failure.
        self._output = io.StringIO()

    @property
    def rhs_evaluations(self) -> int:
        return self._done_evaluations + self._evaluations

    @property
    def restarts(self) -> int:
        return self._clock.count

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
            derivative(self._clock.t_ref + tau, y, yp, c, s1, s2, left, right)

        def roots(tau: float, y: np.ndarray, g: np.ndarray) -> None:
            root_kernel(self._clock.t_ref + tau, y, g, c, s1, s2, left, right, step, near)

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
        self._clock.restarted(self._t)
        self._output.seek(0)
        self._output.truncate()
        self._solver.init_step(0.0, self._y)

    def reset(self, mode: Mode, t: float, y: np.ndarray) -> None:
        self._solver, self._roots = self._problem(mode)
        self._t, self._y = t, np.array(y, dtype=float)
        self._initialise()

    def advance(self, target: float, *, t_stop: float, one_step: bool) -> Step:
        assert self._solver is not None
        method, t_ref = ("onestep" if one_step else "normal"), self._clock.t_ref
        while True:
            with contextlib.redirect_stdout(self._output):
                out = self._solver.step(target - t_ref, method=method, tstop=t_stop - t_ref)
            if self._clock.refused_at_root(out.status):
                self._initialise()  # at the root just returned
                t_ref = self._clock.t_ref
                continue
            self._evaluations = out.nfev
            if out.status < 0:
                said = " ".join(self._output.getvalue().split())
                raise EngineFailure(f"{out.message}; CVODE: {said}" if said else out.message, out.status)
            break
        step = self._clock.step(
            out.status,
            float(out.t),
            np.array(out.y, dtype=float),
            target=target,
            t_stop=t_stop,
            one_step=one_step,
            fired=lambda: self._fired(out),
        )
        self._t, self._y = step.t, step.y
        return step

    def _fired(self, out: Any) -> tuple[int, ...]:
        """The roots of the last return; scikit-sundae keeps every root in Python lists for the
        solver's lifetime: they are emptied, so that memory stays flat in the length of the run."""
        roots = self._roots
        fired = tuple(int(i) for i in np.flatnonzero(out.i_events[-1]))
        roots._i.clear()
        roots._t.clear()
        roots._y.clear()
        return fired
