"""Shared builders for constructed cases, and hypothesis profiles.

``HYPOTHESIS_PROFILE=thorough pytest tests/test_properties.py`` runs 1500 fresh examples per
property instead of the default fixed 100.
"""

import os
import signal
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from oscillator import Case, InitialState, Parameters, SolverOptions

# CI runs the same 100 examples of each property every time (derandomize): a red run is a change
# of the code, never a new random draw.  The thorough profile draws afresh, to explore.
settings.register_profile(
    "default", max_examples=100, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("thorough", max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

# The Pythons the tests start import the package the tests import: the installed one, as the
# commands do. Started in a checkout, `python -c` would put the source tree first, numba would
# compile every kernel again for that second copy, and Python its modules on every start.
os.environ["PYTHONSAFEPATH"] = "1"

# A shell without job control starts a background command ('pytest ... &') with SIGINT ignored,
# and every process the tests start would inherit that: the tests of Ctrl-C would then see a
# command that cannot be interrupted.  They need the disposition a terminal gives.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


#: The package's notice of a first compile (``oscillator.compiled.NOTICE_VARIABLE``, written out:
#: importing that module says the notice), off while the tests compile the kernels before their
#: workers start (:func:`pytest_configure` says it instead).
NOTICE = "OSCILLATOR_COMPILE_NOTICE"


def pytest_configure(config):
    """On a fresh install (numba's cache empty), the kernels compiled once, before the test workers
    start (this runs in pytest-xdist's controller first): both workers compiled all of them at once
    (CI's default run: 217 s, against 162 s with the cache filled).  The compiled landing's kernels
    too, and the compiled period map's, as the analyses compile them before their own workers
    (``before_workers``), and the friction chains' in a second process meanwhile.  It says so
    itself: the package's own notice ("once ... later runs ...") speaks of one command's kernels."""
    if hasattr(config, "workerinput"):
        return
    told = NOTICE in os.environ
    os.environ.setdefault(NOTICE, "0")
    try:
        from oscillator.compiled import CACHE, kernels_cached
    finally:
        if not told:
            del os.environ[NOTICE]
    if not CACHE or kernels_cached():
        return
    import subprocess
    import sys

    print(
        "tests: numba's cache is empty (a fresh install): compiling every kernel the tests use before the test "
        "workers start; the next runs load them",
        file=sys.stderr,
        flush=True,
    )

    from oscillator.attractors.mapping import _compile_landing
    from oscillator.cli.console import compile_kernels
    from oscillator.orbits.stroboscopic import compile_period_map

    # The chains' kernels (and the pieces' integrator, about 15 s) in a second process meanwhile:
    # the two sets share none of their compiled functions (measured cold: 19 s and 25 s in turn).
    here = str(Path(__file__).resolve().parent)
    code = f"import sys; sys.path.insert(0, {here!r}); from conftest import _compile_chains; _compile_chains()"
    helper = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    compile_kernels(beside=True, show=False)
    _compile_landing()
    compile_period_map()
    if helper.wait() != 0:  # it failed: compiled here, where a failure shows
        _compile_chains()


def _compile_chains() -> None:
    """The friction chains' kernels (field, roots, CVODE's callbacks; the field called from Python
    for the orbit's measures; the tangent equations and the roots' gradients of the orbits'
    derivatives): about 6 s a worker, cold."""
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.chain_orbits import find_chain_orbit
    from oscillator.orbits.chain_response import orbit_measures

    chain = (
        FrictionChain(Omega=1.0)
        .mass("m", 1.0, v=1.0)
        .spring("m", k=1.0)
        .damper("m", c=0.5)
        .force("m", Q=1.0)
        .friction("m", mu_s=0.2, mu_k=0.1)
        .jenkins("m", kt=1.0, F=0.1)
        .stop("m", side="right", at=5.0, K=10.0)
    )
    orbit = find_chain_orbit(chain, transient=5)
    orbit_measures(orbit)
    orbit.sensitivities("Omega")


#: A system with every nonlinear and contact term off; stops far away.
LINEAR = dict(
    m1=1.0, m2=2.0, C1=0.0, C2=0.0, C3=0.0, C4=0.0, C5=0.0,
    K1=4.0, K2=0.0, K3=0.0, K4=2.0, K5=0.0, K6=0.0,
    mu_k=0.1, mu_s=0.2, d=1e6, d1=1e6, Q1=0.0, Q2=0.0, Omega=1.0,
    phi1=0.0, phi2=0.0, P1=0.0, P2=0.0, g=9.8,
)  # fmt: skip


def make_case(t_end, *, initial, name="constructed", options=None, **params):
    values = {**LINEAR, **params}
    return Case(
        name=name,
        parameters=Parameters(**values),
        initial=InitialState(*initial),
        t_end=t_end,
        options=options or SolverOptions(),
    )


#: m2 (2 kg, no spring) driven at 1.5 times its static threshold at Omega = 1e8 rad/s: it leaves
#: rest, then its velocity changes sign twice per forcing period, 3.2e7 times per second.
CHATTER = dict(K1=0.0, K4=0.0, Q2=1.5 * 0.2 * 2.0 * 9.8, Omega=1e8)


def chatter_case(t_end=1.0, **options):
    return make_case(t_end, initial=(0.0, 0.0, 0.0, 0.5, 0.0), name="chatter", options=SolverOptions(**options),
                     **CHATTER)  # fmt: skip


def assert_same_tables(a, b):
    """Two sweeps' tables (``read_sweep``) are equal, but for wall times."""
    import pandas as pd

    from oscillator.analysis.sweep_points import TABLES

    for name in TABLES:
        left = a[name].drop(columns=["wall_time"], errors="ignore").reset_index(drop=True)
        right = b[name].drop(columns=["wall_time"], errors="ignore").reset_index(drop=True)
        pd.testing.assert_frame_equal(left, right)


@pytest.fixture
def build():
    return make_case


@pytest.fixture(scope="session")
def once(tmp_path_factory, worker_id):
    """``once(name, compute)``: ``compute()`` run by one of the test workers only, the others
    reading its pickled result (pytest-xdist's recipe: a module's fixture is otherwise computed by
    every worker that runs one of its tests, 12 to 18 s each for the frequency responses)."""
    import pickle

    from filelock import FileLock

    def computed(name, compute):
        if worker_id == "master":  # no workers
            return compute()
        path = tmp_path_factory.getbasetemp().parent / f"once-{name}.pickle"
        with FileLock(f"{path}.lock"):
            if path.is_file():
                return pickle.loads(path.read_bytes())
            value = compute()
            path.write_bytes(pickle.dumps(value))
            return value

    return computed


#: Mass 1 a hardening Duffing oscillator (K2 > 0, a light damper, no friction, the stops far);
#: mass 2 a linear one beside it, uncoupled.
DUFFING = dict(
    m1=1.0, K1=1.0, K2=0.05, C1=0.05, C2=0.0, K3=0.0, C3=0.0, m2=1.5, K4=1.0, K5=0.0, C4=0.2, C5=0.0, K6=1.0,
    mu_k=0.0, mu_s=0.0, P1=0.0, P2=0.0, d=1000.0, d1=1000.0, Q1=0.2, Q2=0.1, Omega=0.8, phi1=0.0, phi2=0.0,
    x1=0.0, v1=0.0, x2=0.0, v2=0.1,
)  # fmt: skip


@pytest.fixture(scope="session")
def duffing(once):
    """The Duffing example of docs/frequency.md, run as the page shows it (and checked to be the
    system of :data:`DUFFING`), by one test worker."""
    return once("duffing", _duffing)


def _duffing():
    import oscillator as osc
    from oscillator import resolve_case

    page = (Path(__file__).resolve().parents[1] / "docs" / "frequency.md").read_text(encoding="utf-8")
    block = page.split("A hardening Duffing oscillator", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    scope = {"osc": osc}
    exec(compile("\n".join(line[2:] for line in block.splitlines()), "docs/frequency.md", "exec"), scope)
    assert scope["case"] == resolve_case("instance-1", **DUFFING)
    return scope["found"]


#: The frequency response of the window where two orbits coexist (docs/frequency.md).
FRC_WINDOW = ["frc", "instance-1", "--set", "Q2=71.165", "--param", "Omega", "1.5999", "1.6001", "--starts", "16"]


@pytest.fixture(scope="session")
def small_frc(tmp_path_factory, once):
    """A small frequency response's folder (the window's, 2 seeds, 3 sweep values), computed by
    one test worker (tests that change it copy it first)."""
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    def computed():
        folder = tmp_path_factory.mktemp("small") / "frc"
        command = [*FRC_WINDOW, "--seeds", "2", "--sweep", "3", "--out", str(folder), "--no-plots"]
        assert CliRunner().invoke(app, command).exit_code == 0
        return folder

    return once("small-frc", computed)


@pytest.fixture
def work(tmp_path):
    """An empty working folder for one command (a case file can be written beside it)."""
    folder = tmp_path / "work"
    folder.mkdir()
    return folder


def random_case(seed, t_end=12.0):
    """A random valid system with stops close by, so that contacts, rest and re-sticking occur."""
    import numpy as np

    rng = np.random.default_rng(seed)
    p = dict(
        m1=rng.uniform(0.5, 2), m2=rng.uniform(0.5, 2), C1=rng.uniform(0, 0.3), C2=rng.uniform(0, 0.1),
        C3=rng.uniform(0, 1.5), C4=rng.uniform(0, 0.3), C5=rng.uniform(0, 0.1), K1=rng.uniform(0.2, 3),
        K2=rng.uniform(0, 1), K3=rng.uniform(0.5, 5), K4=rng.uniform(0.2, 3), K5=rng.uniform(0, 1),
        K6=rng.uniform(0.5, 5), mu_k=rng.uniform(0.05, 0.3),
    )  # fmt: skip
    p["mu_s"] = p["mu_k"] * rng.uniform(1, 1.8)
    p.update(
        d=rng.uniform(0.2, 2), d1=rng.uniform(0.2, 2), Q1=rng.uniform(0, 15), Q2=rng.uniform(0, 15),
        Omega=rng.uniform(0.8, 3), phi1=rng.uniform(0, 6.3), phi2=rng.uniform(0, 6.3),
        P1=rng.uniform(0, 0.5), P2=rng.uniform(0, 0.5),
    )  # fmt: skip
    x1 = rng.uniform(-1, 1)
    x2 = x1 + rng.uniform(-0.5, 2.5)
    v1 = rng.choice([0.0, rng.uniform(-2, 2)])
    v2 = rng.choice([0.0, rng.uniform(-2, 2)])
    return make_case(t_end, initial=(0.0, x1, v1, x2, v2), name=f"random-{seed}", **p)


#: Run the command with ``simulate`` wrapped so that it prints "running" (on stderr) once the
#: integration has taken its first step: a test sends its signal then, whatever the machine's
#: speed, instead of after a sleep that a loaded machine may not have finished importing in.
RUNNING = """
import sys
import oscillator.hybrid.simulate as simulation
original = simulation.simulate
def simulate(*args, progress=None, **kwargs):
    said = []
    def report(t):
        if not said:
            said.append(t)
            print("running", file=sys.stderr, flush=True)
        if progress is not None:
            progress(t)
    return original(*args, progress=report, **kwargs)
simulation.simulate = simulate
from oscillator.__main__ import main
main()
"""


def start_running(args, **options):
    """``oscillator ARGS`` in a subprocess (pipes for its streams), returned once it says it is
    integrating (see :data:`RUNNING`)."""
    import subprocess
    import sys

    process = subprocess.Popen([sys.executable, "-c", RUNNING, *map(str, args)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, **options)  # fmt: skip
    line = process.stderr.readline()
    assert line.strip() == "running", line + process.stderr.read()
    assert signals_heard(process.pid), _signal_state(process.pid)
    return process


#: Run the command with one library function wrapped: at its ``n``-th call it says "reached" (on
#: stderr) and waits there for the signal the test sends (or carries on after a minute).
REACHED = """
import sys, time, importlib
module, name = sys.argv[1].rsplit(".", 1)
target, n, calls = importlib.import_module(module), int(sys.argv[2]), []
original = getattr(target, name)
def reached(*args, **kwargs):
    calls.append(1)
    if len(calls) == n:
        print("reached", file=sys.stderr, flush=True)
        time.sleep(60)
    return original(*args, **kwargs)
setattr(target, name, reached)
sys.argv[1:] = sys.argv[3:]
from oscillator.__main__ import main
main()
"""


def start_reaching(function: str, args, *, call: int = 1, **options):
    """``oscillator ARGS`` in a subprocess, returned once it has reached the ``call``-th call of
    ``function`` (``"module.name"``, looked up in its module when called) and waits there."""
    import subprocess
    import sys

    process = subprocess.Popen([sys.executable, "-c", REACHED, function, str(call), *map(str, args)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **options)  # fmt: skip
    line = process.stderr.readline()
    assert line.strip() == "reached", line + process.stderr.read()
    assert signals_heard(process.pid), _signal_state(process.pid)
    return process


def _signal_state(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/status") as status:
            return "".join(line for line in status if line.startswith(("SigBlk", "SigIgn", "SigCgt")))
    except OSError:
        return "(no /proc)"


def signals_heard(pid: int) -> bool:
    """Whether process ``pid`` neither blocks nor ignores SIGINT (where /proc tells)."""
    import signal

    state = _signal_state(pid)
    if not state.startswith("Sig"):
        return True
    bit = 1 << (signal.SIGINT - 1)
    masks = {line.split(":")[0]: int(line.split(":")[1], 16) for line in state.splitlines()}
    return not (masks.get("SigBlk", 0) & bit or masks.get("SigIgn", 0) & bit)


def rewritten(part, change, meta=None) -> None:
    """The part with its table changed by ``change`` (and its metadata's ``meta`` replaced, if
    given), its key kept: a damage that a reader of the key alone would not see."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(part)
    kept = json.loads(table.schema.metadata[b"oscillator"])
    if meta is not None:
        kept["meta"] = meta
    frame = change(table.to_pandas())
    changed = pa.Table.from_pandas(frame, preserve_index=False)
    pq.write_table(changed.replace_schema_metadata({b"oscillator": json.dumps(kept)}), part)
