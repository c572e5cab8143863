"""A measurement file: a CSV table someone measured, read as untrusted text.

A header row naming the columns, then one row per measurement; lines starting with ``#`` are
comments.  The file is read only where a command is told to (``oscillator calibrate CASE
DATA``), at most :data:`MAX_BYTES`, UTF-8; every text in it is data, printed escaped, never a
name of another file.
"""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd

from oscillator.errors import InputError
from oscillator.io.files import read_untrusted
from oscillator.text import printable

__all__ = ["MAX_BYTES", "read_measurements"]

#: The largest measurement file read (bytes).
MAX_BYTES = 64 * 2**20


def read_measurements(path: Path) -> pd.DataFrame:
    """The table of the measurement file ``path`` (module docstring).

    Raises
    ------
    InputError
        The file cannot be read, is not UTF-8, is larger than :data:`MAX_BYTES`, or is not a CSV
        table with a header row and at least one data row.
    """
    text = read_untrusted(path, what="measurement file", field="data", limit=MAX_BYTES)
    try:
        table = pd.read_csv(io.StringIO(text.removeprefix("\ufeff")), comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as error:
        reason = printable(str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__)
        raise InputError(
            f"measurement file {printable(str(path))} is not a CSV table ({reason}); give a header row naming the "
            "columns, then one row per measurement",
            field="data",
        ) from None
    if table.empty:
        raise InputError(
            f"measurement file {printable(str(path))} holds no measurement; give one row per measurement under its "
            "header",
            field="data",
        )
    table.columns = [str(c).strip() for c in table.columns]
    return table
