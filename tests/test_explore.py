"""The explorer's computations, without a browser (issue 40): what it shows is what `simulate` and
`find_attractors` give; its controls; the server's refusals, its warning and Ctrl-C."""

from __future__ import annotations

import dataclasses
import html
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import oscillator as osc
from conftest import random_case
from oscillator.errors import InputError
from oscillator.exploring.controls import START, controls_of
from oscillator.exploring.scene import EVENT_COLUMNS, GRID, TIME_AGREEMENT, differences, scene_of
from oscillator.exploring.serving import check_address, is_loopback
from oscillator.hybrid.recording import SaveAt
from oscillator.io.cases import resolve_case, section_times

COMMAND = str(Path(sys.executable).with_name("oscillator"))


def test_a_scene_is_the_motion_simulate_gives_with_its_strobe_points_and_intervals():
    """Instance 1 (both masses rest at the start, then slide) over 10 periods with K3 moved: the
    events are simulate's, the strobe points its states at t0 + kT, the rests its rests."""
    scene = scene_of("instance-1", 10, K3=2.5)
    case = resolve_case("instance-1", K3=2.5)
    marks = section_times(case, 0, 10)
    direct = osc.simulate(resolve_case(case, t_end=float(marks[-1])), save=SaveAt(ts=marks))
    # the same run but for the grid CVODE stops at: the same events, to its tolerance (rtol 1e-10)
    assert np.allclose(scene.events.t, direct.events.t, rtol=0, atol=1e-8)
    assert scene.events[["mass", "kind", "theorem", "equation"]].equals(
        direct.events[["mass", "kind", "theorem", "equation"]]
    )
    assert np.allclose(scene.strobe[["x1", "v1", "x2", "v2"]], direct.trajectory[["x1", "v1", "x2", "v2"]], atol=1e-9)
    assert len(scene.trajectory) == 10 * GRID + 1 + len(direct.events)
    # m2 rests from t0 until its first event (it leaves rest through the flow barrier, Thm 5.4)
    first = direct.events[direct.events.mass == 2].iloc[0]
    assert scene.rests[2][0] == (pytest.approx(1.0), pytest.approx(first.t)) and first.theorem == "5.4"
    for mass in (1, 2):  # each rest ends where the mass leaves domain 0
        leaving = direct.events[(direct.events.mass == mass) & (direct.events.from_domain == 0)].t.tolist()
        assert [b for _, b in scene.rests[mass] if b < scene.t_end] == pytest.approx(leaving)
    assert scene.contacts == {"left": [], "right": []} and scene.status == "complete"


def test_a_scene_of_an_impacting_motion_has_its_contacts():
    """The impacting system (d = 1, d1 = 3.5): contact intervals where the mode says so."""
    scene = scene_of("instance-1", 5, d=1, d1=3.5, Omega=1.5)
    for side in ("left", "right"):
        assert scene.contacts[side], side
        for a, b in scene.contacts[side]:
            middle = scene.trajectory.iloc[np.argmin(np.abs(scene.trajectory.t - 0.5 * (a + b)))]
            gap = middle.x1 - middle.x2 + 1 if side == "left" else middle.x1 - 3.5
            assert (gap < 1e-6) if side == "left" else (gap > -1e-6), (side, a, b, gap)


def test_every_parameter_and_start_value_has_a_physical_control():
    """25 parameters and the start; each slider holds the case's value; masses, Omega and g stay
    above zero, springs and friction at or above it."""
    case = resolve_case("instance-3")
    controls = controls_of(case)
    assert [c.name for c in controls] == [*osc.Parameters.names(), *START]
    for control in controls:
        assert control.start <= control.value <= control.end and control.step > 0, control
        if control.name in ("m1", "m2", "Omega", "g"):
            assert control.start > 0
        elif control.name not in (*START, "phi1", "phi2", "d", "d1"):
            assert control.start >= 0
        # the steps count from the case's value: the arrow keys reach it again (they counted from
        # the lower end: g went 9.8 -> 9.88 -> 9.78)
        for end in (control.start, control.end):
            steps = (control.value - end) / control.step
            assert abs(steps - round(steps)) < 1e-6, (control, steps)
        assert control.title == (f"{control.name} ({control.unit})" if control.unit else control.name)
    assert {c.group for c in controls} == {"Forcing", "Mass m1", "Mass m2", "Stops", "Friction", "Start"}
    assert next(c for c in controls if c.name == "K1").title == "K1 (N/m)"


