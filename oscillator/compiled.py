"""numba, set up once for the package: compiled code is cached where it can be, and a damaged cache
is compiled afresh instead of breaking every command.

Every module with compiled kernels takes ``njit`` and ``cfunc`` from here, not from numba:

* **Where the cache lives.**  numba caches compiled code next to the source (``__pycache__``) or,
  where that is read-only (a shared install), in the user's cache folder.  When neither can be
  written (a read-only install run by a user without a writable home, as on many clusters), the
  cache goes to the temporary folder (``oscillator-numba-<uid>``), and if even that cannot be
  written, the kernels are compiled without a cache.  A ``NUMBA_CACHE_DIR`` set by the user is
  used as given.
* **A damaged cache file** (an interrupted write, a full disk, an emptied or corrupted ``.nbi`` or
  ``.nbc`` file) is read as a cache miss: the kernel is compiled again and the file rewritten.
  numba 0.68 raises ``EOFError``/``UnpicklingError`` instead (numba issue #10434; the fix,
  numba PR #10656, is not released yet); :func:`_read_damaged_as_missing` backports it.
* **A slice assigned from an array of another shape** raises numba's plain ``ValueError``
  ("cannot assign slice from input of different size"), not the one naming both shapes, whose
  formatting (f-strings of integer tuples) numba compiles again in every process that compiles
  such an assignment, though a correct kernel never runs it: :func:`_plain_shape_errors`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar, overload

import numba
from numba.core import caching

from oscillator.folders import private_scratch, writable

__all__ = ["CACHE", "COMPILING", "cfunc", "holds", "hot", "kernels_cached", "njit"]


def _cache_location() -> str | None:
    """Where numba's cache goes (``""``: numba's own choice), or None for no cache at all."""
    given = getattr(numba.config, "CACHE_DIR", "")  # NUMBA_CACHE_DIR, as numba read it
    if given:
        return str(given)
    if writable(Path(__file__).parent / "__pycache__"):
        return ""
    try:
        from numba.misc.appdirs import user_cache_dir

        if writable(Path(user_cache_dir(appname="numba"))):
            return ""
    except (ImportError, OSError, KeyError):
        pass
    fallback = private_scratch("oscillator-numba")
    return None if fallback is None else str(fallback)


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled switching rules, i.e. whether the next start
    loads the kernels (about a second) rather than compiling them (about half a minute).

    The cache folder is found as numba finds it (the first of its locators that can be used);
    an index there of ``model/theorems.py``'s kernels counts as the cache.  (One left stale by
    an upgrade counts too: the commands then say so when the loading has taken a while.)
    """
    source = str(Path(__file__).parent / "model" / "theorems.py")

    def probe() -> None:  # pragma: no cover - never called: the locators read its code object
        pass

    locators: list[Any] = caching.CacheImpl._locator_classes
    for locator in locators:
        try:
            found = locator.from_function(probe, source)
            if found is None:
                continue
            found.ensure_cache_path()
        except Exception:  # numba tries the next locator likewise
            continue
        return any(Path(found.get_cache_path()).glob("theorems.*.nbi"))
    return False


def holds(kernel: Any) -> bool:
    """Whether numba's cache holds ``kernel`` (a compiled function) already: its index file is
    there (one left by an older install counts too, as for :func:`kernels_cached`)."""
    cache = getattr(kernel, "_cache", None)
    index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
    return index is not None and Path(index).exists()


def _read_damaged_as_missing() -> None:
    """Make numba treat a cache file it cannot unpickle as missing (numba PR #10656)."""
    files = getattr(caching, "IndexDataCacheFile", None)
    if files is None or getattr(files, "_oscillator_guarded", False):
        return
    load_index, load_data = files._load_index, files._load_data

    def guarded_index(self: Any) -> Any:
        try:
            return load_index(self)
        except Exception:  # an unreadable index: as if there were none
            return {}

    def guarded_data(self: Any, name: str) -> Any:
        try:
            return load_data(self, name)
        except OSError:
            raise  # numba's own handling (a removed file)
        except Exception as damaged:  # an unreadable data file: as if it had been removed
            raise OSError(f"damaged cache file {name}") from damaged

    files._load_index, files._load_data = guarded_index, guarded_data
    files._oscillator_guarded = True


def _plain_shape_errors() -> None:
    """Give numba's CPU target the generic target's message for a slice assignment between
    arrays of different shapes (numba's ``raise_with_shape_context``).

    The CPU message formats both shapes; numba compiles that formatting (``str`` of integers,
    joined) in every process that compiles a kernel assigning a slice from an array, once a pair
    of dimensions (measured by ``python benchmarks/compile.py``: docs/performance.md, Start-up).
    It is the message of a bug in a kernel, and stays a ``ValueError``."""
    from numba.np import arrayobj

    cpu = getattr(arrayobj, "ol_raise_with_shape_context_cpu", None)
    generic = getattr(arrayobj, "ol_raise_with_shape_context_generic", None)
    if cpu is not None and generic is not None:
        cpu.__code__ = generic.__code__


_location = _cache_location()
if _location:
    setattr(numba.config, "CACHE_DIR", _location)  # noqa: B010 - numba's config module, read when it caches
_read_damaged_as_missing()
_plain_shape_errors()

#: Whether compiled kernels are cached on disk.
CACHE = _location is not None

#: What a program's first use says while the kernels compile (the command line says it its own way).
COMPILING = "oscillator: compiling the numerical kernels once (10 to 20 s); later runs load them in about a second"
#: Set to ``0`` (the command line does) to say nothing here.
NOTICE_VARIABLE = "OSCILLATOR_COMPILE_NOTICE"


def _say_compiling() -> None:
    """A program's first simulation compiles the kernels (10 to 20 s; it waited in silence): said
    once on stderr when numba's cache does not hold them, in the main process only (workers load
    what it compiled)."""
    import multiprocessing
    import os
    import sys

    if os.environ.get(NOTICE_VARIABLE) == "0" or multiprocessing.parent_process() is not None:
        return
    if not kernels_cached():
        print(COMPILING, file=sys.stderr, flush=True)


_say_compiling()


def _cached(decorator: Callable[..., Any]) -> Callable[..., Any]:
    @functools.wraps(decorator)
    def wrapped(*args: Any, **options: Any) -> Any:
        if not CACHE:
            options.pop("cache", None)
        return decorator(*args, **options)

    return wrapped


if TYPE_CHECKING:  # numba's own, as the type checker knows them
    from numba import cfunc, njit
else:
    #: ``numba.njit`` and ``numba.cfunc``, with ``cache=True`` dropped when no cache can be written.
    njit = _cached(numba.njit)
    cfunc = _cached(numba.cfunc)


_F = TypeVar("_F", bound=Callable[..., Any])


@overload
def hot(function: _F) -> _F: ...


@overload
def hot(*, inline: bool = False) -> Callable[[_F], _F]: ...


def hot(function: Callable[..., Any] | None = None, *, inline: bool = False) -> Any:
    """:func:`njit` for the integrators' inner loops: cached, without numba's reference counting
    (``_nrt=False``: an array passed to a function costs two atomic operations a call, most of a
    step's time; such a function allocates no array), and with IEEE arithmetic (a division by
    zero gives ``inf``, not an exception: the loops test for numbers that are not finite
    themselves).  ``inline`` inlines the function into its callers.  ``@hot`` or ``@hot(inline=True)``."""
    options: dict[str, Any] = {"cache": True, "error_model": "numpy"}
    if inline:
        options["inline"] = "always"
    else:
        options["_nrt"] = False
    decorate = njit(**options)
    return decorate if function is None else decorate(function)
