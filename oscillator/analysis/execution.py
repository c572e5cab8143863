"""Running many independent computations: in this process, on a local process pool, or on Dask.

Sweeps (:mod:`oscillator.analysis.sweeps`) and the global analyses (:mod:`oscillator.attractors`)
each run a pure, top-level function on many tasks; an :class:`Executor`, made once at an
analysis's entry and passed down, runs them (:func:`run_tasks` for one batch) and yields the
results as they finish, whatever runs them:

* ``workers == 1`` (or a single task): one after another, in this process;
* a local pool of processes forked from multiprocessing's fork server (spawned without one), at
  most ``4 workers`` tasks in flight so that memory stays flat; the workers ignore Ctrl-C and exit
  if this process dies (:mod:`oscillator.io.signals`), and on an interrupt or an error here they
  are stopped at once, so nothing outlives the caller;
* a Dask client: the ``shared`` arguments scattered once to every worker, one future a task.

The function is called as ``function(*shared, *task, **keywords)``.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import numbers
import os
import sys
import time
import urllib.parse
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

from oscillator.errors import InputError, OscillatorError
from oscillator.io.signals import interrupts_ignored, prepare_worker, quiet_resource_tracker
from oscillator.text import shown

__all__ = [
    "MAX_WORKERS_PER_CORE",
    "Executor",
    "Pool",
    "before_workers",
    "check_progress",
    "check_runner",
    "check_workers",
    "connect",
    "keyed",
    "run_tasks",
]

T = TypeVar("T")

#: The most local worker processes per core: more only share the cores.
MAX_WORKERS_PER_CORE = 4
#: The exit status of a worker that was asked, while it imported the caller's script, to start
#: workers of its own: the script runs its work at import, with no ``__main__`` guard.
_UNGUARDED_SCRIPT = 86
_UNGUARDED_MESSAGE = (
    "workers: the worker processes stopped as they started, because the script runs its work when it is "
    "imported: each worker imports the script again (as multiprocessing starts them). Put the code that "
    'runs with workers > 1 under `if __name__ == "__main__":`, or run with workers=1'
)


#: Below this many starts a many-start computation whose workers are not given runs in this
#: process: starting the pool costs as much as it gains, or more (``benchmarks/pool.py``, the
#: documented basins on 2 cores, 2026-11-28: 100 starts 2.91 s on one worker and 4.09 s on two;
#: 900 starts 5.98 s and 5.89 s; 2,025 starts 10.80 s and 8.62 s).
SERIAL_BELOW = 1000


def check_workers(workers: object, starts: int | None = None) -> int:
    """``workers`` checked (a whole number from 1 to 4 per core), or for None every core (one
    where ``starts`` is given and below :data:`SERIAL_BELOW`)."""
    most = MAX_WORKERS_PER_CORE * (os.cpu_count() or 1)
    if workers is None:
        return 1 if starts is not None and starts < SERIAL_BELOW else os.cpu_count() or 1
    if not isinstance(workers, numbers.Integral) or isinstance(workers, bool) or not 1 <= int(workers) <= most:
        raise InputError(
            f"workers must be a whole number from 1 to {most} ({MAX_WORKERS_PER_CORE} per core), got {shown(workers)}",
            field="workers",
        )
    return int(workers)


def check_runner(workers: object, client: object = None, progress: object = None) -> int:
    """The options of a many-start computation checked at its entry, before any work:
    ``workers`` (:func:`check_workers`), ``client`` (a ``dask.distributed.Client`` or None) and
    ``progress`` (a callable or None).  Returns the number of workers."""
    if client is not None and not callable(getattr(client, "submit", None)):
        hint = " (for an address, connect first: oscillator.analysis.execution.connect(address))"
        raise InputError(
            f"client must be a dask.distributed.Client or None, got {shown(client)}"
            + (hint if isinstance(client, str) else ""),
            field="client",
        )
    check_progress(progress)
    return check_workers(workers)


def check_progress(progress: object) -> None:
    """Refuse a ``progress`` that is neither None nor a function ``progress(done, total)``."""
    if progress is not None and not callable(progress):
        raise InputError(
            f"progress must be a function progress(done, total) or None, got {shown(progress)}", field="progress"
        )


def keyed(key: Any, function: Callable[..., T], *arguments: Any) -> tuple[Any, T]:
    """``(key, function(*arguments))``: a task whose result comes back with its key, so that
    results yielded as they finish can be put in order (``executor.map(keyed, [(k, f, ...)])``)."""
    return key, function(*arguments)


class Executor:
    """Where an analysis's tasks run, made once and passed down: this process (``workers == 1``),
    a local :class:`Pool` started on entering the block and used for every batch, or a Dask
    ``client``.  Checked as :func:`check_runner` checks them.

    >>> with Executor(workers=1) as executor:
    ...     list(executor.map(pow, [(2, 3), (3, 2)]))
    [8, 9]
    """

    def __init__(self, workers: object = 1, client: object = None, progress: object = None) -> None:
        self.workers = check_runner(workers, client, progress)
        self.client = client
        self._stack = contextlib.ExitStack()
        self._pool: Pool | None = None

    def __enter__(self) -> Executor:
        if self.client is None and self.workers > 1:
            self._pool = self._stack.enter_context(Pool(self.workers))
        return self

    def __exit__(self, *exc: Any) -> None:
        self._pool = None
        self._stack.__exit__(*exc)

    def map(
        self,
        function: Callable[..., T],
        tasks: Iterable[tuple[Any, ...]],
        shared: tuple[Any, ...] = (),
        keywords: dict[str, Any] | None = None,
    ) -> Iterator[T]:
        """``function(*shared, *task, **keywords)`` for every task, yielded as each finishes (in
        the tasks' order when run in this process)."""
        return run_tasks(
            function, tasks, shared=shared, keywords=keywords, workers=self.workers, client=self.client, pool=self._pool
        )

    def ahead(
        self, function: Callable[..., T], tasks: Iterable[tuple[Any, ...]], shared: tuple[Any, ...] = ()
    ) -> Iterator[T]:
        """:meth:`map`, with every task sent to a local pool at the call (not as the results are
        taken): work for the workers while this process does something else first.  In this
        process, or on Dask, the same as :meth:`map`."""
        if self._pool is None or self.client is not None:
            return self.map(function, tasks, shared)
        return self._pool.run(function, list(tasks), shared, {}, at_once=True)


def run_tasks(
    function: Callable[..., T],
    tasks: Iterable[tuple[Any, ...]],
    *,
    shared: tuple[Any, ...] = (),
    keywords: dict[str, Any] | None = None,
    workers: int = 1,
    client: Any = None,
    pool: Pool | None = None,
) -> Iterator[T]:
    """``function(*shared, *task, **keywords)`` for every task, yielded as each finishes (in the
    tasks' order when run in this process).  ``pool``: an open :class:`Pool` to run them on (kept
    open afterwards, for the next batch), instead of one started for these tasks."""
    tasks = list(tasks)
    keywords = keywords or {}
    if client is not None:
        return _on_dask(client, function, tasks, shared, keywords)
    if pool is not None:
        return pool.run(function, tasks, shared, keywords)
    if workers <= 1 or len(tasks) <= 1:
        return (function(*shared, *task, **keywords) for task in tasks)
    return _once(function, tasks, shared, keywords, min(workers, len(tasks)))


def _once(
    function: Callable[..., T],
    tasks: list[tuple[Any, ...]],
    shared: tuple[Any, ...],
    keywords: dict[str, Any],
    workers: int,
) -> Iterator[T]:
    with Pool(workers) as pool:
        yield from pool.run(function, tasks, shared, keywords)


#: What must be ready in this process before local workers start: kernels each worker would
#: otherwise compile at once (both workers of a fresh install compiled the landing's: basins 10 x 10
#: took 25 s cold against 3.3 s warm, 1.24 GB between them).  Registered by the modules whose tasks
#: need them (:func:`before_workers`); each run once a process.
_PREPARE: list[Callable[[], None]] = []
_PREPARED: set[Callable[[], None]] = set()


def before_workers(prepare: Callable[[], None]) -> Callable[[], None]:
    """Register ``prepare()`` to run in this process, once, before local workers are started (a
    decorator): compiling into numba's cache here, the workers load what it compiled."""
    _PREPARE.append(prepare)
    return prepare


def _prepared() -> None:
    for prepare in _PREPARE:
        if prepare not in _PREPARED:
            prepare()
            _PREPARED.add(prepare)


#: How local workers start: forked from multiprocessing's fork server, a process started afresh
#: (not forked from this one, whose threads a fork would copy half-way) that imports the first
#: pool's task module once; each worker then starts with the package loaded, where a spawned one
#: imported it again (seconds of CPU a worker, for every pool).  Spawned where there is no fork
#: server (Windows).
START_METHOD = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


def _preload(function: Callable[..., Any]) -> None:
    """The fork server, when the first pool starts it, imports ``function``'s module (a later
    pool's workers import what else they need themselves)."""
    module = getattr(function, "__module__", None)
    if START_METHOD == "forkserver" and module and module != "__main__":
        multiprocessing.get_context("forkserver").set_forkserver_preload([module])


class Pool:
    """A local pool of worker processes (:data:`START_METHOD`), for several batches of tasks in turn.

    The workers ignore Ctrl-C and exit if this process dies (:mod:`oscillator.io.signals`); when
    the block is left by an interrupt or an error they are stopped at once, so nothing outlives
    the caller."""

    def __init__(self, workers: int) -> None:
        if getattr(multiprocessing.current_process(), "_inheriting", False):
            # This is a worker importing a script that has no `if __name__ == "__main__":` guard:
            # end it quietly, and let the parent say why (multiprocessing would raise here).  Its
            # status must reach the parent: a fork server's child exits 1 on a SystemExit.
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(_UNGUARDED_SCRIPT)
        self.workers = workers
        _prepared()  # the kernels compiled here once, before the workers start and load them
        quiet_resource_tracker()
        with interrupts_ignored():  # the workers are born ignoring SIGINT: the parent alone handles it
            self._executor = cf.ProcessPoolExecutor(
                max_workers=workers,
                mp_context=multiprocessing.get_context(START_METHOD),
                initializer=prepare_worker,
                initargs=(os.getpid(), dict(os.environ)),
            )

    def __enter__(self) -> Pool:
        return self

    def __exit__(self, kind: object, *_: object) -> None:
        if kind is None:
            self._executor.shutdown()
            return
        for process in list(getattr(self._executor, "_processes", {}).values()):  # no public way to stop busy ones
            process.terminate()
        self._executor.shutdown(wait=True, cancel_futures=True)  # quick now; frees the pool's semaphores

    def run(
        self,
        function: Callable[..., T],
        tasks: list[tuple[Any, ...]],
        shared: tuple[Any, ...],
        keywords: dict[str, Any],
        at_once: bool = False,
    ) -> Iterator[T]:
        """The tasks' results as they finish; at most ``4 workers`` chunks in flight, so that
        memory stays flat, or all of them (``at_once``: work sent ahead, for the workers to run
        while the caller does other work).  The tasks go in chunks of :func:`chunk_size` (the
        shared arguments are sent once a chunk, not once a task).  The first chunks are sent at
        the call, the rest as the results are taken."""
        _preload(function)
        size = chunk_size(len(tasks), self.workers)
        chunks = [(function, shared, keywords, tasks[k : k + size]) for k in range(0, len(tasks), size)]
        limit = len(chunks) if at_once else 4 * self.workers
        pending, running = iter(chunks), set[cf.Future[list[T]]]()
        self._fill(pending, running, limit)
        return self._results(pending, running, limit)

    def _fill(self, pending: Iterator[tuple[Any, ...]], running: set[cf.Future[list[T]]], limit: int) -> None:
        for chunk in pending:
            # A submit may spawn a worker, which must be born ignoring SIGINT; once all are
            # running, a Ctrl-C during a submit is the parent's, as anywhere else.
            spawning = len(getattr(self._executor, "_processes", None) or {}) < self.workers
            with interrupts_ignored() if spawning else contextlib.nullcontext():
                running.add(self._executor.submit(_run_chunk, *chunk))
            if len(running) >= limit:
                return

    def _results(self, pending: Iterator[tuple[Any, ...]], running: set[cf.Future[list[T]]], limit: int) -> Iterator[T]:
        while running:
            finished, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            for future in finished:
                running.discard(future)
                try:
                    results = future.result()
                except BrokenProcessPool as exc:
                    error = self._broken()
                    raise error from (None if isinstance(error, InputError) else exc)
                yield from results
            self._fill(pending, running, limit)

    def _broken(self) -> Exception:
        """Why the pool broke: a script without a ``__main__`` guard (said so, with the fix), or
        a worker that died (killed, out of memory)."""
        processes = list(getattr(self._executor, "_processes", {}).values())
        for process in processes:  # the broken pool is stopping them all: their status comes at once
            process.join(timeout=10)
        codes = [process.exitcode for process in processes]
        if _UNGUARDED_SCRIPT in codes:
            return InputError(_UNGUARDED_MESSAGE, field="workers")
        return OscillatorError(
            "a worker process died (killed, or out of memory); run again (a resumable computation goes on where "
            "it stopped), with fewer workers if memory is short",
            field="workers",
        )


#: The most tasks a chunk of :meth:`Pool.run` holds (a killed run loses at most a chunk in flight
#: per worker, and progress is told a chunk at a time).
MAX_CHUNK = 8


def chunk_size(tasks: int, workers: int) -> int:
    """Tasks a chunk: at least 8 chunks a worker where there are tasks enough (the last ones
    balance the workers' load), at most :data:`MAX_CHUNK`."""
    return max(1, min(MAX_CHUNK, tasks // (8 * max(1, workers))))


def _run_chunk(
    function: Callable[..., T], shared: tuple[Any, ...], keywords: dict[str, Any], chunk: list[tuple[Any, ...]]
) -> list[T]:
    """A chunk's tasks, in a worker, in order."""
    return [function(*shared, *task, **keywords) for task in chunk]


def _on_dask(
    client: Any,
    function: Callable[..., T],
    tasks: list[tuple[Any, ...]],
    shared: tuple[Any, ...],
    keywords: dict[str, Any],
) -> Iterator[T]:
    from distributed import as_completed

    # hash=False: a key of this call's own.  With Dask's default (a key from the data's hash), the
    # next batch's identical data (an atlas's next row) would share the key of this batch's, which
    # is released when this batch ends, and its tasks are cancelled for "lost dependencies".
    on_cluster = [client.scatter(item, broadcast=True, hash=False) for item in shared]
    futures = [client.submit(function, *on_cluster, *task, pure=False, **keywords) for task in tasks]
    try:
        for future in as_completed(futures):
            yield future.result()
            future.release()
    finally:
        client.cancel(futures)


def _scheduler_address(scheduler: str) -> str:
    """Refuse an address that is not ``tcp://HOST:PORT`` (or tls://, ucx://, inproc://)."""
    try:
        parsed = urllib.parse.urlsplit(scheduler)
        port = parsed.port
    except ValueError:  # "tcp://[::1": an unclosed IPv6 bracket; a port that is no number
        parsed, port = urllib.parse.urlsplit(""), None
    if (
        parsed.scheme not in ("tcp", "tls", "ucx", "inproc")
        or not parsed.hostname
        or (parsed.scheme != "inproc" and port is None)
    ):
        raise InputError(
            f"scheduler {shown(scheduler)} is not the address of a Dask scheduler; give tcp://HOST:PORT",
            field="scheduler",
        )
    return scheduler


#: Seconds a scheduler has to greet a new connection.
_GREETING_TIMEOUT = 10.0
#: The largest first frame a Dask scheduler's greeting (its handshake) can plausibly have, in bytes.
_GREETING_MOST = 1 << 20


def _probe(scheduler: str, host: str, port: int, *, greets: bool) -> None:
    """Connect to the scheduler's port and, over plain TCP, read its whole greeting within
    :data:`_GREETING_TIMEOUT`: a Dask scheduler sends its handshake at once, one message framed by
    its size as 8 bytes (little-endian), then its frames' count and sizes, then the frames
    (:func:`_greeting`).  A server that sends nothing (a web server waiting for a request),
    something else (an SSH banner, read as a frame size of exabytes), a size and then nothing, or a
    message Dask cannot read is not one: Dask would wait on it, try to allocate that much, or fail
    with a ``struct.error``."""
    import socket

    with socket.create_connection((host, port), timeout=_GREETING_TIMEOUT) as probe:
        if not greets:
            return
        problem = _greeting(probe, time.monotonic() + _GREETING_TIMEOUT)
    if problem is not None:
        raise InputError(
            f"scheduler {shown(scheduler)} is not a Dask scheduler ({problem}, where a Dask scheduler greets at once "
            "with its handshake); check the address and port",
            field="scheduler",
        )


def _greeting(probe: Any, deadline: float) -> str | None:
    """What is wrong with the first message read from ``probe`` as a Dask handshake (None: it is
    one: a mapping that Dask's own protocol decodes), every read bounded by ``deadline``."""
    import struct

    def exactly(count: int) -> bytes:
        received = b""
        while len(received) < count:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            probe.settimeout(left)
            try:
                chunk = probe.recv(min(count - len(received), 1 << 16))
            except (TimeoutError, OSError):
                break
            if not chunk:
                break
            received += chunk
        return received

    prefix = exactly(8)
    if len(prefix) < 8:
        return f"it said {'nothing' if not prefix else repr(prefix)} within {_GREETING_TIMEOUT:g} s of connecting"
    (size,) = struct.unpack("<Q", prefix)
    if not 8 <= size <= _GREETING_MOST:
        return f"it sent {prefix!r}, a message of {size} bytes"
    body = exactly(size)
    if len(body) < size:
        return f"it announced a message of {size} bytes and sent {len(body)} within {_GREETING_TIMEOUT:g} s"
    try:
        from distributed.protocol.core import loads
        from distributed.protocol.utils import unpack_frames

        frames, missing = unpack_frames(body, partial=True)
        if sum(missing) > _GREETING_MOST:
            return f"its message announced {sum(missing)} bytes more"
        for count in missing:
            frame = exactly(count)
            if len(frame) < count:
                return f"its message stopped short within {_GREETING_TIMEOUT:g} s"
            frames.append(memoryview(frame))
        message = loads(frames, deserialize=False)
    except Exception as error:  # whatever Dask's protocol raises on bytes that are not its own
        return f"its first message is not Dask's ({type(error).__name__})"
    return None if isinstance(message, dict) else "its first message is not a handshake"


def connect(scheduler: str) -> Any:
    """A Dask client of the scheduler at ``scheduler``, or a clear error."""
    address = _scheduler_address(scheduler)
    try:
        from distributed import Client
    except ImportError as exc:
        raise InputError(
            "scheduler needs Dask: pip install 'oscillator[dask]' (dask.distributed)", field="scheduler"
        ) from exc
    parsed = urllib.parse.urlsplit(address)
    try:
        if parsed.scheme in ("tcp", "tls"):  # a refused connection is said at once, not after Dask's retries
            _probe(scheduler, parsed.hostname or "", parsed.port or 0, greets=parsed.scheme == "tcp")
        return Client(address, timeout="10s")
    except InputError:
        raise
    except (OSError, ValueError, TypeError) as exc:
        raise InputError(
            f"scheduler {shown(scheduler)}: cannot reach the Dask scheduler ({exc}); check the address",
            field="scheduler",
        ) from exc
