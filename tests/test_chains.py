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
    "a stop without stiffness": (
        BLADE + '[[element]]\ntype = "stop"\non = "blade"\nside = "right"\nat = 1\nK = 0\n',
        "element 'stop-4': K must be positive",
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
