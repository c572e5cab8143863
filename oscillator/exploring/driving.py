"""Driving the explorer in a real browser: for its tests, its latency benchmark and the docs' screenshots.

:class:`Served` runs ``oscillator explore`` as a user does (a separate process on a free port of
127.0.0.1) and stops it with Ctrl-C; :func:`browser_page` opens a page in the system's Chromium
through Playwright (``pip install playwright``; no browser is downloaded: Debian's ``chromium``,
or the one ``$CHROMIUM`` names), and records every request the page makes to another host, which
it refuses (the page must work offline).  :func:`wait_revision` waits until the page shows the
motion of a given revision, painted, and says how long after the last key press or click (timed in
the page itself, so that the driver's own round trips do not count).  :func:`click_map` clicks a
folder's picture and waits for what the click found.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

__all__ = ["Served", "browser_page", "chromium", "click_map", "wait_revision"]

_LOCAL = ("http://127.0.0.1", "ws://127.0.0.1", "http://[::1]", "ws://[::1]", "data:", "blob:", "about:")


def chromium() -> str | None:
    """The Chromium to drive: ``$CHROMIUM``, else ``chromium`` on the path, else None."""
    given = os.environ.get("CHROMIUM")
    return given if given else shutil.which("chromium") or shutil.which("chromium-browser")


class Served:
    """``oscillator explore ARGS --port 0`` in its own process, until :meth:`stop` (Ctrl-C)."""

    def __init__(self, *args: str, cwd: Path | None = None) -> None:
        command = str(Path(sys.executable).with_name("oscillator"))
        self.process = subprocess.Popen(
            [command, "explore", *args, "--port", "0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
        )
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        if " at http://" not in line:
            self.process.kill()
            _, err = self.process.communicate()
            raise RuntimeError(f"oscillator explore did not start: {line!r} {err!r}")
        self.url = line.split(" at ", 1)[1].split(" ", 1)[0]

    def stop(self) -> tuple[int, str, str]:
        """Ctrl-C, and what the command printed after it: ``(exit code, stdout, stderr)``."""
        self.process.send_signal(signal.SIGINT)
        try:
            out, err = self.process.communicate(timeout=60)
        finally:
            self.process.kill()
        return self.process.returncode, out, err

    def __enter__(self) -> Served:
        return self

    def __exit__(self, *_: object) -> None:
        if self.process.poll() is None:
            self.stop()


@contextmanager
def browser_page(
    width: int = 1400, height: int = 1300, *, also: tuple[str, ...] = ()
) -> Iterator[tuple[Any, list[str]]]:
    """A page of headless Chromium and the list of the other hosts' addresses it asked for
    (each refused); ``also`` names more address prefixes it may reach (a test's page elsewhere)."""
    from playwright.sync_api import sync_playwright

    executable = chromium()
    if executable is None:
        raise RuntimeError("no Chromium: install Debian's chromium (apt install chromium) or set $CHROMIUM")
    elsewhere: list[str] = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": width, "height": height})

            def route(route: Any) -> None:
                if route.request.url.startswith(_LOCAL + also):
                    route.continue_()
                else:
                    elsewhere.append(route.request.url)
                    route.abort()

            page.route("**/*", route)
            page.add_init_script(_WATCH)
            yield page, elsewhere
        finally:
            browser.close()


#: In the page: ``__revision(n, checked)`` resolves once the frame is painted in which the status
#: line first shows revision ``n`` (and, with ``checked``, CVODE's verdict on it), with the time
#: since the last key press or click (``performance.now()``, ms).  The status line is found through
#: the page's shadow roots and watched for changes.
_WATCH = """
(() => {
  window.__input = performance.now();
  for (const kind of ['keydown', 'mousedown']) {
    document.addEventListener(kind, () => { window.__input = performance.now(); }, true);
  }
  const find = (root, selector) => {
    const found = root.querySelector(selector);
    if (found) return found;
    for (const element of root.querySelectorAll('*')) {
      if (element.shadowRoot) {
        const inner = find(element.shadowRoot, selector);
        if (inner) return inner;
      }
    }
    return null;
  };
  window.__find = find;
  let holder = null;  // the element whose content the status line is: found once, then read
  const shown = () => {
    if (holder === null || !holder.isConnected) {
      const span = find(document, 'span[data-revision]');
      holder = span ? span.parentNode : null;
    }
    return holder ? holder.querySelector('span[data-revision]') : null;
  };
  // waits on the status line's changes, not on every animation frame: a frame requested at each
  // vsync keeps the browser drawing, and takes the processor the server simulates on
  window.__revision = (n, checked) => new Promise(done => {
    const ok = () => {
      const span = shown();
      return span !== null && Number(span.dataset.revision) >= n && (!checked || span.dataset.checked !== undefined);
    };
    const finish = () => {
      // the frame that shows it: a task posted from its animation callback runs after its paint
      requestAnimationFrame(() => {
        const channel = new MessageChannel();
        channel.port1.onmessage = () => done(performance.now() - window.__input);
        channel.port2.postMessage(null);
      });
    };
    const watch = () => {
      if (ok()) return finish();
      if (holder === null) return setTimeout(watch, 20);  // the page is not built yet
      let timer = null;
      const seen = () => {
        if (!ok()) return;
        observer.disconnect();
        clearInterval(timer);
        finish();
      };
      const observer = new MutationObserver(seen);
      observer.observe(holder, {childList: true, subtree: true, attributes: true, characterData: true});
      timer = setInterval(seen, 100);  // should the status line be built again elsewhere
    };
    watch();
  });
})();
"""


def wait_revision(page: Any, revision: int, timeout: float = 60.0, *, checked: bool = False) -> float:
    """Wait until the page's status line shows ``revision`` (or a later one) - with ``checked``,
    CVODE's verdict on it - and the browser has painted it; the milliseconds since the last key
    press or click, measured in the page."""
    page.set_default_timeout(timeout * 1e3)
    waited = """([n, checked, ms]) => Promise.race([window.__revision(n, checked), new Promise((_, fail) =>
        setTimeout(() => fail(new Error(`revision ${n} not shown within ${ms} ms`)), ms))])"""
    return float(page.evaluate(waited, [revision, checked, timeout * 1e3]))


def click_map(page: Any, x: float, y: float, click: int = 1, timeout: float = 60.0) -> Any:
    """Click the folder's picture (the page's first canvas) at ``(x, y)``, fractions of its width
    and height from its top left corner, and wait for what click number ``click`` found: its
    ``.oscillator-picked-found`` element (Playwright's locator)."""
    box = page.locator(".bk-Canvas").first.bounding_box()
    page.mouse.click(box["x"] + x * box["width"], box["y"] + y * box["height"])
    found = page.locator(f".oscillator-picked-found[data-click='{click}']")
    found.wait_for(timeout=timeout * 1e3)
    return found
