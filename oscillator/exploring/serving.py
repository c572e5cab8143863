"""Serving the explorer: on the loopback address by default, one session per browser tab.

The port is checked before the server starts (a port in use is refused with one line), the page's
websocket accepts only the page's own origin (another site open in the same browser cannot drive
it), and Bokeh's and Panel's scripts are served by the server itself: the page fetches nothing
from the internet.  Ctrl-C stops the server and returns.
"""

from __future__ import annotations

import gc
import ipaddress
import socket
from collections.abc import Callable
from typing import Any

from oscillator.errors import InputError

__all__ = ["LOOPBACK", "check_address", "is_loopback", "serve"]

LOOPBACK = "127.0.0.1"


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


def serve(
    make: Callable[[], Any],
    *,
    address: str = LOOPBACK,
    port: int = 5006,
    title: str = "oscillator explore",
    ready: Callable[[str], None] | None = None,
) -> None:
    """Serve a page made by ``make()`` for each session at ``http://address:port/`` until Ctrl-C.

    ``ready`` is called with the page's URL once the server listens."""
    import panel as pn

    port = check_address(address, port)
    host = f"[{address}]" if ":" in address else address
    origins = [f"{host}:{port}"] + ([f"localhost:{port}"] if is_loopback(address) else [])
    server = pn.serve(
        {"/": make},
        port=port,
        address=address,
        websocket_origin=origins,
        show=False,
        start=False,
        title=title,
        verbose=False,
    )
    # what the process holds now (the libraries, the compiled kernels) moves out of the collector's
    # sight: a full collection scanned it all in 130-150 ms, in the middle of a change (measured)
    gc.collect()
    gc.freeze()
    server.start()
    if ready is not None:  # said from inside the loop: a Ctrl-C as soon as it is read stops the loop
        server.io_loop.add_callback(ready, f"http://{host}:{port}/")
    try:
        server.io_loop.start()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
