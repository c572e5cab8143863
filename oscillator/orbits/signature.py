"""An orbit's cycle of switches: the identity of a periodic motion along a branch and across
parameter points (:class:`Signature`: each mass's own cycle of :class:`~oscillator.model.events.EventKind`),
read from its events."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, TypeVar

import pandas as pd

from oscillator.model.events import EventKind

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.shooting import PeriodMap


class _Named(Protocol):
    @property
    def value(self) -> str: ...


K = TypeVar("K", bound=_Named)

__all__ = ["Signature", "cyclic_signature", "event_signature", "own_cycle", "signature_of", "signature_text"]


def event_signature(events: pd.DataFrame) -> tuple[tuple[int, EventKind], ...]:
    """The orbit's switches over one period, in order: ``((2, SLIDING_ONSET), (2, SLIDING_VANISH), ...)``
    (grazing contacts are not switches and are left out)."""
    switches = events[events.kind.isin(EventKind.values_where(lambda kind: kind.switches))]
    return tuple((int(mass), EventKind(kind)) for mass, kind in zip(switches["mass"], switches["kind"], strict=True))


def signature_text(signature: tuple[tuple[int, EventKind], ...]) -> str:
    """An :func:`event_signature` for display: ``"m2 sliding_onset, m2 sliding_vanish, ..."``."""
    return ", ".join(f"m{mass} {kind.value}" for mass, kind in signature)


@dataclass(frozen=True)
class Signature:
    """Each mass's own cycle of switches over one period, the orbit's identity along a branch.

    ``cycles[mass - 1]`` is mass ``mass``'s switches as a cycle, written from the rotation whose
    text sorts first: where the section cuts the orbit, and how the two masses' events
    interleave, do not change it; only a change of a mass's own cycle does (a rest interval or a
    pair of switches appearing or vanishing).  ``str()`` gives the text form shown to people and
    stored in tables: ``"m1: passable, passable; m2: passable, sliding_onset, ..."``.
    """

    cycles: tuple[tuple[EventKind, ...], tuple[EventKind, ...]]

    @property
    def rests(self) -> int:
        """Rest intervals per period, both masses together."""
        return sum(kind.starts_rest for cycle in self.cycles for kind in cycle)

    def __str__(self) -> str:
        return "; ".join(
            f"m{mass}: {', '.join(cycle) if cycle else 'none'}" for mass, cycle in enumerate(self.cycles, start=1)
        )


def cyclic_signature(image: PeriodMap) -> Signature:
    """The :class:`Signature` of an orbit through ``image`` (:func:`signature_of` its events)."""
    return signature_of(image.kinds, image.t1 - image.t0)


def signature_of(events: Sequence[tuple[float, int, EventKind]], span: float) -> Signature:
    """The :class:`Signature` of the events ``(t, mass, kind)`` of one return of length ``span``.

    Each mass's switches are read as a cycle (a switch at both ends of the return, there because
    the orbit is on a boundary at the section, counted once).
    """
    cycles = [own_cycle([(t, kind) for t, m, kind in events if m == mass and kind.switches], span) for mass in (1, 2)]
    return Signature((cycles[0], cycles[1]))


def own_cycle(own: Sequence[tuple[float, K]], span: float) -> tuple[K, ...]:
    """One owner's switches ``(t, kind)`` over one return of length ``span``, as a cycle: a
    switch at both ends of the return (the orbit on a boundary at the section) counted once, and
    written from the rotation whose text sorts first, so that where the section cuts the orbit
    does not change it.  (A mass's cycle here; an element's in a friction chain's
    :func:`oscillator.attractors.chain_attractors.chain_signature`.)"""
    kinds = [kind for _, kind in own]
    if len(kinds) > 1 and kinds[0] == kinds[-1] and abs((own[-1][0] - own[0][0]) - span) <= 1e-6 * span:
        kinds.pop()
    rotations = [tuple(kinds[k:] + kinds[:k]) for k in range(len(kinds))]
    return min(rotations, key=lambda cycle: [kind.value for kind in cycle], default=())
