"""The explorer in a real browser (issue 40): Debian's Chromium driven by Playwright, the page served
by ``oscillator explore`` as a user runs it.  The page loads with nothing fetched from elsewhere; a
slider's key press changes the event table to what ``simulate`` gives for the new value; a click on
an atlas cell shows the attractor ``find_attractors`` finds there, one on a frequency response's
picture the orbit its folder holds; a case file's ``<script>`` title shows as text.

Without Chromium or Playwright these tests are skipped, unless ``OSCILLATOR_REQUIRE_BROWSER`` is set
(CI sets it: there a missing browser fails the run)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import oscillator as osc
from oscillator.exploring.driving import Served, browser_page, chromium, click_map, wait_revision
from oscillator.exploring.maps import picture_of
from oscillator.io.cases import resolve_case

pytestmark = pytest.mark.slow

try:
    import playwright.sync_api  # noqa: F401

    MISSING = None if chromium() else "no Chromium (apt install chromium)"
except ImportError:
    MISSING = "no Playwright (pip install playwright)"
if MISSING and not os.environ.get("OSCILLATOR_REQUIRE_BROWSER"):
    pytest.skip(MISSING, allow_module_level=True)

COMMAND = str(Path(sys.executable).with_name("oscillator"))


def rows(page) -> list[list[str]]:
    """The event table's rows on screen (SlickGrid draws the visible ones), cells as shown."""
    page.locator(".slick-row").first.wait_for()
    return [row.locator(".slick-cell").all_inner_texts() for row in page.locator(".slick-row").all()]


def model_value(page, name: str) -> float:
    return float(page.evaluate("n => Bokeh.documents[0].get_model_by_name(n).value", name))


