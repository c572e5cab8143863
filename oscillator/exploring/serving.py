"""Serving the explorer: on the loopback address by default, one session per browser tab, and
nothing a web page elsewhere can reach.

Bokeh's server and Panel's bring more routes than the page uses (``/autoload.js``, ``/metadata``,
Panel's ``/components/<module>/...``, which imports the module its URL names).  Every request
passes :class:`Guard` before any of them sees it:

* **routes**: only what the page loads (:data:`ROUTES`: the page, its websocket, Bokeh's and
  Panel's static files, the icon), with ``GET`` or ``HEAD``; any other path is 404, any other
  method 405, before a handler is chosen;
* **Host**: the address served on (and ``localhost`` for a loopback address; this machine's names
  and addresses for ``0.0.0.0``), with its port: a name that an attacker's DNS points at this
  machine (DNS rebinding) is refused;
* **Origin**: absent, or the page's own; **Sec-Fetch-Site**: absent, ``same-origin`` or ``none``
  (an address typed or pasted): a request that a page of another site makes (an ``<img>``, a
  link, a form, a frame, a script's fetch) is refused, even where it carries no Origin;
* **pages**: at most :data:`MAX_PAGES` open at once (each holds a session and its motion); one
  more is told to close one (503).  A page closed is let go after :data:`LINGER_MS`.

Bokeh's and Panel's scripts are served by the server itself: the page fetches nothing from the
internet.  Ctrl-C stops the server and returns.
"""

from __future__ import annotations

import gc
import ipaddress
import logging
import re
import socket
from collections.abc import Callable
from typing import Any

from tornado.httputil import HTTPServerRequest
from tornado.routing import Router
from tornado.web import RequestHandler

from oscillator.errors import InputError
from oscillator.exploring.runner import close_all

__all__ = ["LOOPBACK", "MAX_PAGES", "ROUTES", "Guard", "check_address", "is_loopback", "serve"]

LOOPBACK = "127.0.0.1"
#: The paths the page asks for: the page, its websocket, the static files (Bokeh's own under
#: ``/static/``, Panel's under ``/static/extensions/``: files from the libraries' folders only)
#: and the icon.
ROUTES = re.compile(r"/|/ws|/favicon\.ico|/static/[A-Za-z0-9_./@%^-]+")
#: The methods the page uses.
METHODS = ("GET", "HEAD")
#: ``Sec-Fetch-Site`` values of requests from the page itself or typed by the user.
OWN_SITES = ("same-origin", "none")
#: Pages (sessions) open at once.
MAX_PAGES = 16
#: How long a closed page's session is kept (ms), and how often they are looked for.
LINGER_MS = 5000
CHECK_MS = 1000
_FULL = f"{MAX_PAGES} explorer pages are open; close one and load this page again"


def is_loopback(address: str) -> bool:
    """Whether ``address`` is this machine only (``127.0.0.0/8``, ``::1``, ``localhost``)."""
    if address == "localhost":
        return True
    try:
        return ipaddress.ip_address(address).is_loopback
    except ValueError:
        return False


def check_address(address: str, port: int) -> int:
    """The port to serve on at ``address`` (a free one for ``0``); a port outside 0-65535 or in
    use, or an address this machine does not have, refused with the field and the fix."""
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise InputError(f"port must be a whole number from 1 to 65535 (0: a free one), got {port!r}", field="port")
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((address, port))
            return int(probe.getsockname()[1])
        except OSError as error:
            if error.errno in (98, 48, 10048):  # EADDRINUSE on Linux, macOS, Windows
                raise InputError(
                    f"port {port} is in use on {address}; choose another with --port", field="port"
                ) from None
            raise InputError(
                f"cannot listen on {address}:{port} ({error.strerror}); give another --address", field="address"
            ) from None
        except (socket.gaierror, UnicodeError, ValueError):
            raise InputError(
                f"{address!r} is not an address of this machine; give one such as 127.0.0.1 or ::1", field="address"
            ) from None


def hosts_of(address: str, port: int) -> tuple[str, ...]:
    """The ``Host`` values a browser sends to ``address:port`` (IPv6 in brackets), lower case:
    ``localhost`` too for a loopback address; for every address (``0.0.0.0``, ``::``), the loopback
    names and this machine's own names and addresses."""
    names = [address] + (["localhost"] if is_loopback(address) else [])
    try:
        everywhere = ipaddress.ip_address(address).is_unspecified
    except ValueError:
        everywhere = False
    if everywhere:
        names += ["localhost", "127.0.0.1", "::1", socket.gethostname(), socket.getfqdn()]
        try:
            names += [str(info[4][0]) for info in socket.getaddrinfo(socket.gethostname(), None)]
        except OSError:
            pass
    hosts = (f"[{name}]" if ":" in name else name for name in names)
    return tuple(dict.fromkeys(f"{host}:{port}".lower() for host in hosts))


