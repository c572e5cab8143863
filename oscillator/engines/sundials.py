"""SUNDIALS' C libraries, loaded from the scikit-sundae wheel, with the CVODE API the package calls.

scikit-sundae (the dependency that provides SUNDIALS) bundles the libraries in its wheel as
``scikit_sundae.libs/libsundials_<name>-<hash>.so.<version>``.  Those names are not a public
API, so they are found through the installed distribution's file list, never guessed; they are
loaded with ``RTLD_LOCAL`` so that another SUNDIALS in the process (scikit-sundae's own
extension modules) keeps its symbols to itself.  Nothing here imports scikit-sundae's Python
module (which imports SciPy).

The signatures are SUNDIALS 7's (``sunrealtype`` double, ``sunindextype`` int32 as the wheel is
built); :data:`SUPPORTED` is checked against ``SUNDIALSGetVersion``.
"""

from __future__ import annotations

import ctypes
import functools
import os
from dataclasses import dataclass
from importlib import metadata
from typing import Any

__all__ = ["SUPPORTED", "Sundials", "SundialsUnavailable", "describe", "flag_name", "load"]

#: The SUNDIALS major versions whose API and vector layout this module is written for.
SUPPORTED = (7,)
#: The libraries the C engine needs, in load order.
LIBRARIES = ("core", "nvecserial", "sunmatrixdense", "sunlinsoldense", "cvode")
#: CVODE's constants (cvode.h).
CV_ADAMS, CV_NORMAL, CV_ONE_STEP = 1, 1, 2
CV_SUCCESS, CV_TSTOP_RETURN, CV_ROOT_RETURN = 0, 1, 2

_P = ctypes.c_void_p
_INT = ctypes.c_int
_LONG = ctypes.c_long
_DOUBLE = ctypes.c_double
_INDEX = ctypes.c_int32

#: (library, function, restype, argtypes) of every C function used.
_API: tuple[tuple[str, str, Any, tuple[Any, ...]], ...] = (
    ("core", "SUNContext_Create", _INT, (_INT, ctypes.POINTER(_P))),
    ("core", "SUNContext_Free", _INT, (ctypes.POINTER(_P),)),
    ("core", "SUNContext_ClearErrHandlers", _INT, (_P,)),
    ("core", "SUNContext_PushErrHandler", _INT, (_P, _P, _P)),
    ("core", "SUNDIALSGetVersion", _INT, (ctypes.c_char_p, _INT)),
    ("core", "N_VDestroy", None, (_P,)),
    ("core", "N_VGetArrayPointer", ctypes.POINTER(_DOUBLE), (_P,)),
    ("core", "SUNMatDestroy", None, (_P,)),
    ("core", "SUNLinSolFree", _INT, (_P,)),
    ("nvecserial", "N_VNew_Serial", _P, (_INDEX, _P)),
    ("sunmatrixdense", "SUNDenseMatrix", _P, (_INDEX, _INDEX, _P)),
    ("sunlinsoldense", "SUNLinSol_Dense", _P, (_P, _P, _P)),
    ("cvode", "CVodeCreate", _P, (_INT, _P)),
    ("cvode", "CVodeInit", _INT, (_P, _P, _DOUBLE, _P)),
    ("cvode", "CVodeReInit", _INT, (_P, _DOUBLE, _P)),
    ("cvode", "CVodeSStolerances", _INT, (_P, _DOUBLE, _DOUBLE)),
    ("cvode", "CVodeSetLinearSolver", _INT, (_P, _P, _P)),
    ("cvode", "CVodeSetUserData", _INT, (_P, _P)),
    ("cvode", "CVodeSetMaxNonlinIters", _INT, (_P, _INT)),
    ("cvode", "CVodeSetMaxConvFails", _INT, (_P, _INT)),
    ("cvode", "CVodeSetInitStep", _INT, (_P, _DOUBLE)),
    ("cvode", "CVodeSetMinStep", _INT, (_P, _DOUBLE)),
    ("cvode", "CVodeSetMaxStep", _INT, (_P, _DOUBLE)),
    ("cvode", "CVodeSetMaxOrd", _INT, (_P, _INT)),
    ("cvode", "CVodeSetMaxNumSteps", _INT, (_P, _LONG)),
    ("cvode", "CVodeRootInit", _INT, (_P, _INT, _P)),
    ("cvode", "CVodeSetRootDirection", _INT, (_P, _P)),
    ("cvode", "CVodeSetNoInactiveRootWarn", _INT, (_P,)),
    ("cvode", "CVodeSetStopTime", _INT, (_P, _DOUBLE)),
    ("cvode", "CVodeClearStopTime", _INT, (_P,)),
    ("cvode", "CVode", _INT, (_P, _DOUBLE, _P, ctypes.POINTER(_DOUBLE), _INT)),
    ("cvode", "CVodeGetRootInfo", _INT, (_P, _P)),
    ("cvode", "CVodeGetNumRhsEvals", _INT, (_P, ctypes.POINTER(_LONG))),
    ("cvode", "CVodeGetReturnFlagName", _P, (_LONG,)),
    ("cvode", "CVodeFree", None, (ctypes.POINTER(_P),)),
)

