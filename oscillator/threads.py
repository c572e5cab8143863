"""One BLAS thread for the package's process and the workers it starts.

The package's matrices have a few dozen rows at most (a monodromy, a Jacobian, a matrix
exponential of one mode). A second BLAS thread does not share such work: it spins between calls,
doubling the CPU time of every small product, solve and exponential, and on a loaded machine the
spinning thread takes a core from the computation (``benchmarks/threads.py`` measures both).
``import oscillator`` therefore asks for one BLAS thread, unless the user chose a number: any of
:data:`CHOSEN` set in the environment leaves every library as configured.
"""

from __future__ import annotations

import os
import sys

__all__ = ["CHOSEN", "one_blas_thread"]

#: The variables through which a user chooses BLAS's threads: any of them set, the package leaves
#: the threads alone.
CHOSEN = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS")


def one_blas_thread() -> None:
    """One thread in every BLAS library: those loaded from now on (and in the worker processes,
    which inherit the environment) through ``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS``,
    those already loaded (NumPy imported before the package) through threadpoolctl; nothing
    where the user set any of :data:`CHOSEN`."""
    if any(name in os.environ for name in CHOSEN):
        return
    os.environ["OPENBLAS_NUM_THREADS"] = os.environ["MKL_NUM_THREADS"] = "1"
    if "numpy" in sys.modules:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1, user_api="blas")