def test_a_slider_moves_the_event_table_to_what_simulate_gives(tmp_path):
    with Served("instance-1", cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        assert "#1: 50 periods" in page.locator("span[data-revision='1']").inner_text()
        page.locator(".control-K3 .noUi-handle").focus()
        page.keyboard.press("ArrowRight")
        wait_revision(page, 2)
        value = model_value(page, "K3")
        assert value == pytest.approx(2.0 + 0.02)  # one step of the slider (4 / 200)
        case = resolve_case("instance-1", K3=value)
        direct = osc.simulate(resolve_case(case, t_end=case.initial.t0 + 50 * case.parameters.period))
        status = page.locator("span[data-revision='2']").inner_text()
        assert f"{len(direct.events)} events" in status, status
        shown = rows(page)
        assert len(shown) >= 8
        for cells, (_, event) in zip(shown, direct.events.iterrows(), strict=False):
            t, mass, kind, *_, theorem, equation, _boundary = cells
            assert float(t) == pytest.approx(event.t, abs=1e-6) and int(mass) == event.mass, (cells, event)
            assert (kind, theorem, equation) == (event.kind, event.theorem, event.equation), cells
        page.screenshot(path=tmp_path / "explore.png", full_page=True)
        assert not elsewhere, elsewhere
    assert served.process.returncode == 0


@pytest.fixture(scope="module")
def atlas(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("explore") / "atlas"
    subprocess.run(
        [COMMAND, "atlas", "instance-1", "--x", "Omega", "1.5", "1.7", "3", "--y", "Q2", "70", "71.5", "2",
         "--transient", "30", "--record", "8", "--out", str(folder), "--no-plots", "--quiet"],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    return folder


def test_a_click_on_an_atlas_cell_shows_the_attractors_find_attractors_finds_there(atlas, tmp_path):
    with Served(str(atlas), cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        found = click_map(page, 0.45, 0.5)
        text, count = found.inner_text(), int(found.get_attribute("data-count") or 0)
        wait_revision(page, 2)  # the first attractor's motion follows
        shown = (float(v) for v in re.match(r"Omega = ([\d.]+), Q2 = ([\d.]+)", text).groups())
        omega, q2 = model_value(page, "Omega"), model_value(page, "Q2")  # the cell's, put on the sliders
        assert (omega, q2) == pytest.approx(tuple(shown), rel=1e-5)
        assert not elsewhere, elsewhere
    picture = picture_of(atlas)
    index = picture.nearest(omega, q2)
    case, starts = picture.starts_at(index)
    expected = osc.find_attractors(case, states=starts)
    assert f"{len(expected.attractors)} attractor(s)" in text, text
    for attractor in expected.attractors:
        point = ", ".join(f"{v:.6g}" for v in attractor.points[0])
        assert f"{attractor.name}: section point ({point})" in text, (text, point)
    assert count == len(expected.attractors) >= 1


def test_a_click_on_a_frequency_response_shows_the_orbit_the_folder_holds_there(small_frc, tmp_path):
    """A picture of points (no cells): a click anywhere picks the nearest branch point, whose orbit
    the folder holds: it is shown and put on the sliders."""
    points = pd.read_parquet(small_frc / "points.parquet")
    with Served(str(small_frc), "--periods", "5", cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        click_map(page, 0.5, 0.5)
        held = page.locator(".oscillator-held").inner_text()
        wait_revision(page, 2)  # the motion from the orbit follows
        shown = {name: model_value(page, name) for name in ("Omega", "x1", "v1", "x2", "v2")}
        assert not elsewhere, elsewhere
    row = points.iloc[int(np.argmin(np.abs(points.Omega - shown["Omega"])))]
    assert shown == pytest.approx({name: row[name] for name in shown}, abs=1e-12)
    assert held.startswith(f"branch {row.branch}: a stable period-{row.period} orbit through ("), held


def test_a_case_text_with_a_script_shows_as_text(tmp_path):
    import tomllib

    import tomli_w

    from oscillator.io.cases import case_to_toml

    hostile = '<script>window.__pwned = 1</script><img src=x onerror="window.__pwned = 2">'
    data = tomllib.loads(case_to_toml(resolve_case("instance-3")))
    data |= {"title": hostile, "description": f"{hostile} & more"}
    path = tmp_path / "hostile.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    with Served(str(path), cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        heading = page.locator(".oscillator-title").inner_text()
        assert hostile in heading, heading
        assert page.get_by_text(f"{hostile} & more").count() == 1
        assert page.evaluate("() => window.__pwned === undefined")
        assert not elsewhere, elsewhere  # the <img> was never fetched either
    assert np.isfinite(served.process.returncode)


HOSTILE = """<!doctype html><html><body>
<img src="{url}components/this/x/y/z"><img src="{url}components/venv.__main__/x/y/z">
<img src="{url}autoload.js?bokeh-autoload-element=x"><iframe src="{url}"></iframe>
<iframe name="sink"></iframe><form id="post" method="post" action="{url}" target="sink"></form>
<script>
window.__done = (async () => {{
  const tries = ["components/this/x/y/z", "components/venv.__main__/x/y/z", "metadata", ""];
  const said = [];
  for (const path of tries) {{
    try {{ await fetch("{url}" + path, {{mode: "no-cors"}}); said.push("sent"); }} catch (e) {{ said.push("refused"); }}
    try {{ const r = await fetch("{url}" + path); said.push("read " + r.status); }} catch (e) {{ said.push("unread"); }}
  }}
  document.getElementById("post").submit();
  said.push(await new Promise(done => {{
    const socket = new WebSocket("{url}".replace("http", "ws") + "ws");
    socket.onopen = () => done("websocket opened");
    socket.onerror = () => done("websocket refused");
  }}));
  return said;
}})();
</script></body></html>"""


@pytest.fixture
def elsewhere_page(tmp_path):
    """A web page of another site (``http://localhost:PORT``, not the explorer's 127.0.0.1), served
    from a folder of its own; yields a function that writes its ``index.html`` and its address."""
    import functools
    import http.server
    import threading

    root = tmp_path / "elsewhere"
    root.mkdir()
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(root))
    handler.log_message = lambda *args: None
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()

    def page(text: str) -> str:
        (root / "index.html").write_text(text, encoding="utf-8")
        return f"http://localhost:{server.server_address[1]}/index.html"

    yield page
    server.shutdown()
    server.server_close()


def test_a_page_of_another_site_can_make_the_explorer_import_write_or_stop_nothing(tmp_path, elsewhere_page):
    """Panel's ``/components/<module>/...`` imported the module its URL named: ``this`` printed the
    Zen of Python on the server, ``venv.__main__`` made virtual environments in its folder and stopped
    it.  From another site's page (images, frames, fetches, a form, a websocket) nothing reaches it."""
    served_in = tmp_path / "served"
    served_in.mkdir()
    with Served("instance-1", cwd=served_in) as served, browser_page(also=("http://localhost",)) as (page, _):
        page.goto(elsewhere_page(HOSTILE.format(url=served.url)))
        said = page.evaluate("() => window.__done")
        assert said.count("refused") + said.count("sent") == 4 and "websocket refused" in said, said
        assert not [s for s in said if s.startswith("read")] or all(s == "read 403" for s in said if "read" in s)
        assert served.process.poll() is None  # still serving
        page.goto(served.url)  # and its own page works
        wait_revision(page, 1)
        code, out, err = served.stop()
    assert code == 0 and out.strip().endswith("stopped"), (code, out, err)
    assert "Beautiful is better than ugly" not in out + err and "Traceback" not in err, err
    assert list(served_in.iterdir()) == []


def test_the_explorer_answers_on_ipv6_loopback(tmp_path):
    """``--address ::1``: the page is served (Bokeh's own address check could not read it) and works."""
    with Served("instance-3", "--address", "::1", cwd=tmp_path) as served, browser_page() as (page, _):
        assert served.url.startswith("http://[::1]:")
        page.goto(served.url)
        assert wait_revision(page, 1) >= 0
        assert "events" in page.locator("span[data-revision='1']").inner_text()


def test_many_requests_at_once_leave_the_explorer_answering(tmp_path):
    """200 requests for the page at once (they made 200 explorers, kept the server busy for 6
    minutes and grew it by 565 MB): at most MAX_PAGES explorers at a time, the rest told to close a
    page (a 503, or that line on the page); every request answered (within the timeout, which only
    catches a hang), and a page served again once the unused sessions are let go."""
    import concurrent.futures
    import time
    import urllib.error
    import urllib.request

    def status(url: str) -> int:
        try:
            with urllib.request.urlopen(url, timeout=120) as answer:
                return 503 if b"explorer pages are open" in answer.read() else int(answer.status)
        except urllib.error.HTTPError as error:
            return int(error.code)

    with Served("instance-1", cwd=tmp_path) as served:
        with concurrent.futures.ThreadPoolExecutor(50) as pool:
            codes = list(pool.map(status, [served.url] * 200))
        assert set(codes) == {200, 503}, codes  # some made, the rest refused: the bound held
        deadline = time.monotonic() + 120  # the unused sessions are let go after a few seconds
        while status(served.url) != 200:
            assert time.monotonic() < deadline, "the explorer never served a page again"
            time.sleep(0.5)


def status(page) -> str:
    return page.locator("span[data-revision]").inner_text()


def test_stepping_by_the_keys_shows_each_runs_events_and_returns_to_the_case(tmp_path):
    """Omega 1.60 -> 1.58 -> 1.56 -> 1.54 by the arrow keys: the event table shows 1.54's rows (it
    kept 1.58's, the runs having as many events); the page's address says Omega = 1.54, and a reload
    shows that view; three keys back reach the case's value exactly, and the address is plain again."""
    with Served("instance-1", cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        page.locator(".control-Omega .noUi-handle").focus()
        for _ in range(3):
            page.keyboard.press("ArrowLeft")
        wait_revision(page, 4)
        value = model_value(page, "Omega")
        assert value == pytest.approx(1.54, abs=1e-12)
        case = resolve_case("instance-1", Omega=value)
        direct = osc.simulate(resolve_case(case, t_end=case.initial.t0 + 50 * case.parameters.period))
        shown = [float(cells[0]) for cells in rows(page)]
        assert shown == pytest.approx(direct.events.t.iloc[: len(shown)].to_list(), abs=1e-6)
        assert page.url.endswith("/?Omega=1.54")
        page.reload()
        wait_revision(page, 1)
        assert model_value(page, "Omega") == 1.54 and f"{len(direct.events)} events" in status(page)
        page.locator(".control-Omega .noUi-handle").focus()
        for _ in range(3):
            page.keyboard.press("ArrowRight")
        wait_revision(page, 4)
        assert model_value(page, "Omega") == pytest.approx(1.6, abs=1e-12) and page.url == served.url
        assert not elsewhere, elsewhere


def test_a_burst_of_key_presses_runs_its_first_and_its_last(tmp_path):
    """30 key presses 30 ms apart ran 30 simulations (the last drawn 7.6 s later): now a burst of
    changes runs its first at once and its last once the keys rest, and the page ends on the last
    value.  The server counts the bursts as it saw them (a press that reached it after the others
    had rested QUIET s begins one: a loaded machine may deliver a burst in parts), so the verdict
    does not depend on the machine's speed: at most two runs a burst, and on a quiet machine one
    burst."""
    with Served("instance-1", cwd=tmp_path) as served, browser_page() as (page, _):
        page.goto(served.url)
        wait_revision(page, 1, checked=True)
        span = page.locator("span[data-revision]")
        runs, bursts = int(span.get_attribute("data-runs")), int(span.get_attribute("data-bursts"))
        handle = page.locator(".control-Omega .noUi-handle").element_handle()
        page.evaluate(
            """async (h) => { for (let k = 0; k < 30; k++) {
                 h.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowLeft', bubbles: true}));
                 await new Promise(r => setTimeout(r, 30)); } }""",
            handle,
        )
        wait_revision(page, 31)
        span = page.locator("span[data-revision]")
        runs, bursts = int(span.get_attribute("data-runs")) - runs, int(span.get_attribute("data-bursts")) - bursts
        assert model_value(page, "Omega") == pytest.approx(1.6 - 30 * 0.02, abs=1e-12)
        assert 1 <= bursts < 30 and runs <= 2 * bursts, (runs, bursts)
        assert "#31:" in status(page)


def test_a_value_that_costs_too_much_is_bounded_said_and_leaves_the_server_answering(tmp_path):
    """C1 = 1e6 typed: 108,304 grazings in 50 periods, a 5.9 GB message, the server deaf for 20
    minutes.  Now the run stops at the explorer's bound and says so, while another tab's request
    is answered; a refused value (K3 = 1e199) is said and never left on its slider."""
    import urllib.request

    with Served("instance-1", cwd=tmp_path) as served, browser_page() as (page, _):
        page.goto(served.url)
        wait_revision(page, 1)
        box = page.get_by_placeholder("e.g. K3=2.5")
        box.fill("C1=1e6")
        box.press("Enter")
        with urllib.request.urlopen(served.url, timeout=60) as answer:  # another tab, meanwhile
            assert answer.status == 200 and b"Bokeh" in answer.read()
        wait_revision(page, 2)
        assert page.locator(".oscillator-bounded").count() == 1
        assert "stopped after 10000 events" in status(page) and "the explorer's bound" in status(page)
        box.fill("K3=1e199")
        box.press("Enter")
        wait_revision(page, 3)
        assert "K3 = 1e+199 is beyond any physical scale" in status(page) and model_value(page, "K3") == 2.0
        page.locator(".control-K1 .noUi-handle").focus()
        page.keyboard.press("ArrowRight")
        wait_revision(page, 4)
        assert "events" in status(page) and "K3" not in status(page)  # the refused value is not in the way
        page.get_by_role("button", name="Reset to the case's values").click()
        wait_revision(page, 5)
        assert model_value(page, "C1") == 0.05 and page.url == served.url


def test_a_system_file_explored_in_the_browser_moves_with_its_named_sliders(tmp_path):
    """A friction chain's page (issue 51): a slider for ``platform.F``, whose key press shows the
    events ``chain_scene_of`` gives for the new value, in the chain's own table (element, mass,
    kind, modes, theorem); the file's title, a script, shows as text."""
    import tomllib

    import tomli_w

    from oscillator.exploring.scene import chain_scene_of
    from oscillator.io.chains import chain_from_dict

    hostile = "<script>window.__pwned = 1</script>Blade"
    data = tomllib.loads((Path(__file__).parents[1] / "docs" / "systems" / "blade-damper.toml").read_text())
    path = tmp_path / "blade.toml"
    path.write_text(tomli_w.dumps(data | {"title": hostile}), encoding="utf-8")
    chain = chain_from_dict(data)
    with Served(str(path), "--periods", "20", cwd=tmp_path) as served, browser_page() as (page, elsewhere):
        page.goto(served.url)
        wait_revision(page, 1)
        assert hostile in page.locator(".oscillator-title").inner_text()
        assert page.evaluate("() => window.__pwned === undefined")
        page.locator(".control-platform-F .noUi-handle").focus()
        page.keyboard.press("ArrowRight")
        wait_revision(page, 2)
        value = model_value(page, "platform.F")
        assert value == pytest.approx(0.3 + 0.003)  # one step of the slider (0.6 / 200)
        expected = chain_scene_of(chain.with_values({"platform.F": value}), 20).events
        status = page.locator("span[data-revision='2']").inner_text()
        assert f"20 periods, {len(expected)} events; cvode" in status, status
        shown = rows(page)
        assert len(shown) >= 8
        for cells, (_, event) in zip(shown, expected.iterrows(), strict=False):
            t, element, mass, kind, before, after, theorem, _equations = cells
            assert float(t) == pytest.approx(event.t, abs=1e-6), (cells, event)
            assert (element, mass, kind, int(before), int(after), theorem) == (
                event.element, event.mass, event.kind, event.mode_before, event.mode_after, event.theorem
            ), cells  # fmt: skip
        page.screenshot(path=tmp_path / "explore-system.png", full_page=True)
        assert not elsewhere, elsewhere
    assert served.process.returncode == 0