def test_bad_input_is_refused_naming_the_field():
    with pytest.raises(InputError, match="periods must be a whole number"):
        scene_of("instance-1", 0)
    with pytest.raises(InputError) as refused:
        osc.explore("instance-1", mu_s=0.01)
    assert refused.value.field == "mu_s"
    with socket.create_server(("127.0.0.1", 0)) as busy:
        port = busy.getsockname()[1]
        with pytest.raises(InputError, match=f"port {port} is in use on 127.0.0.1; choose another with --port"):
            check_address("127.0.0.1", port)
    with pytest.raises(InputError, match="port must be"):
        check_address("127.0.0.1", 70000)
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.7")


def test_an_explorer_redraws_on_a_change_and_keeps_the_last_motion_on_an_impossible_one():
    """The object a notebook displays: a slider let go runs the case on screen; a value typed in
    the box too; mu_s below mu_k is said in the status line, escaped, and the motion stays."""

    def let_go(name: str, value: float) -> None:  # what the page sends when a drag ends
        slider = explorer.widgets[name]
        slider.value = value
        slider.trigger("value_throttled", None, value)

    explorer = osc.explore("instance-3", periods=5)
    assert explorer.scene is not None and explorer.revision == 1 and "5 periods" in explorer.status.object
    let_go("Omega", 2.0)
    assert explorer.revision == 2 and explorer.scene.case.parameters.Omega == 2.0
    drawn, reference = scene_of("instance-3", 5, engine="dop853", Omega=2.0), scene_of("instance-3", 5, Omega=2.0)
    assert explorer.scene.engine == "dop853"  # drawn with the compiled engine, then checked (at once here)
    assert np.allclose(explorer.scene.events.t, drawn.events.t, rtol=0, atol=1e-12)
    assert np.abs(explorer.scene.events.t - reference.events.t).max() < TIME_AGREEMENT
    assert "CVODE agrees, event by event" in explorer.status.object and "data-checked" in explorer.status.object
    explorer.set_box.value = "K3=12.5"  # beyond the slider's end: the slider widens
    assert explorer.widgets["K3"].value == explorer.widgets["K3"].end == 12.5
    assert explorer.scene.case.parameters.K3 == 12.5 and explorer.revision == 3
    let_go("mu_s", 0.0)
    assert "mu_s must be &gt;= mu_k" in explorer.status.object and explorer.scene.case.parameters.Omega == 2.0
    explorer.set_box.value = "nothing=1"
    assert "'nothing' is not a parameter or start value" in html.unescape(explorer.status.object)
    bundle = explorer._repr_mimebundle_()
    assert "application/vnd.holoviews_exec.v0+json" in bundle[0], list(bundle[0])


def _same_scene(fast, slow) -> None:
    """Two scenes of one motion: the same events (times to 1e-9 s), trajectory, strobe points,
    rests, contacts and ending."""
    assert len(fast.events) == len(slow.events)
    columns = list(EVENT_COLUMNS[1:])
    assert (fast.events[columns].astype(str).to_numpy() == slow.events[columns].astype(str).to_numpy()).all()
    np.testing.assert_allclose(fast.events.t, slow.events.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.trajectory.to_numpy(), slow.trajectory.to_numpy(), rtol=0, atol=1e-8)
    np.testing.assert_allclose(fast.strobe.to_numpy(), slow.strobe.to_numpy(), rtol=0, atol=1e-8)
    assert (fast.rests, fast.contacts, fast.status) == (slow.rests, slow.contacts, slow.status)


def _python_supervisor(case, periods):
    """The scene with the compiled run refused: simulate's supervisor, in Python, with DOP853."""
    import oscillator.exploring.scene as scene

    compiled = scene._compiled_run
    scene._compiled_run = lambda case, grid: None
    try:
        return scene_of(case, periods, engine="dop853")
    finally:
        scene._compiled_run = compiled


