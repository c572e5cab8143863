"""The C-level CVODE engine: active here, identical to scikit-sundae's, every object freed, errors told."""

import ctypes
import gc
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings

from conftest import random_case
from oscillator import Mode, SimulationFailed, load_case, simulate
from oscillator.engines import default_engine
from oscillator.engines.cvode_c import CCvodeEngine
from oscillator.engines.sundials import SUPPORTED, load
from test_properties import systems


def test_the_compiled_engine_is_the_default_on_this_machine():
    """CI fails here, loudly, if SUNDIALS' libraries stop loading (a silent fallback would hide it)."""
    sundials = load()
    assert int(sundials.version.split(".")[0]) in SUPPORTED
    assert set(sundials.paths) >= {"core", "nvecserial", "sunmatrixdense", "sunlinsoldense", "cvode"}
    assert default_engine() == "cvode"
    assert simulate("instance-1", t_end=2.0).stats.engine == "cvode"


@pytest.mark.parametrize(
    "case", ["instance-1", "instance-2", "instance-3", "instance-4", "instance-5", 1, 141, 190, 268]
)
def test_the_compiled_engine_gives_the_same_tables_as_scikit_sundae(case):
    case = random_case(case) if isinstance(case, int) else load_case(case)
    compiled, python = simulate(case, engine="cvode"), simulate(case, engine="sksundae")
    pd.testing.assert_frame_equal(compiled.events, python.events, check_exact=True)
    pd.testing.assert_frame_equal(compiled.trajectory, python.trajectory, check_exact=True)
    assert compiled.energy == python.energy
    counts = ("returns", "rhs_evaluations", "restarts", "root_returns", "events")
    assert [getattr(compiled.stats, k) for k in counts] == [getattr(python.stats, k) for k in counts]


def test_a_solver_failure_is_told_in_the_error_and_nothing_is_printed(capfd):
    with pytest.raises(
        SimulationFailed,
        match=r"CVODE failed after t = .* with flag -1 \(CV_TOO_MUCH_WORK: took max_num_steps steps.*; CVODE: "
        r"\[CVode, Error: -1\] At t = .*mxstep steps taken before reaching tout",
    ) as caught:
        simulate("instance-3", max_num_steps=20, t_eval=[1.5, 4.0])
    assert caught.value.result is not None and caught.value.result.stats.engine == "cvode"
    printed = capfd.readouterr()
    assert printed.out == "" and printed.err == ""


def _rss_kib() -> int:
    with open(f"/proc/{os.getpid()}/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="reads the resident size from /proc")
def test_ten_thousand_problems_are_created_and_freed_with_flat_memory():
    case = load_case("instance-1")
    p, options = case.parameters, case.options
    y = np.zeros(8)
    y[:4] = case.initial.y

    resting = Mode(domain1=0, domain2=0, left=False, right=False)

    def batch(n):
        for _ in range(n):
            engine = CCvodeEngine(p, options)
            engine.reset(resting, case.initial.t0, y)
            engine.advance(1.01, t_stop=2.0, one_step=False)
            engine.close()
        gc.collect()

    batch(1000)  # warm: allocator pools, numba's dispatchers
    before = _rss_kib()
    batch(9000)
    grown = _rss_kib() - before
    assert grown < 4096, f"resident memory grew by {grown} KiB over 9,000 problems"


def test_the_compiled_callbacks_are_loaded_from_numbas_cache():
    """Compiled once per install: a new process finds both callbacks in numba's cache."""
    code = "import oscillator.engines.callbacks as cb; print(cb.rhs.cache_hits, cb.roots.cache_hits)"
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)  # fills the cache if empty
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    assert out.split() == ["1", "1"]


@settings(max_examples=40)
@given(systems())
def test_the_engines_agree_on_random_systems(case):
    """The property-test systems (tests/test_properties.py): identical event tables, or the same refusal."""
    outcomes = []
    for engine in ("cvode", "sksundae"):
        try:
            outcomes.append(simulate(case, engine=engine, record_trajectory=False).events)
        except SimulationFailed as error:
            outcomes.append(str(error))
    if isinstance(outcomes[0], str):  # both stop, at the same point (the solver's words differ)
        assert isinstance(outcomes[1], str) and outcomes[0].split(" with flag")[0] == outcomes[1].split(" with flag")[0]
    else:
        pd.testing.assert_frame_equal(outcomes[0], outcomes[1], check_exact=True)


def test_a_mass_at_rest_under_no_force_prints_no_warning(capfd):
    """m2 at rest with no force on it and no friction (beside a frictionless Duffing oscillator
    m1): root functions identically zero at restarts; CVODE stops watching them without a word
    on stdout (its logger printed a warning there at each of the 24 restarts)."""
    duffing = {"m1": 1.0, "K1": 0.0, "K2": 1.0, "C1": 0.05, "C2": 0.0, "Q1": 7.5, "Omega": 1.0, "x1": 2.5, "v1": 0.0}
    still = {"mu_k": 0.0, "mu_s": 0.0, "P1": 0.0, "P2": 0.0, "Q2": 0.0, "x2": 0.0, "v2": 0.0, "d": 1e3, "d1": 1e3}
    result = simulate("instance-1", t0=0.0, t_end=30.0, **duffing, **still)
    assert result.status.value == "complete" and len(result.events) > 0
    assert (result.trajectory.v2 == 0.0).all()
    ctypes.CDLL(None).fflush(None)  # SUNDIALS' logger writes through C's buffered stdout
    printed = capfd.readouterr()
    assert printed.out == "" and printed.err == ""