#: SUNDIALS' error handler: (line, function, file, message, error code, user data, context).
ERROR_HANDLER = ctypes.CFUNCTYPE(None, _INT, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, _INT, _P, _P)


class SundialsUnavailable(RuntimeError):
    """SUNDIALS' C libraries cannot be used here; the message says why."""


@dataclass(frozen=True)
class Sundials:
    """The loaded libraries: ``api.<C function name>`` with its signature declared."""

    version: str
    paths: dict[str, str]
    api: Any


def library_paths() -> dict[str, str]:
    """``name -> path`` of SUNDIALS' libraries in the installed scikit-sundae distribution."""
    try:
        files = metadata.distribution("scikit-sundae").files or []
    except metadata.PackageNotFoundError as exc:
        raise SundialsUnavailable("scikit-sundae is not installed") from exc
    found: dict[str, str] = {}
    for file in files:
        folder, _, name = str(file).rpartition("/")
        if folder == "scikit_sundae.libs" and name.startswith("libsundials_") and ".so" in name:
            key = name.removeprefix("libsundials_").split("-")[0].split(".")[0]
            found[key] = str(file.locate())
    missing = [name for name in LIBRARIES if name not in found]
    if missing:
        raise SundialsUnavailable(
            f"the scikit-sundae wheel holds no libsundials_{missing[0]} (its layout is not one this version "
            f"supports; scikit-sundae {metadata.version('scikit-sundae')})"
        )
    return found


class _Api:
    """Attribute access to the declared C functions of several libraries."""


@functools.cache
def load() -> Sundials:
    """Load and declare the libraries once per process; raise :class:`SundialsUnavailable`."""
    paths = library_paths()
    mode = os.RTLD_LOCAL | os.RTLD_NOW
    try:
        libraries = {name: ctypes.CDLL(paths[name], mode=mode) for name in LIBRARIES}
    except OSError as exc:
        raise SundialsUnavailable(f"SUNDIALS' libraries cannot be loaded ({exc})") from exc
    api: Any = _Api()
    for library, name, restype, argtypes in _API:
        try:
            function = getattr(libraries[library], name)
        except AttributeError as exc:
            raise SundialsUnavailable(f"libsundials_{library} has no {name}") from exc
        function.restype = restype
        function.argtypes = argtypes
        setattr(api, name, function)
    buffer = ctypes.create_string_buffer(64)
    api.SUNDIALSGetVersion(buffer, len(buffer))
    version = buffer.value.decode("ascii", "replace")
    major = version.split(".")[0]
    if not major.isdigit() or int(major) not in SUPPORTED:
        raise SundialsUnavailable(f"SUNDIALS {version} is not a supported version ({SUPPORTED} only)")
    return Sundials(version, paths, api)


#: What the flags a run can meet mean, in a user's words.
MEANINGS = {
    -1: "took max_num_steps steps without reaching the output time",
    -2: "could not reach the requested accuracy for a step",
    -3: "the error test failed repeatedly or the step fell to the min step size",
    -4: "the corrector failed to converge repeatedly or the step fell to the min step size",
    -6: "the linear solver's setup failed",
    -7: "the linear solver failed",
    -8: "the right-hand side failed",
    -12: "the root functions failed",
    -22: "an input was invalid",
}

_LIBC = ctypes.CDLL(None)
_LIBC.free.argtypes = (_P,)
_LIBC.free.restype = None


def describe(flag: int) -> str:
    """A flag's name and meaning, e.g. ``CV_TOO_MUCH_WORK: took max_num_steps steps ...``."""
    meaning = MEANINGS.get(flag)
    return f"{flag_name(flag)}: {meaning}" if meaning else flag_name(flag)


def flag_name(flag: int) -> str:
    """CVODE's name of a return flag, e.g. ``CV_TOO_MUCH_WORK`` (SUNDIALS allocates it; freed here)."""
    address = load().api.CVodeGetReturnFlagName(flag)
    if not address:
        return f"flag {flag}"
    try:
        return ctypes.string_at(address).decode("ascii", "replace")
    finally:
        _LIBC.free(address)
