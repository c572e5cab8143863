"""The explorer's simulations, run off the server's loop, the latest change only.

A page's every change asks for a simulation (a few to a few hundred ms) and, once the controls
rest, for CVODE's check of it.  Run on the server's loop, they held every other page and the
server's own messages while they ran (30 key presses in a second ran 30 simulations, the last
drawn 7.6 s later; a reload waited 16 s for work its old page had abandoned).  A :class:`Runner`
runs them one at a time in a thread of its own:

* a change while one runs waits, and a later change replaces it: only the last one waiting runs;
* a change within :data:`QUIET` s of the one before waits until the changes rest that long (the
  first of a burst runs at once, then the last: 30 key presses in a second run 2 simulations);
* a job may ask to wait (CVODE's check, once the controls rest) and is dropped by any change that
  comes first; one running is told to stop (its ``stop()`` says so) when a change comes;
* each result reaches ``deliver`` on the server's loop (Bokeh's ``add_next_tick_callback``, the
  one call a thread may make on a document) with the job's number, so that a page draws only
  the result of the last change asked.

Outside a server (a notebook) jobs run at once, in the caller's thread.
"""

from __future__ import annotations

import threading
import time
import weakref
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

__all__ = ["QUIET", "Job", "Runner", "close_all"]

#: Changes closer together than this (s) are one burst: its first runs at once, its last once it rests.
QUIET = 0.15


@dataclass
class Job:
    """One simulation asked for: ``work(stop)`` computes it (``stop()`` is true once another job
    is asked); ``number`` orders the jobs asked; ``wait`` s before it may start (0: at once,
    or as the burst rule says); ``kind`` says what it is."""

    work: Callable[[Callable[[], bool]], Any]
    number: int
    wait: float = 0.0
    kind: str = "draw"  #: what it is, for the count of :attr:`Runner.ran`
    asked: float = field(default_factory=time.monotonic)


#: Every runner alive, so that a stopping server can end their threads (:func:`close_all`).
_LIVE: weakref.WeakSet[Runner] = weakref.WeakSet()


def close_all(timeout: float = 10.0) -> None:
    """Close every runner and wait (at most ``timeout`` s in all) for its thread to end: a job
    still running in compiled code while the interpreter shuts down can crash it (the explorer
    stopped by Ctrl-C while a page's check ran exited with SIGSEGV after saying "stopped")."""
    runners = list(_LIVE)
    for runner in runners:
        runner.close()
    deadline = time.monotonic() + timeout
    for runner in runners:
        thread = runner._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(max(0.0, deadline - time.monotonic()))


class Runner:
    """Runs :class:`Job` s one at a time in a thread of its own (module docstring); ``deliver(job,
    result, error)`` is called through ``on_loop`` (None: in the caller's thread, jobs run at
    once)."""

    def __init__(
        self,
        deliver: Callable[[Job, Any, BaseException | None], None],
        on_loop: Callable[[Callable[[], None]], None] | None = None,
        quiet: float = QUIET,
    ) -> None:
        self.deliver, self.on_loop, self.quiet = deliver, on_loop, quiet
        self._pending: Job | None = None
        self._running: Job | None = None
        self._last_asked = -float("inf")
        self._closed = False
        self._condition = threading.Condition()
        self._thread: threading.Thread | None = None
        #: The jobs run of each kind (``"draw"``, ``"check"``), for the tests and the status line.
        self.ran: Counter[str] = Counter()
        #: The bursts of changes seen: a change that came when none had for :attr:`quiet` s began
        #: one (each runs at most twice: its first change and its last).
        self.bursts = 0
        _LIVE.add(self)

    @property
    def latest(self) -> int:
        """The number of the last job asked (0 before any)."""
        with self._condition:
            newest = self._pending or self._running
            return newest.number if newest is not None else 0

    def ask(self, job: Job, *, change: bool = True) -> None:
        """Run ``job`` when its turn comes; it replaces any job waiting, and tells a running one
        to stop.  A ``change`` (the controls moved) counts for the burst rule; a check does not."""
        if self.on_loop is None:  # no server: at once
            self._run(job)
            return
        with self._condition:
            if change:
                now = time.monotonic()
                if now - self._last_asked < self.quiet:
                    job.wait = max(job.wait, self.quiet)
                else:
                    self.bursts += 1
                self._last_asked = now
            self._pending = job
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, name="oscillator-explore", daemon=True)
                self._thread.start()
            self._condition.notify_all()

    def close(self) -> None:
        """No more jobs: the one waiting is dropped, a running one told to stop, the thread ends."""
        with self._condition:
            self._closed, self._pending = True, None
            self._condition.notify_all()

    def _stopped(self, job: Job) -> Callable[[], bool]:
        return lambda: self._closed or (self._pending is not None and self._pending.number > job.number)

    def _next(self) -> Job | None:
        """The job to run next, once its wait is over (None once closed)."""
        with self._condition:
            while True:
                if self._closed:
                    return None
                job = self._pending
                if job is None:
                    self._condition.wait()
                    continue
                left = job.wait - (time.monotonic() - max(job.asked, self._last_asked))
                if left > 0:
                    self._condition.wait(left)
                    continue
                self._pending, self._running = None, job
                return job

    def _loop(self) -> None:
        while (job := self._next()) is not None:
            self._run(job)
            with self._condition:
                self._running = None

    def _run(self, job: Job) -> None:
        self.ran[job.kind] += 1
        result: Any = None
        error: BaseException | None = None
        try:
            result = job.work(self._stopped(job))
        except Exception as exc:  # handed to the page, which says it
            error = exc
        if self.on_loop is None:
            self.deliver(job, result, error)
        elif not self._closed:
            self.on_loop(lambda: self.deliver(job, result, error))
