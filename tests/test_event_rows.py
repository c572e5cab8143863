"""The compiled switching rules write events as rows of numbers; the tables read them back.

The rows' codes must read back as the texts the article's names give (``∂Ω12(2)``,
``F2^(0>0_1)``, ``(5.28)``, ``III-b``), the log must keep exactly the rows it was told to keep,
and a run that nobody reads a table of must not import pandas.
"""

import dataclasses
import re
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from conftest import random_case
from oscillator import simulate
from oscillator.engines import build_engine
from oscillator.hybrid.record import EventLog, RunRecord
from oscillator.hybrid.recording import SaveAt, recording
from oscillator.hybrid.supervisor import Supervisor
from oscillator.io.cases import resolve_case
from oscillator.io.tables import events_frame
from oscillator.model.events import WIDTH, EventKind, event_of_row
from oscillator.model.fields import kinetic_threshold
from oscillator.model.phase_space import Mode
from oscillator.model.resolving import resolve
from oscillator.model.roots import Root

BOUNDARY = re.compile(r"^(∂Ω(12|34|56|78|13|24|15|26|37|48|57|68|17|28|35|46)\((1|2)\)|x1 = d1|z1 = -d)$")
NAME = re.compile(r"^(F[12]\^\(([1-8]|0>0_[1-8])\)|v1|zdot1|)$")
STATE = re.compile(r"^(I|II|III|IV)-[abcd]$")


@pytest.fixture(scope="module")
def every_kind():
    """The events of constructed runs that reach every domain and every kind of event."""
    results = [simulate(random_case(seed), record_trajectory=False) for seed in (1, 145, 190, 268)]
    return [r.events for r in results]


def test_every_code_reads_back_as_the_articles_name(every_kind):
    kinds = set()
    for events in every_kind:
        kinds |= set(events.kind)
        assert events.boundary.map(BOUNDARY.match).all()
        assert events.G_alpha.map(NAME.match).all() and events.G_beta.map(NAME.match).all()
        assert events.state_from.map(STATE.match).all() and events.state_to.map(STATE.match).all()
        assert events.theorem.isin([f"5.{k}" for k in range(1, 10)] + ["Def. 5.2", "Def. 5.4"]).all()
        assert events.equation.str.fullmatch(r"\(5\.\d{1,2}\)").all()
        # a G-function's name is of the event's own mass
        named = events[events.G_alpha.str.startswith("F")]
        assert (named.G_alpha.str[1].astype(int) == named.mass).all()
        # Theorem 5.4's events, and only they, say which branch decided
        assert (events.branch != "").eq(events.theorem == "5.4").all()
    assert {"passable", "sliding_onset", "sliding_vanish", "left_contact_onset", "right_contact_onset"} <= kinds


def test_a_row_reads_back_as_the_event_its_table_row_shows():
    case = random_case(145)
    p, options = case.parameters, case.options
    record = RunRecord()
    policy = recording(SaveAt(steps=False), max_rows=10, period=p.period)
    engine = build_engine(None, p, options)
    try:
        Supervisor(p, options, engine, policy).run(case.initial.t0, case.initial.y, case.t_end, record)
    finally:
        engine.close()
    rows = record.events.rows
    assert len(rows) == record.event_count > 20
    decoded = pd.DataFrame([dataclasses.asdict(event_of_row(row)) for row in rows]).astype({"kind": "str"})
    pd.testing.assert_frame_equal(decoded, events_frame(rows), check_dtype=False)


def test_resolve_decides_an_arrival_as_the_theorems_say():
    # m2 of Instance 1 moving with v2 < 0 (domain 1) reaches v2 = 0 at t = 0 with x = 0, m1 at
    # rest: A2 = 0, so both sides' fields F2 = A2 -+ (mu_k g + p2) point at the boundary:
    # Theorem 5.2 (sliding exists), Eq. (5.16).
    case = resolve_case("instance-1")
    p = case.parameters
    mode = Mode.from_signs(0, -1, left=False, right=False)
    resolution = resolve(0.0, (0.0, 0.0, 0.0, 1e-17), p, mode, [Root.VELOCITY_2], case.options)
    (event,) = resolution.events
    assert (event.mass, event.kind, event.theorem, event.equation) == (2, EventKind.SLIDING_ONSET, "5.2", "(5.16)")
    assert (event.boundary, event.G_alpha, event.G_beta) == ("∂Ω12(2)", "F2^(1)", "F2^(2)")
    threshold = kinetic_threshold(p, 2)
    assert (event.G0_alpha, event.G0_beta) == pytest.approx((threshold, -threshold), abs=1e-15)
    assert (event.state_from, event.state_to) == ("I-b", "I-d")
    assert resolution.mode == Mode.from_signs(0, 0, left=False, right=False)
    assert resolution.y[3] == 0.0  # the velocity is projected onto its boundary


def test_the_log_keeps_what_it_is_told_to_keep_as_it_grows():
    log = EventLog(capacity=2)
    for k in range(5):
        buffer = log.free(3)
        buffer[len(log) : len(log) + 3] = k
        if k % 2 == 0:  # rows written but not kept are overwritten by the next ones
            log.keep(3)
    assert len(log) == 9
    assert log.rows[:, 0].tolist() == [0.0] * 3 + [2.0] * 3 + [4.0] * 3
    assert log.stage(np.ones((2, WIDTH))) == 2 and len(log) == 9
    assert log.staged(2).sum() == 2 * WIDTH


def test_a_run_whose_tables_nobody_reads_does_not_import_pandas():
    code = (
        "import sys\n"
        "from oscillator import simulate\n"
        "result = simulate('instance-3', record_trajectory=False)\n"
        "print('pandas' in sys.modules, result.stats.events, result.success)\n"
        "print(len(result.events), 'pandas' in sys.modules, result.events.kind.iloc[0])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "8", "True", "8", "True", "passable"]
