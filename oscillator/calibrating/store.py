"""A calibration's resumable folder (``calibration.json``): each start's fit kept as it ends, so
that the same calibration run again reads back the starts it finished and fits only the rest
(``oscillator calibrate ... --out DIR``, docs/calibration.md).

A part ``start-KKK.parquet`` holds start ``K``'s end (:class:`~oscillator.calibrating.fit.Fit`):
one row per measurement with its weighted residual, the model's value and the Jacobian's columns
``d0``, ``d1``, ...; its metadata the scaled point, the cost, SciPy's verdict, the simulations,
the crossings and the notes. A start that found no orbit is a part without rows. The marker
keeps the calibration's identity: the model, a digest of the data as read, the ranges and every
setting a fit depends on (not the intervals' level, which only the summary uses).
"""

from __future__ import annotations

import hashlib
import inspect
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.store import Expected, TableFolder, identity
from oscillator.calibrating.fit import Fit
from oscillator.calibrating.steady import Crossing

__all__ = ["FITTED", "CalibrationStore", "calibration_store"]


class CalibrationStore(TableFolder):
    """The resumable folder of a calibration (module docstring)."""

    FORMAT = 1

    def __init__(self, folder: Path, identity: dict[str, Any], *, name: str = "") -> None:
        super().__init__(folder, "calibration.json", identity, name=name)

    @staticmethod
    def _name(k: int) -> str:
        return f"start-{k:03d}"

    def write_fit(self, k: int, u0: np.ndarray, fit: Fit) -> None:
        """Keep start ``k``'s end (from the scaled point ``u0``)."""
        frame = pd.DataFrame({"residual": fit.residuals, "fitted": fit.fitted})
        for j in range(fit.jacobian.shape[1]):
            frame[f"d{j}"] = fit.jacobian[:, j]
        meta = {"u": [float(v) for v in fit.u], "cost": fit.cost, "evaluations": fit.evaluations}
        meta |= {"message": fit.message, "success": fit.success, "runs": fit.runs, "notes": list(fit.notes)}
        meta["crossings"] = [[c.evaluation, c.at, c.before, c.after] for c in fit.crossings]
        self.write(self._name(k), frame, meta, key=_key(k, u0))

    def read_fit(self, k: int, u0: np.ndarray, rows: int) -> Fit | None:
        """Start ``k``'s end if the folder holds it (``rows`` measurements), else None; a part that
        is not that start's is refused by name."""
        n = len(u0)
        columns = {"residual": "number", "fitted": "number"} | {f"d{j}": "number" for j in range(n)}
        check = _meta_problem(n, rows)
        kept = self.read(self._name(k), Expected(_key(k, u0), columns, check=check))
        if kept is None:
            return None
        frame, meta = kept
        jacobian = frame[[f"d{j}" for j in range(n)]].to_numpy(float).reshape(len(frame), n)
        crossings = tuple(Crossing(int(e), float(at), int(b), int(a)) for e, at, b, a in meta["crossings"])
        return Fit(
            np.array(meta["u"], dtype=float),
            float(meta["cost"]),
            frame.residual.to_numpy(float),
            jacobian,
            frame.fitted.to_numpy(float),
            int(meta["evaluations"]),
            str(meta["message"]),
            bool(meta["success"]),
            runs=int(meta["runs"]),
            crossings=crossings,
            notes=tuple(str(note) for note in meta["notes"]),
        )


def _key(k: int, u0: np.ndarray) -> dict[str, Any]:
    return {"start": k, "u0": [float(v) for v in u0]}


def _meta_problem(n: int, rows: int) -> Any:
    """What is wrong with a start's part of ``n`` parameters and ``rows`` measurements."""

    def problem(frame: pd.DataFrame, meta: Any) -> str:
        fields = {"u", "cost", "evaluations", "message", "success", "runs", "notes", "crossings"}
        if not isinstance(meta, dict) or not fields <= set(meta):
            return "its metadata lacks the fit's verdict"
        u, cost = meta["u"], meta["cost"]
        if not isinstance(u, list) or len(u) != n or not all(isinstance(v, float | int) and 0 <= v <= 1 for v in u):
            return f"its point is not {n} numbers from 0 to 1"
        if not isinstance(cost, float | int) or not (math.isnan(cost) or cost >= 0):
            return "its cost is not a number at least 0"
        if len(frame) != (0 if math.isnan(cost) else rows):
            return f"it has {len(frame)} rows, where the data has {rows}"
        if not all(isinstance(meta[f], int) and meta[f] >= 0 for f in ("evaluations", "runs")):
            return "its counts are not whole numbers"
        if not isinstance(meta["notes"], list) or not isinstance(meta["crossings"], list):
            return "its notes or crossings are not lists"
        if not all(isinstance(c, list) and len(c) == 4 for c in meta["crossings"]):
            return "its crossings are not four numbers each"
        return ""

    return problem


#: The settings of :func:`~oscillator.calibrating.fit.calibrate` that its fits depend on.
FITTED = ("over", "starts", "loss", "f_scale", "transient", "seed", "max_evaluations")


def calibration_store(
    folder: Path,
    system: Any,
    data: pd.DataFrame,
    vary: Mapping[str, Sequence[float]],
    **settings: Any,
) -> CalibrationStore:
    """The resumable folder of calibrating ``system`` to ``data`` over ``vary`` with ``settings``
    (:func:`~oscillator.calibrating.fit.calibrate`'s :data:`FITTED` keywords; those left out take
    its defaults). ``calibrate`` refuses a store made for other arguments than its own."""
    from oscillator.calibrating.fit import _system, calibrate
    from oscillator.errors import InputError
    from oscillator.text import printable

    unknown = sorted(set(settings) - set(FITTED))
    if unknown:
        raise InputError(
            f"calibration_store takes {', '.join(FITTED)}, not {', '.join(map(printable, unknown))}", field="settings"
        )
    defaults = {name: p.default for name, p in inspect.signature(calibrate).parameters.items() if name in FITTED}
    model = _system(system)
    digest = hashlib.sha256(data.to_csv(index=False).encode("utf-8")).hexdigest()
    ranges = {str(name): [float(v) for v in bounds] for name, bounds in vary.items()}
    pieces = identity(model, data_sha256=digest, vary=ranges, **(defaults | settings))
    return CalibrationStore(folder, pieces, name=str(getattr(model, "name", "") or ""))
