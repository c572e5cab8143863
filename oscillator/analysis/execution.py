"""Running many independent computations: in this process, on a local process pool, or on Dask.

Sweeps (:mod:`oscillator.analysis.sweeps`) and the search for attractors
(:mod:`oscillator.analysis.attractors`) each run a pure, top-level function on many tasks;
:func:`run_tasks` runs it and yields the results as they finish, whatever runs them:

* ``workers == 1`` (or a single task): one after another, in this process;
* a local pool of ``spawn``-ed processes, at most ``4 workers`` tasks in flight so that memory
  stays flat; the workers ignore Ctrl-C and exit if this process dies
  (:mod:`oscillator.io.signals`), and on an interrupt or an error here they are stopped at once,
  so nothing outlives the caller;
* a Dask client: the ``shared`` arguments scattered once to every worker, one future a task.

The function is called as ``function(*shared, *task, **keywords)``.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

from oscillator.io.signals import interrupts_ignored, prepare_worker, quiet_resource_tracker

__all__ = ["run_tasks"]

T = TypeVar("T")


def run_tasks(
    function: Callable[..., T],
    tasks: Iterable[tuple[Any, ...]],
    *,
    shared: tuple[Any, ...] = (),
    keywords: dict[str, Any] | None = None,
    workers: int = 1,
    client: Any = None,
) -> Iterator[T]:
    """``function(*shared, *task, **keywords)`` for every task, yielded as each finishes (in the
    tasks' order when run in this process)."""
    tasks = list(tasks)
    keywords = keywords or {}
    if client is not None:
        return _on_dask(client, function, tasks, shared, keywords)
    if workers <= 1 or len(tasks) <= 1:
        return (function(*shared, *task, **keywords) for task in tasks)
    return _on_pool(function, tasks, shared, keywords, min(workers, len(tasks)))


def _on_pool(
    function: Callable[..., T],
    tasks: list[tuple[Any, ...]],
    shared: tuple[Any, ...],
    keywords: dict[str, Any],
    workers: int,
) -> Iterator[T]:
    context = multiprocessing.get_context("spawn")
    quiet_resource_tracker()
    pending = iter(tasks)
    running: set[cf.Future[T]] = set()
    with interrupts_ignored():  # the workers are born ignoring SIGINT: the parent alone handles it
        pool = cf.ProcessPoolExecutor(
            max_workers=workers, mp_context=context, initializer=prepare_worker, initargs=(os.getpid(),)
        )

        def fill() -> None:
            for task in pending:
                running.add(pool.submit(function, *shared, *task, **keywords))
                if len(running) >= 4 * workers:
                    return

        fill()
    try:
        while running:
            finished, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            for future in finished:
                running.discard(future)
                yield future.result()
            fill()
    except BaseException:
        for process in list(getattr(pool, "_processes", {}).values()):  # no public way to stop busy workers
            process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)  # quick now; frees the pool's semaphores
        raise
    pool.shutdown()


def _on_dask(
    client: Any,
    function: Callable[..., T],
    tasks: list[tuple[Any, ...]],
    shared: tuple[Any, ...],
    keywords: dict[str, Any],
) -> Iterator[T]:
    from distributed import as_completed

    on_cluster = [client.scatter(item, broadcast=True) for item in shared]
    futures = [client.submit(function, *on_cluster, *task, pure=False, **keywords) for task in tasks]
    try:
        for future in as_completed(futures):
            yield future.result()
            future.release()
    finally:
        client.cancel(futures)
