"""One event vocabulary: every kind of event and of bifurcation is known to every consumer, and
no consumer compares kinds as string literals (issue 26)."""

import ast
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from oscillator.model.events import EventKind
from oscillator.orbits.branch import Bifurcation
from oscillator.report.figures import KIND_STYLE
from oscillator.report.orbits import BIFURCATION_MARKERS, BIFURCATION_STYLE
from oscillator.report.transitions import BOTH_MASSES_SENTENCES, SENTENCES, transition_log

#: The package's source, as the checkout holds it (the tests import the installed copy).
PACKAGE = Path(__file__).resolve().parents[1] / "oscillator"
#: Where the kinds are defined, the only places their text may be written.
DEFINITIONS = {PACKAGE / "model" / "events.py", PACKAGE / "orbits" / "branch.py", PACKAGE / "model" / "chain_rules.py"}
#: The same words meaning something else.
OTHER_MEANINGS = {
    ("analysis/locate.py", "grazing"): "the word `oscillator locate --what` takes",
    ("cli/run.py", "fold"): "rich's overflow mode",
    ("cli/system.py", "fold"): "rich's overflow mode",
}


def _row(kind: EventKind, mass: int) -> SimpleNamespace:
    return SimpleNamespace(t=1.0, mass=mass, kind=kind.value, boundary="∂Ω12(1)", from_domain=1, to_domain=2,
                           theorem="5.1", equation="(5.10)", branch="", G0_alpha=-0.5, G1_alpha=0.25, G0_beta=0.5,
                           G1_beta=0.1, G_alpha="F1^(1)", G_beta="F1^(2)", distance=0.01)  # fmt: skip


@pytest.mark.parametrize("kind", list(EventKind))
def test_every_event_kind_has_every_property_and_every_consumer(kind):
    assert isinstance(kind.switches, bool) and isinstance(kind.starts_rest, bool)
    assert kind.contact in (None, "right", "left")
    assert not (kind.starts_rest and kind.ends_rest)
    marker, face, size = KIND_STYLE[kind]
    assert marker and face and size > 0
    # told once: by mass, or for both masses' rows together
    assert (kind in SENTENCES) != (kind in BOTH_MASSES_SENTENCES)
    rows = [_row(kind, 1), _row(kind, 2)] if kind.both_masses else [_row(kind, 1)]
    (line,) = transition_log(pd.DataFrame([vars(r) for r in rows]))  # one line, a sentence in it
    assert len(line.split("—", 1)[1].strip()) > 20, line


@pytest.mark.parametrize("kind", list(Bifurcation))
def test_every_bifurcation_kind_has_a_marker_and_a_class(kind):
    assert BIFURCATION_MARKERS[kind] and BIFURCATION_STYLE[kind]
    assert isinstance(kind.nonsmooth, bool)


def test_bifurcations_of_multipliers():
    assert Bifurcation.of_multiplier(complex(1.0, 0.0)) is Bifurcation.FOLD
    assert Bifurcation.of_multiplier(complex(-1.0, 0.0)) is Bifurcation.PERIOD_DOUBLING
    assert Bifurcation.of_multiplier(complex(0.6, 0.8)) is Bifurcation.TORUS


def test_no_module_compares_kinds_as_string_literals():
    """The kinds' text is written where they are defined and nowhere else in the package."""
    words = {kind.value for kind in EventKind} | {kind.value for kind in Bifurcation}
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path in DEFINITIONS:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        exports = [
            node
            for node in tree.body
            if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets)
        ]
        exported = {id(n) for node in exports for n in ast.walk(node)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and node.value in words and id(node) not in exported:
                where = str(path.relative_to(PACKAGE))
                if (where, node.value) not in OTHER_MEANINGS:
                    found.append(f"{where}:{node.lineno} {node.value!r}")
    assert found == []