@pytest.mark.parametrize(
    "case",
    [*(f"instance-{k}" for k in range(1, 6)), "impacts", *(f"random-{seed}" for seed in range(24))],
)
def test_the_compiled_run_draws_what_simulates_supervisor_draws(case):
    """The explorer's DOP853 scenes come from the supervisor compiled whole
    (hybrid.batch.run_compiled): event for event what simulate's supervisor gives with the same
    engine, on the instances (rest at the start, leaving it at t0), the impacting system and
    random systems with stops close by (contacts, rest, re-sticking); every one of them runs
    compiled (none falls back)."""
    import oscillator.exploring.scene as scene

    if case == "impacts":
        case = resolve_case("instance-1", d=1, d1=3.5, Omega=1.5)
    elif case.startswith("random"):
        case = random_case(int(case.split("-")[1]))
    marks = section_times(resolve_case(case), 0, 20)
    grid = np.linspace(marks[0], marks[-1], 20 * GRID + 1)
    assert scene._compiled_run(resolve_case(case, t_end=float(marks[-1])), grid) is not None
    _same_scene(scene_of(case, 20, engine="dop853"), _python_supervisor(case, 20))


def test_a_run_outgrowing_the_compiled_buffers_goes_through_simulate(monkeypatch):
    import oscillator.exploring.scene as scene

    expected = _python_supervisor("instance-3", 10)
    monkeypatch.setattr(scene, "EVENT_ROWS", 0)  # room for no event: the compiled run gives up
    calls = []
    simulated = scene._simulated_run
    monkeypatch.setattr(scene, "_simulated_run", lambda *args: calls.append(args) or simulated(*args))
    _same_scene(scene_of("instance-3", 10, engine="dop853"), expected)
    assert len(calls) == 1


def test_differences_are_told_event_by_event_to_the_tables_precision():
    scene = scene_of("instance-3", 5, Omega=2.0)
    assert differences(scene, scene)[0] is None and differences(scene, scene)[1] == 0.0
    events = scene.events.copy()
    events.loc[7, "t"] += 2 * TIME_AGREEMENT  # a time beyond the table's precision
    later = dataclasses.replace(scene, events=events)
    said, largest = differences(later, scene)
    assert said is not None and said.startswith("event 8 differs") and largest == pytest.approx(2e-6, rel=1e-6)
    events = scene.events.copy()
    events.loc[3, "theorem"] = "5.9"  # another rule at the same time
    assert differences(dataclasses.replace(scene, events=events), scene)[0].startswith("event 4 differs")
    fewer = dataclasses.replace(scene, events=scene.events.iloc[:-2])
    assert differences(fewer, scene)[0] == f"{len(scene.events) - 2} events against {len(scene.events)}"
    stopped = dataclasses.replace(scene, status="failed")
    assert differences(stopped, scene)[0] == "the run ended 'failed' against 'complete'"


def test_cvodes_motion_replaces_one_that_differs_and_the_reference_is_not_checked(monkeypatch):
    import oscillator.exploring.app as app

    monkeypatch.setattr(app, "differences", lambda shown, reference: ("event 3 differs (made up)", 1.0))
    explorer = osc.explore("instance-3", periods=3)
    assert explorer.scene.engine == "cvode" and "oscillator-differs" in explorer.status.object
    assert "drawn instead of dop853's: event 3 differs (made up)" in explorer.status.object
    reference = osc.explore("instance-3", periods=3, engine="cvode")
    assert reference.scene.engine == "cvode" and "CVODE" not in reference.status.object
    with pytest.raises(InputError, match=r"engine must be one of cvode, .*, got 'euler'"):
        osc.explore("instance-3", engine="euler")


def test_the_case_file_saved_is_the_case_on_screen():
    from oscillator.io.cases import load_case

    explorer = osc.explore("instance-3", periods=2)
    explorer._put({"K3": 1.75})
    text = explorer._case_file().getvalue()
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"explored-{os.getpid()}.toml"
    try:
        path.write_text(text, encoding="utf-8")
        assert load_case(path).parameters == resolve_case("instance-3", K3=1.75).parameters
    finally:
        path.unlink(missing_ok=True)
    names = [download.filename for download in explorer.downloads]
    assert names == ["instance-3-explored.toml", "instance-3-events.csv", "instance-3-trajectory.csv"]
    import pandas as pd

    events = pd.read_csv(explorer._events_file())
    assert len(events) == len(explorer.scene.events) and np.allclose(events.t, explorer.scene.events.t)
    trajectory = pd.read_csv(explorer._trajectory_file())
    assert np.allclose(trajectory[["t", "x1", "v2"]], explorer.scene.trajectory[["t", "x1", "v2"]])


