"""Text that comes from outside (case files, command lines, file names), made safe to show.

A message quotes what it refuses, so that the user sees it; but a terminal must never receive an
escape sequence from it, a message stays on one line, and a value of a megabyte is not echoed
whole.
"""

from __future__ import annotations

import unicodedata

__all__ = ["printable", "shown", "unsafe_characters"]


def _unsafe(character: str) -> bool:
    """Control characters, lone surrogates, and the bidirectional overrides that can make text
    read backwards ("Trojan source")."""
    return (
        unicodedata.category(character) in ("Cc", "Cs")
        or "\u202a" <= character <= "\u202e"
        or "\u2066" <= character <= "\u2069"
    )


def unsafe_characters(text: str, *, allow: str = "") -> list[str]:
    """The control characters (and bidi overrides) in ``text``, other than those in ``allow``."""
    return [c for c in text if _unsafe(c) and c not in allow]


def printable(text: str) -> str:
    """``text`` with control characters, lone surrogates and bidi overrides written as escapes."""
    return "".join(repr(c)[1:-1] if _unsafe(c) else c for c in text)


def shown(value: object, limit: int = 60) -> str:
    """``repr(value)`` for a message: printable, and cut to about ``limit`` characters."""
    text = printable(repr(value))
    return text if len(text) <= limit else f"{text[: limit - 1]}…"
