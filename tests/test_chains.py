"""Friction chains declared by users (issue 51): the system file of the issue read as written, the
Python builder giving the same chain, a file written back read back equal, and every bad
declaration refused in one message naming the element and the field, with the fix."""

from __future__ import annotations

import pytest

from oscillator.errors import InputError
from oscillator.io.chains import chain_to_toml, load_system
from oscillator.model.chains import MAX_MASSES, FrictionChain

BLADE = """
title = "Blade with a friction damper"
[system]
Omega = 1.0
g = 9.8
t0 = 0.0
[[mass]]
name = "blade"
m = 1.0
x = 0.0
v = 0.5
[[mass]]
name = "damper"
m = 0.1
[[element]]
type = "spring"
on = "blade"
k = 1.0
[[element]]
type = "jenkins"
on = "blade"
with = "damper"
kt = 2.0
F = 0.3
[[element]]
type = "force"
on = "blade"
Q = 0.5
phi = 0.0
"""


def _file(tmp_path, text: str):
    path = tmp_path / "machine.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_issues_system_file_is_read_as_written(tmp_path):
    chain = load_system(_file(tmp_path, BLADE))
    assert [(m.name, m.m, m.x, m.v) for m in chain.masses] == [("blade", 1.0, 0.0, 0.5), ("damper", 0.1, 0.0, 0.0)]
    assert [(e.name, e.type, e.on, e.with_) for e in chain.elements] == [
        ("spring-1", "spring", "blade", None),
        ("jenkins-2", "jenkins", "blade", "damper"),
        ("force-3", "force", "blade", None),
    ]
    assert chain.elements[0].values == {"k": 1.0, "k3": 0.0}  # the defaults filled in
    assert chain.elements[1].values == {"kt": 2.0, "F": 0.3}
    assert (chain.Omega, chain.g, chain.t0, chain.title) == (1.0, 9.8, 0.0, "Blade with a friction damper")


def test_the_builder_gives_the_files_chain_and_a_written_file_reads_back_equal(tmp_path):
    built = (
        FrictionChain(Omega=1.0, title="Blade with a friction damper")
        .mass("blade", m=1.0, v=0.5)
        .mass("damper", m=0.1)
        .spring("blade", k=1.0)
        .jenkins("blade", "damper", kt=2.0, F=0.3)
        .force("blade", Q=0.5)
    )
    assert built == load_system(_file(tmp_path, BLADE))
    every = (
        built.mass("third", m=2.0, x=-0.5)
        .damper("third", "damper", c=0.1, c3=0.01)
        .friction("third", mu_s=0.3, mu_k=0.2, w=0.4, P=0.1)
        .stop("blade", side="right", at=2.0, K=100.0, C=0.5)
        .contact("third", "damper", side="left", gap=0.25, K=50.0)
        .jenkins("damper", kt=1.0, F=0.1, name="to the ground")
    )
    assert load_system(_file(tmp_path, chain_to_toml(every))) == every
    friction = every.elements[4]
    assert friction.values["N"] is None and every.normal_force(friction) == pytest.approx(2.0 * 9.8)


def _with(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new, 1)


