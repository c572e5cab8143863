"""The system as a value: what a layer reads of a machine instead of assuming it (issue 51).

A :class:`System` says a machine's shape: its masses (their keys and labels), its state's names
in the order the integrated vector holds them, each mass's position and velocity among them, its
parameters' names, its stops and contacts, its mode's width, its measures' suffix per mass.  The
article's two-mass oscillator is :data:`ARTICLE`, written here once from its parameters and
initial state (:mod:`oscillator.model.parameters`); a friction chain's is
:attr:`FrictionChain.system <oscillator.model.chains.FrictionChain.system>`.  A layer that needs a
size or a name takes the system from the value it was given (``case.system``, ``chain.system``),
as diffrax's solvers take the terms they are handed: it does not import the article's model to
learn them.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass

from oscillator.model.parameters import InitialState, Parameters

__all__ = ["ARTICLE", "System"]


@dataclass(frozen=True)
class System:
    """A machine's shape (module docstring).

    Attributes
    ----------
    title : str
        What the machine is.
    masses : tuple
        Each mass's key: what event tables write in their ``mass`` column (the article's 1, 2; a
        chain's mass names).
    labels : tuple of str
        Each mass's label in figures and measures' names (``m1``; a chain's mass name).
    state : tuple of str
        The state's names, in the order the integrated vector holds them: each mass's position and
        velocity, then any further state (a Jenkins slider's ``z:<element>``).
    parameters : tuple of str
        Every parameter's name.
    contacts : tuple of str
        The stops and contacts (the article's ``right``, ``left``; a chain's element names).
    mode_width : int
        The mode's integers: one per switching element (the article's two velocity signs and two
        contact flags).
    """

    title: str
    masses: tuple[Hashable, ...]
    labels: tuple[str, ...]
    state: tuple[str, ...]
    parameters: tuple[str, ...]
    contacts: tuple[str, ...]
    mode_width: int

    @property
    def size(self) -> int:
        """The state's length."""
        return len(self.state)

    def _index(self, mass: Hashable) -> int:
        try:
            return self.masses.index(mass)
        except ValueError:
            known = ", ".join(repr(m) for m in self.masses)
            raise KeyError(f"{mass!r} is no mass of {self.title} (masses: {known})") from None

    def position(self, mass: Hashable) -> str:
        """The name of ``mass``'s position in :attr:`state` (``x1``; ``x:blade``)."""
        return self.state[2 * self._index(mass)]

    def velocity(self, mass: Hashable) -> str:
        """The name of ``mass``'s velocity in :attr:`state` (``v1``; ``v:blade``)."""
        return self.state[2 * self._index(mass) + 1]

    def label(self, mass: Hashable) -> str:
        """``mass``'s label (``m1``; ``blade``)."""
        return self.labels[self._index(mass)]

    def suffix(self, mass: Hashable) -> str:
        """The suffix of ``mass``'s response measures' names (``x_max_m1``: ``_m1``)."""
        return f"_{self.label(mass)}"

    @property
    def motion(self) -> tuple[str, ...]:
        """The masses' positions and velocities, mass after mass (the state without sliders)."""
        return self.state[: 2 * len(self.masses)]


#: The article's two-mass oscillator: masses 1 and 2, the state ``x1, v1, x2, v2``, its 25
#: parameters, the right stop and the left contact, its mode (each mass's velocity sign, the left
#: and right contact flags).
ARTICLE = System(
    title="the article's two-mass oscillator",
    masses=(1, 2),
    labels=("m1", "m2"),
    state=tuple(name for name in InitialState.names() if name != "t0"),
    parameters=Parameters.names(),
    contacts=("right", "left"),
    mode_width=4,
)