class Refused(RequestHandler):
    """Every method answered with a status and one line of text, and nothing else done."""

    def initialize(self, status: int, why: str) -> None:
        self.status, self.why = status, why

    def prepare(self) -> None:
        self.set_status(self.status)
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.finish(f"{self.why}\n")


class Guard(Router):
    """Every request checked (module docstring) before ``application`` (Bokeh's tornado
    application) routes it; ``pages()`` counts the sessions open."""

    def __init__(self, application: Any, hosts: tuple[str, ...], pages: Callable[[], int]) -> None:
        self.application, self.hosts, self.pages = application, hosts, pages
        self.origins = tuple(f"http://{host}" for host in hosts)

    def refusal(self, request: HTTPServerRequest) -> tuple[int, str] | None:
        """Why ``request`` is refused, as ``(status, reason)``; None where it may pass."""
        headers = request.headers
        if str(headers.get("Host", "")).lower() not in self.hosts:
            return 403, "this explorer answers to its own address only; open the address the command printed"
        origin = headers.get("Origin")
        if origin is not None and origin.lower() not in self.origins:
            return 403, "a page of another origin cannot use this explorer"
        if headers.get("Sec-Fetch-Site", "none") not in OWN_SITES:
            return 403, "a page of another site cannot use this explorer; open the address the command printed"
        if ROUTES.fullmatch(request.path or "") is None or ".." in request.path:
            return 404, "not found"
        if request.method not in METHODS:
            return 405, "method not allowed"
        if request.path == "/" and self.pages() >= MAX_PAGES:
            return 503, _FULL
        return None

    def find_handler(self, request: HTTPServerRequest, **kwargs: Any) -> Any:
        refused = self.refusal(request)
        if refused is None:
            return self.application.find_handler(request, **kwargs)
        status, why = refused
        return self.application.get_handler_delegate(request, Refused, {"status": status, "why": why})


def _page(make: Callable[[], Any], server: Any) -> Any:
    """``make()``'s page, or one line saying that :data:`MAX_PAGES` are open (pages are made one
    at a time: the count is exact here, where the guard's misses those being made)."""
    import panel as pn

    if len(server.get_sessions("/")) >= MAX_PAGES:
        return pn.pane.HTML(f"<p class='oscillator-error'>{_FULL}</p>")
    return make()


def serve(
    make: Callable[[], Any],
    *,
    address: str = LOOPBACK,
    port: int = 5006,
    title: str = "oscillator explore",
    ready: Callable[[str], None] | None = None,
) -> None:
    """Serve a page made by ``make()`` for each session at ``http://address:port/`` until Ctrl-C,
    every request passing :class:`Guard`.

    ``ready`` is called with the page's URL once the server listens."""
    import panel as pn

    port = check_address(address, port)
    hosts = hosts_of(address, port)
    server: Any = None
    # Bokeh's own websocket check cannot read an IPv6 address (and warns of the "*" it is given
    # instead): the guard checks every Origin
    origins = ["*"] if any(host.startswith("[") for host in hosts) else list(hosts)
    quiet = logging.getLogger("bokeh.server.util")
    level = quiet.level
    quiet.setLevel(logging.ERROR)
    try:
        server = pn.serve(
            {"/": lambda: _page(make, server)},
            port=port,
            address=address,
            websocket_origin=origins,
            show=False,
            start=False,
            title=title,
            verbose=False,
            location=False,  # Panel's reading of the address fails on IPv6; the page keeps its own
            unused_session_lifetime_milliseconds=LINGER_MS,
            check_unused_sessions_milliseconds=CHECK_MS,
        )
    finally:
        quiet.setLevel(level)
    server._http.request_callback = Guard(server._tornado, hosts, lambda: len(server.get_sessions("/")))
    # a refused request is answered, not printed: a page elsewhere could fill the terminal
    logging.getLogger("tornado.access").setLevel(logging.ERROR)
    # what the process holds now (the libraries, the compiled kernels) moves out of the collector's
    # sight: a full collection scanned it all in 130-150 ms, in the middle of a change (measured)
    gc.collect()
    gc.freeze()
    server.start()
    if ready is not None:  # said from inside the loop: a Ctrl-C as soon as it is read stops the loop
        server.io_loop.add_callback(ready, f"http://{hosts[0]}/")
    try:
        server.io_loop.start()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
        close_all()  # no page's job left running in compiled code as the interpreter ends
