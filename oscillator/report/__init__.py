"""What a reader sees: figures in the article's style, the transition log, and the report (Markdown and
one self-contained HTML file) built from a small document model that escapes all user text."""

import os as _os
from pathlib import Path as _Path

from oscillator.folders import private_scratch as _private_scratch
from oscillator.folders import writable as _writable


def _matplotlib_config_folder() -> None:
    """matplotlib keeps its font cache in ``MPLCONFIGDIR`` or ``~/.config/matplotlib``; where that
    cannot be written it warns and makes a new temporary folder at every start.  Give it a
    private one that lasts instead (before matplotlib is imported)."""
    if "MPLCONFIGDIR" in _os.environ:
        return
    config = _os.environ.get("XDG_CONFIG_HOME") or str(_Path(_os.path.expanduser("~")) / ".config")
    if not _writable(_Path(config) / "matplotlib"):
        folder = _private_scratch("oscillator-matplotlib")
        if folder is not None:
            _os.environ["MPLCONFIGDIR"] = str(folder)


_matplotlib_config_folder()