def _command(*args: str, **options) -> subprocess.CompletedProcess:
    return subprocess.run([COMMAND, "explore", *args], capture_output=True, text=True, timeout=120, **options)


@pytest.mark.slow
def test_the_command_refuses_a_port_in_use_and_a_folder_it_cannot_read(tmp_path):
    with socket.create_server(("127.0.0.1", 0)) as busy:
        port = busy.getsockname()[1]
        done = _command("instance-3", "--port", str(port), cwd=tmp_path)
    assert (
        done.returncode == 2
        and done.stderr.strip() == f"error: port {port} is in use on 127.0.0.1; choose another with --port"
    )
    damaged = tmp_path / "atlas"
    damaged.mkdir()
    (damaged / "atlas.json").write_text("{not json", encoding="utf-8")
    done = _command(str(damaged), "--port", "0", cwd=tmp_path)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "atlas holds no finished atlas" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and sorted(p.name for p in tmp_path.iterdir()) == ["atlas"]


@pytest.mark.slow
def test_the_command_serves_until_ctrl_c_and_warns_on_another_address(tmp_path):
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = subprocess.Popen(
        [COMMAND, "explore", "instance-3", "--port", str(port), "--address", "0.0.0.0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
    )
    try:
        line = server.stdout.readline()
        assert line.strip() == f"explorer of instance-3 at http://0.0.0.0:{port}/ (Ctrl-C stops it)", line
        server.send_signal(signal.SIGINT)  # at once: the address is said from the serving loop
        out, err = server.communicate(timeout=30)
    finally:
        server.kill()
    assert server.returncode == 0 and out.strip() == "stopped", (server.returncode, out, err)
    assert err.startswith("warning: serving on 0.0.0.0: anyone who can reach this machine") and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_notebook_displays_the_explorer(tmp_path):
    """In a Jupyter kernel, the explorer as a cell's value displays as Panel's interactive output
    (its model and the comms that carry a slider's change to the kernel)."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell('import oscillator as osc\nosc.explore("instance-3", periods=5)')]
    nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()  # fmt: skip
    outputs = notebook.cells[0].outputs
    assert not [out for out in outputs if out.output_type == "error"], outputs
    kinds = {kind for out in outputs for kind in out.get("data", {})}
    assert "application/vnd.holoviews_exec.v0+json" in kinds and "text/html" in kinds, kinds


def test_the_python_example_of_the_page_runs():
    """docs/explore.md's Python block: the explorer of instance-3 at Omega = 2.2, its events."""
    page = (Path(__file__).parents[1] / "docs" / "explore.md").read_text(encoding="utf-8")
    code = page.split("```python\n", 1)[1].split("```", 1)[0]
    space: dict = {}
    exec(compile(code, "docs/explore.md", "exec"), space)
    explorer = space["explorer"]
    assert explorer.scene.periods == 20 and explorer.scene.case.parameters.Omega == 2.2
    assert len(explorer.scene.events) > 0


def _request(path: str = "/", method: str = "GET", **headers: str):
    from tornado.httputil import HTTPHeaders, HTTPServerRequest, RequestStartLine

    fields = {"Host": "127.0.0.1:5006"} | {name.replace("_", "-"): value for name, value in headers.items()}
    return HTTPServerRequest(start_line=RequestStartLine(method, path, "HTTP/1.1"), headers=HTTPHeaders(fields))


@pytest.mark.parametrize(
    ("request_", "status"),
    [
        (_request("/"), None),
        (_request("/ws", Origin="http://127.0.0.1:5006", Sec_Fetch_Site="same-origin"), None),
        (_request("/static/js/bokeh.min.js?v=1", Sec_Fetch_Site="same-origin"), None),
        (_request("/static/extensions/panel/panel.min.js"), None),
        (_request("/", Host="localhost:5006", Sec_Fetch_Site="none"), None),
        # Panel's route that imports the module its URL names, and Bokeh's that the page never asks for
        (_request("/components/this/x/y/z"), 404),
        (_request("/components/venv.__main__/x/y/z"), 404),
        (_request("/autoload.js"), 404),
        (_request("/metadata"), 404),
        (_request("/static/../../etc/passwd"), 404),
        (_request("/", method="POST"), 405),
        # DNS rebinding: a name of the attacker's, pointed at this machine
        (_request("/", Host="evil.example:5006"), 403),
        (_request("/", Host="127.0.0.1:5007"), 403),
        (_request("/ws", Origin="http://evil.example"), 403),
        (_request("/ws", Origin="null"), 403),
        # an <img>, a link or a frame on another site: no Origin, but the browser says where it came from
        (_request("/static/js/bokeh.min.js", Sec_Fetch_Site="cross-site"), 403),
        (_request("/", Sec_Fetch_Site="same-site"), 403),
    ],
)
def test_the_server_passes_only_its_own_pages_requests(request_, status):
    from oscillator.exploring.serving import Guard, hosts_of

    guard = Guard(None, hosts_of("127.0.0.1", 5006), lambda: 0)
    refused = guard.refusal(request_)
    assert (refused and refused[0]) == status, refused


def test_the_server_bounds_the_pages_open_at_once():
    from oscillator.exploring.serving import MAX_PAGES, Guard, hosts_of

    hosts = hosts_of("127.0.0.1", 5006)
    assert Guard(None, hosts, lambda: MAX_PAGES - 1).refusal(_request("/")) is None
    full = Guard(None, hosts, lambda: MAX_PAGES)
    assert full.refusal(_request("/"))[0] == 503
    assert full.refusal(_request("/ws", Origin="http://127.0.0.1:5006")) is None  # an open page keeps working


def test_the_hosts_a_browser_may_name():
    from oscillator.exploring.serving import hosts_of

    assert hosts_of("127.0.0.1", 80) == ("127.0.0.1:80", "localhost:80")
    assert hosts_of("::1", 80) == ("[::1]:80", "localhost:80")
    everywhere = hosts_of("0.0.0.0", 80)
    assert {"0.0.0.0:80", "127.0.0.1:80", "localhost:80", "[::1]:80"} <= set(everywhere)
    assert "evil.example:80" not in everywhere


def test_the_page_says_what_changed_keeps_it_in_its_address_and_resets():
    """The title stays the case's, a line below it says what the page changed; the address holds
    the changed values only (numbers), the reset gives the case's values back; a case changed by
    overrides does not show the description of the one it came from."""
    explorer = osc.explore("instance-1", periods=5)
    assert "changed here" not in explorer.heading.object and explorer._address() == ""
    explorer._put({"Omega": 1.54, "x1": 2.5})
    explorer.periods_box.value = 6
    assert explorer._address() == "?Omega=1.54&x1=2.5&periods=6"
    explorer.update()
    assert "changed here: Omega 1.6 → 1.54, x1 3 → 2.5" in explorer.heading.object
    assert explorer.url.data["query"] == ["?Omega=1.54&x1=2.5&periods=6"] and explorer.scene.periods == 6
    explorer._reset()
    assert explorer.values()["Omega"] == 1.6 and explorer._address() == "" and explorer.scene.periods == 5
    assert "Both masses start at rest" in explorer.description.text  # the case's own description
    assert osc.explore(resolve_case("instance-1", K3=2.5), periods=2).description.text == ""


def test_the_orbit_pane_shows_the_orbits_multipliers_and_measures_with_its_impact_power():
    """The "Orbit and multipliers" button on the impacting system of docs/noise.md: the orbit Newton
    finds from the motion's end, its multipliers, and its measures (the impact power between the
    masses among them) as the library gives them."""
    explorer = osc.explore("instance-1", periods=30, d=1, d1=3.5, Omega=1.6)
    explorer._orbit()
    shown = html.unescape(explorer.orbit_text.object)
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6, transient=30)
    measures = orbit.response().columns()
    assert "Period-1 orbit" in shown and f"{abs(orbit.multipliers[0]):.6g}" in shown
    for name in ("impact_max_right", "impact_max_left", "impact_power_left"):
        assert f"{name} = {measures[name]:.6g}" in shown, name