MASSES = "\n".join(f'[[mass]]\nname = "m{k}"\nm = 1.0' for k in range(MAX_MASSES + 1))
BAD = {
    # what is wrong: (the file, what the message must say, the field)
    "no mass": ('[system]\nOmega = 1.0\n', "the system has no mass; declare one", "mass"),
    "a zero mass": (_with(BLADE, "m = 0.1", "m = 0.0"), "mass 'damper': m must be positive", "m"),
    "a negative mass": (_with(BLADE, "m = 0.1", "m = -1"), "mass 'damper': m must be positive", "m"),
    "an element on no mass": (
        _with(BLADE, 'with = "damper"', 'with = "dampr"'),
        "element 'jenkins-2': with = 'dampr' is no mass of the system; did you mean 'damper'?",
        "with",
    ),
    "mu_s < mu_k": (
        BLADE + '[[element]]\ntype = "friction"\non = "damper"\nmu_s = 0.1\nmu_k = 0.2\n',
        "element 'friction-4': mu_s (0.1) must be at least mu_k (0.2)",
        "mu_s",
    ),
    "a negative gap": (
        BLADE + '[[element]]\ntype = "contact"\non = "damper"\nwith = "blade"\nside = "left"\ngap = -1\nK = 1\n',
        "element 'contact-4': gap must not be negative",
        "gap",
    ),
    "two friction elements on a mass": (
        BLADE + '[[element]]\ntype = "friction"\non = "blade"\nmu_s = 0.3\nmu_k = 0.2\n'
        '[[element]]\ntype = "friction"\non = "blade"\nmu_s = 0.3\nmu_k = 0.2\nname = "again"\n',
        "element 'again': mass 'blade' has a friction element already ('friction-4')",
        "on",
    ),
    "an unknown type": (
        _with(BLADE, 'type = "jenkins"', 'type = "jenkin"'), "unknown type 'jenkin'; did you mean 'jenkins'?", "type"
    ),
    "an unknown field": (
        _with(BLADE, "kt = 2.0", "kT = 2.0"), "element 'jenkins-2': unknown field 'kT'; did you mean 'kt'?", "kT"
    ),
    "too many masses": (MASSES, f"at most {MAX_MASSES} masses fit the compiled kernels", "mass"),
    "a contact without with": (
        BLADE + '[[element]]\ntype = "contact"\non = "damper"\nside = "left"\ngap = 1\nK = 1\n',
        "a contact acts between two masses; give with = <another mass>",
        "with",
    ),
    "a force with with": (_with(BLADE, 'Q = 0.5', 'with = "damper"\nQ = 0.5'), "leave out with", "with"),
    "a side that is none": (
        BLADE + '[[element]]\ntype = "stop"\non = "blade"\nside = "up"\nat = 1\nK = 1\n',
        "side must be 'left' or 'right'",
        "side",
    ),
    "a stop of negative stiffness": (
        BLADE + '[[element]]\ntype = "stop"\non = "blade"\nside = "right"\nat = 1\nK = -1\n',
        "element 'stop-4': K must not be negative",
        "K",
    ),
    "text for a number": (_with(BLADE, "F = 0.3", 'F = "strong"'), "element 'jenkins-2': F = 'strong' is not", "F"),
    "a missing field": (_with(BLADE, "F = 0.3", ""), "a jenkins needs F; add it", "F"),
    "a name with control characters": (_with(BLADE, 'name = "damper"', 'name = "d\\u001b[31m"'), "printable", "name"),
    "two masses of one name": (
        _with(BLADE, 'name = "damper"', 'name = "blade"'), "two masses are named 'blade'", "name"
    ),
    "an unknown system setting": (
        _with(BLADE, "g = 9.8", "G = 9.8"), "[system]: unknown key 'G'; did you mean 'g'?", "G"
    ),
}  # fmt: skip


@pytest.mark.parametrize("bad", BAD)
def test_a_bad_declaration_is_refused_naming_the_element_and_the_field(tmp_path, bad):
    text, said, field = BAD[bad]
    with pytest.raises(InputError) as refused:
        load_system(_file(tmp_path, text))
    message = str(refused.value)
    assert said in message and refused.value.field == field, message
    assert message.startswith(str(tmp_path)) and "\n" not in message and "\x1b" not in message


