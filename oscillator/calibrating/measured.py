"""Measured steady responses: one row per measurement, checked before any simulation.

A table of the steady response of a machine driven at several values of one parameter (the
forcing frequency ``Omega`` most often): the column named after that parameter, ``measure`` (a
response measure's name: ``x_pp_m1``, ``impact_max_right``, ``x_pp:blade``), ``value`` and,
optionally, ``sigma``, the measurement's standard deviation in the measure's unit.  Several
measures at one frequency, and repeated measurements, are several rows.

Each refusal names the row (counted from 1, as a spreadsheet shows a CSV file's data rows) and the
column, and says what to give instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from oscillator.errors import InputError
from oscillator.text import printable, shown

__all__ = ["FRACTIONS", "NON_NEGATIVE", "Measured", "check_measured"]

#: Measures that cannot be negative (peak-to-peak and RMS values, counts, fractions), by the start
#: of their name: the article's system's (``x_pp_m1``) and a declared system's (``x_pp:blade``).
NON_NEGATIVE = ("x_pp", "x_rms", "a_rms", "v_peak", "rest_", "time_", "onsets_", "stuck:", "closed:", "closings:")
#: Measures that are shares of a period, from 0 to 1.
FRACTIONS = ("rest_", "time_", "stuck:", "closed:")
_COLUMNS = ("measure", "value", "sigma")


@dataclass(frozen=True)
class Measured:
    """Checked measurements (module docstring): ``over`` the parameter the rows were measured
    at, ``table`` with the columns ``over``, ``measure``, ``value`` and ``sigma`` (1.0 where none
    was given: then the noise's scale is estimated from the fit), ``known_sigma`` whether the
    table gave it."""

    over: str
    table: pd.DataFrame
    known_sigma: bool

    @property
    def values(self) -> np.ndarray:
        """The distinct values of :attr:`over`, in increasing order."""
        return np.unique(self.table[self.over].to_numpy())


def _plain(value: object) -> object:
    """A NumPy scalar as the Python number it holds (``1.5``, not ``np.float64(1.5)``)."""
    return value.item() if isinstance(value, np.generic) else value


def _where(row: int, over: str, at: object) -> str:
    return f"data row {row} ({printable(over)} = {shown(_plain(at))})"


def _numbers(table: pd.DataFrame, column: str, over: str) -> np.ndarray:
    values: np.ndarray = pd.to_numeric(table[column], errors="coerce").to_numpy(dtype=float)
    for k in np.flatnonzero(~np.isfinite(values)):
        given = _plain(table[column].iloc[k])
        raise InputError(
            f"{_where(int(k) + 1, over, table[over].iloc[k])}: {column} is {shown(given)}; give a finite number "
            "(or leave the row out)",
            field=column,
        )
    return values


def _check_units(table: pd.DataFrame, over: str) -> None:
    """A value its measure cannot take: a negative amplitude, a share of a period above 1."""
    for k, (measure, value) in enumerate(zip(table.measure, table.value, strict=True)):
        where = f"{_where(int(k) + 1, over, table[over].iloc[k])}: {printable(measure)} = {value:g}"
        if measure.startswith(NON_NEGATIVE) and value < 0:
            raise InputError(f"{where} cannot be negative; check the sign and the unit of the column", field="value")
        if measure.startswith(FRACTIONS) and value > 1:
            raise InputError(
                f"{where} is a share of a period, from 0 to 1; give it as a fraction, not in percent", field="value"
            )


def check_measured(data: object, over: str, parameters: int, measures: tuple[str, ...] | None = None) -> Measured:
    """``data`` (a DataFrame, module docstring) checked: its columns, every row's numbers, each
    measure's name (against ``measures`` where they are known before the first orbit) and values
    it can take, and more rows than ``parameters`` (the fitted parameters' count).

    Raises
    ------
    InputError
        The first fault, by row and column, with the fix.
    """
    if not isinstance(data, pd.DataFrame):
        raise InputError(f"data must be a pandas DataFrame of measurements, got {shown(data)}", field="data")
    missing = [c for c in (over, "measure", "value") if c not in data.columns]
    if missing:
        raise InputError(
            f"data has no column {', '.join(repr(printable(c)) for c in missing)}; give the columns "
            f"{printable(over)!r}, 'measure', 'value' "
            "and optionally 'sigma' (its columns are " + ", ".join(repr(printable(str(c))) for c in data.columns) + ")",
            field="data",
        )
    extra = [str(c) for c in data.columns if c not in (over, *_COLUMNS)]
    if extra:
        raise InputError(
            f"data has a column the fit does not read: {', '.join(map(repr, map(printable, extra)))}; keep "
            f"{over!r}, 'measure', 'value' and 'sigma' (the measurement's standard deviation)",
            field="data",
        )
    if len(data) <= parameters:
        raise InputError(
            f"data has {len(data)} row(s) for {parameters} parameter(s); a fit needs more measurements than "
            "parameters (and one more to estimate the noise)",
            field="data",
        )
    table = pd.DataFrame({over: _numbers(data, over, over)})
    table["measure"] = [_measure(m, k + 1, over, table[over].iloc[k], measures) for k, m in enumerate(data.measure)]
    table["value"] = _numbers(data.assign(**{over: table[over]}), "value", over)
    known = "sigma" in data.columns
    table["sigma"] = _numbers(data.assign(**{over: table[over]}), "sigma", over) if known else 1.0
    for k in np.flatnonzero(table.sigma.to_numpy() <= 0):
        raise InputError(
            f"{_where(int(k) + 1, over, table[over].iloc[k])}: sigma is {table.sigma.iloc[k]:g}; a standard deviation "
            "is positive",
            field="sigma",
        )
    _check_units(table, over)
    return Measured(over, table, known)


def _measure(name: object, row: int, over: str, at: float, measures: tuple[str, ...] | None) -> str:
    if not isinstance(name, str) or not name.strip():
        raise InputError(
            f"{_where(row, over, at)}: measure is {shown(name)}; name a response measure, e.g. 'x_pp_m1'",
            field="measure",
        )
    if measures is not None and name not in measures:
        close = [m for m in measures if m.split("_")[0] == name.split("_")[0]][:6] or list(measures[:6])
        raise InputError(
            f"{_where(row, over, at)}: no response measure named {printable(name)!r}; choose one of "
            f"{', '.join(close)}{', ...' if len(measures) > len(close) else ''}",
            field="measure",
        )
    return name


def check_series(data: object, parameters: int, t0: float, variables: tuple[str, ...]) -> Measured:
    """A measured time series (a DataFrame: ``t``, ``variable`` one of the system's state
    ``variables``, ``value``, optionally ``sigma``) checked like :func:`check_measured`, and its
    times finite, not before the model's start ``t0`` and in increasing order down the rows."""
    if not isinstance(data, pd.DataFrame):
        raise InputError(f"data must be a pandas DataFrame of measurements, got {shown(data)}", field="data")
    renamed = data.rename(columns={"variable": "measure"}) if "variable" in data.columns else data
    if "measure" in data.columns and "variable" in data.columns:
        raise InputError("data has both 'measure' and 'variable'; a time series names a 'variable'", field="data")
    if "variable" not in data.columns:
        raise InputError(
            f"a time series needs the columns 't', 'variable' (one of {', '.join(variables)}), 'value' and "
            "optionally 'sigma'",
            field="data",
        )
    found = check_measured(renamed, "t", parameters, variables)
    table = found.table.rename(columns={"measure": "variable"})
    times = table.t.to_numpy()
    for k in np.flatnonzero(times < t0):
        raise InputError(
            f"{_where(int(k) + 1, 't', times[k])}: the measurement is before the model's start t0 = {t0:g} s; "
            "give times from the start on (or move the start with t0)",
            field="t",
        )
    for k in np.flatnonzero(np.diff(times) < 0):
        raise InputError(
            f"{_where(int(k) + 2, 't', times[k + 1])}: the times are not in order (row {int(k) + 1} is at "
            f"t = {times[k]:g} s); sort the rows by time",
            field="t",
        )
    return Measured("t", table, found.known_sigma)


def check_events(
    data: object,
    parameters: int,
    t0: float,
    kinds: tuple[str, ...],
    masses: tuple[object, ...],
    *,
    by: str = "mass",
) -> Measured:
    """Measured event times (a DataFrame: ``kind``, one of ``kinds``, ``t``, and optionally
    ``sigma`` in seconds and the column ``by``: the article's ``mass``, one of ``masses``, or a
    declared system's ``element``, one of its elements' names), checked by row and column;
    ``value`` is the time. A row without ``by`` matches the kind's event of any mass or element."""
    if not isinstance(data, pd.DataFrame):
        raise InputError(f"data must be a pandas DataFrame of measurements, got {shown(data)}", field="data")
    extra = [str(c) for c in data.columns if c not in ("kind", by, "t", "sigma")]
    if "t" not in data.columns or extra:
        raise InputError(
            f"measured events need the columns 'kind' and 't', and optionally {by!r} and 'sigma'"
            + (f"; the fit does not read {', '.join(map(repr, map(printable, extra)))}" if extra else ""),
            field="data",
        )
    given = data.assign(measure=data["kind"], value=data["t"]).drop(columns=["kind", "t"])
    checked = check_measured(given.drop(columns=by, errors="ignore").assign(at=0.0), "at", parameters, kinds)
    table = checked.table.drop(columns="at").rename(columns={"measure": "kind"})
    table.insert(1, "t", table.value)
    table.insert(1, by, _which(data, by, masses))
    times = table.t.to_numpy()
    for k in np.flatnonzero(times < t0):
        raise InputError(f"data row {int(k) + 1}: t = {times[k]:g} s is before the model's start {t0:g} s", field="t")
    for k in np.flatnonzero(np.diff(times) < 0):
        raise InputError(
            f"data row {int(k) + 2}: t = {times[k + 1]:g} s comes before row {int(k) + 1}'s {times[k]:g} s; "
            "sort the rows by time",
            field="t",
        )
    return Measured("t", table, checked.known_sigma)


def _which(data: pd.DataFrame, by: str, known: tuple[object, ...]) -> np.ndarray:
    """Each row's mass (a number, 0 where not given) or element (a name, ``""`` where not
    given), one of ``known``."""
    if by == "mass":
        given = pd.to_numeric(data[by], errors="coerce") if by in data.columns else pd.Series(0, index=data.index)
        blank: object = 0
    else:
        given = data[by].map(lambda v: "" if pd.isna(v) else str(v).strip()) if by in data.columns else None
        given = pd.Series("", index=data.index) if given is None else given
        blank = ""
    for row, value in enumerate(given.to_numpy()):
        if value != blank and value not in known:
            raise InputError(
                f"data row {row + 1}: {by} is {shown(_plain(data[by].iloc[row]))}; give one of "
                f"{', '.join(map(str, known))} (or leave it out: any {by})",
                field=by,
            )
    column: np.ndarray = given.fillna(0).astype(int).to_numpy() if by == "mass" else given.to_numpy(dtype=object)
    return column
