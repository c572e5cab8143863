"""How many runs of the hybrid simulator this process has made: the cost an analysis reports
(a design counts the simulations each of its stages took, docs/design.md).

A run is one call of the supervisor through :func:`~oscillator.hybrid.simulate.simulate` (a map,
a Newton step's map, a transient), one of a friction chain's through
:func:`~oscillator.hybrid.chain_run.simulate_chain`, or one run whole in compiled code: a start landed by
:func:`oscillator.hybrid.batch.land_compiled`, a period map by
:func:`oscillator.hybrid.batch.map_compiled`.  Worker processes count their own; a task that
reports a cost returns the difference it made.
"""

from __future__ import annotations

__all__ = ["counted", "runs"]

_RUNS = [0]


def counted(count: int = 1) -> None:
    """Add ``count`` runs to this process's tally."""
    _RUNS[0] += count


def runs() -> int:
    """The runs made in this process so far."""
    return _RUNS[0]
