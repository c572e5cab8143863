"""The explorer in the browser: move a parameter, see the motion and its switches; click a map, see
its attractor (docs/explore.md), of the article's system or of a friction chain (docs/systems.md).
:func:`explore` builds it for a notebook; ``oscillator explore`` serves it."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.exploring.app import Explorer
    from oscillator.io.cases import Case
    from oscillator.model.chains import FrictionChain

__all__ = ["explore"]


def explore(
    case_or_folder: Case | FrictionChain | str | Path, periods: int = 50, *, engine: str = "dop853", **overrides: float
) -> Explorer:
    """The explorer of a case (a name, a case file or a :class:`~oscillator.Case`, with
    ``overrides`` of its parameters and start), of a friction chain or a system file (``overrides``
    by the chain's names: ``**{"platform.F": 0.5}``), or of an atlas, basins, sweep or
    frequency-response folder: displayed by a notebook, served by ``oscillator explore``.
    ``engine`` draws each change (see :class:`~oscillator.exploring.app.Explorer`)."""
    from oscillator.exploring.app import Explorer
    from oscillator.exploring.maps import picture_of
    from oscillator.exploring.scene import check_periods
    from oscillator.exploring.subjects import subject_of

    periods = check_periods(periods)
    if isinstance(case_or_folder, str | Path) and Path(case_or_folder).is_dir():
        picture = picture_of(case_or_folder)
        return Explorer(subject_of(picture.case, **overrides), periods, picture=picture, engine=engine)
    return Explorer(subject_of(case_or_folder, **overrides), periods, engine=engine)