def test_the_articles_system_as_a_chain_has_the_articles_field_in_every_mode():
    """The article's two masses written as a friction chain (article_chain): in each of its 36
    modes (each mass slipping either way or stuck, the contact and the stop open or closed), at
    random states and times of Instance 1 and of a system with every term on, the chain's compiled
    field equals the built-in one (model.kernels.rates) to 1e-12."""
    import itertools

    import numpy as np

    from oscillator.io.cases import resolve_case
    from oscillator.model.chain_fields import arrays_of, chain_derivative, pack
    from oscillator.model.chains import article_chain, article_mode
    from oscillator.model.fields import coefficients
    from oscillator.model.kernels import rates

    every = {"C2": 0.1, "C3": 0.3, "C5": 0.05, "K2": 0.2, "K5": 0.3, "P1": 0.4, "P2": 0.2, "phi2": 0.7, "Q2": 3.0}
    rng = np.random.default_rng(51)
    for case in (resolve_case("instance-1"), resolve_case("instance-1", **every)):
        p = case.parameters
        chain = article_chain(p, case.initial)
        a = arrays_of(chain)
        c = coefficients(p)
        for s1, s2, left, right in itertools.product((-1, 0, 1), (-1, 0, 1), (False, True), (False, True)):
            mode = np.array(article_mode(s1, s2, left, right), dtype=np.int64)
            for _ in range(5):
                t, (x1, v1, x2, v2) = rng.uniform(0, 10), rng.uniform(-5, 5, 4)
                v1, v2 = (v1 if s1 else 0.0), (v2 if s2 else 0.0)  # a stuck mass rests
                y, yp = np.array([x1, v1, x2, v2]), np.empty(4)
                chain_derivative(t, y, yp, pack(a, mode))
                expected = rates(t, x1, v1, x2, v2, c, s1, s2, left, right)[:4]
                np.testing.assert_allclose(yp, expected, rtol=1e-12, atol=1e-12 * max(1.0, np.max(np.abs(expected))))


def test_a_jenkins_slider_and_a_belt_in_their_modes():
    """A mass on a belt moving at w = 0.4 with a Jenkins element to the ground (kt = 2, F = 0.3) and
    a contact to a second mass: stuck to the belt it moves with it (x' = w, v' = 0); the stuck
    slider holds (z' = 0) and pulls with kt (u - z); slipping, it pulls with F against its motion
    and follows (z' = u'); the closed contact pushes with K (u + gap) + C u'."""
    import numpy as np

    from oscillator.model.chain_fields import arrays_of, chain_derivative, pack, state_of

    chain = (
        FrictionChain(Omega=2.0)
        .mass("a", m=2.0, x=0.5, v=0.4)
        .mass("b", m=1.0, x=1.0)
        .friction("a", mu_s=0.3, mu_k=0.2, w=0.4)
        .jenkins("a", kt=2.0, F=0.3)
        .contact("a", "b", side="left", gap=0.1, K=10.0, C=0.5)
    )
    a = arrays_of(chain)
    y = state_of(chain)
    assert a.size == 5 and list(y) == [0.5, 0.4, 1.0, 0.0, 0.5]
    from oscillator.model.chain_fields import data_length

    assert len(pack(a, [0, 0, 0])) == data_length(
        2, 3
    )  # what the callbacks read  # the slider unstretched at a's place
    y[4] = 0.2  # the slider has slipped back: its spring is stretched by 0.3

    def field(*mode):
        yp = np.empty(5)
        chain_derivative(0.0, y, yp, pack(a, mode))
        return yp

    stuck = field(0, 0, 0)
    assert list(stuck[:2]) == [0.4, 0.0] and stuck[4] == 0.0  # a rides the belt; the slider holds
    assert stuck[3] == 0.0  # b: no force on it with the contact open
    slipping = field(1, 0, 0)
    assert slipping[1] == pytest.approx((-2.0 * 0.3 - 0.2 * 2.0 * 9.8) / 2.0)  # kt (u - z) and kinetic friction
    assert field(1, 1, 0)[1] == pytest.approx((-0.3 - 0.2 * 2.0 * 9.8) / 2.0) and field(1, 1, 0)[4] == 0.4
    closed = field(1, 1, 1)
    push = 10.0 * (0.5 - 1.0 + 0.1) + 0.5 * (0.4 - 0.0)  # K (u + gap) + C u' = -3.8: a pushed by +3.8, b by -3.8
    assert closed[1] == pytest.approx((-0.3 - 0.2 * 2.0 * 9.8 - push) / 2.0) and closed[3] == pytest.approx(push / 1.0)
