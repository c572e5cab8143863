"""Text that comes from outside (case files, command lines, file names), made safe to show.

A message quotes what it refuses, so that the user sees it; but a terminal must never receive an
escape sequence from it, a message stays on one line, and a value of a megabyte is not echoed
whole.
"""

from __future__ import annotations

import unicodedata

__all__ = ["did_you_mean", "printable", "shown", "unsafe_characters"]


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


def did_you_mean(word: object, choices: list[str] | tuple[str, ...]) -> str:
    """``"; did you mean 'x'?"`` for the choice closest to a misspelt ``word`` (the same letters
    in another case first, then by :mod:`difflib`), or ``""`` where none is close."""
    import difflib

    if not isinstance(word, str) or len(word) > 64:
        return ""
    same = [choice for choice in choices if choice.lower() == word.lower()]
    close = same or difflib.get_close_matches(word, list(choices), n=1, cutoff=0.5)
    return f"; did you mean {close[0]!r}?" if close else ""
