"""A small document model for reports, written out as Markdown and as one self-contained HTML file.

Reports quote text that other people wrote (a case's title, description, expected-event labels
and notes, a run folder's ``run.json``).  So the report is built as data, never as markup:
headings, paragraphs, bullet lists, tables and figures whose content is plain text, with a few
styled spans (emphasis, strong, code) chosen by this package.  Each writer escapes every piece
of text for its language, so nothing in the text can become markup: no HTML tag, no link, no
image, no Markdown emphasis or list.  A figure is named by its file name in the run folder's
``figures/`` (one of the package's own figure names), never by a path taken from text.

The HTML page carries a Content Security Policy that allows no script and no remote resource at
all, as a second line of defence.
"""

from __future__ import annotations

import base64
import html
import os
import re
import stat
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "Block",
    "Bullets",
    "Figure",
    "Heading",
    "Paragraph",
    "Span",
    "Table",
    "html_fragment",
    "to_html",
    "to_markdown",
]


@dataclass(frozen=True, slots=True)
class Span:
    """Text shown with a style: ``"em"``, ``"strong"`` or ``"code"``."""

    text: str
    style: str

    def __post_init__(self) -> None:
        if self.style not in _HTML_TAGS:
            raise ValueError(f"unknown style {self.style!r}")


#: A run of inline content: plain strings (always escaped) and styled spans.
Inline = str | Span


@dataclass(frozen=True, slots=True)
class Heading:
    level: int
    content: tuple[Inline, ...]


@dataclass(frozen=True, slots=True)
class Paragraph:
    content: tuple[Inline, ...]


@dataclass(frozen=True, slots=True)
class Bullets:
    items: tuple[tuple[Inline, ...], ...]


@dataclass(frozen=True, slots=True)
class Table:
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True, slots=True)
class Figure:
    """A figure of the run folder: ``figures/<name>.png``; ``name`` is the package's, not text."""

    name: str
    caption: str

    def __post_init__(self) -> None:
        if not re.fullmatch(r"[a-z0-9][a-z0-9-]*", self.name):
            raise ValueError(f"a figure is named by a plain file name, got {self.name!r}")


Block = Heading | Paragraph | Bullets | Table | Figure


def _flat(text: str) -> str:
    """One line: runs of white space (line breaks included) become one space."""
    return re.sub(r"\s+", " ", text)


# --------------------------------------------------------------------------- Markdown

#: Characters escaped everywhere in Markdown text (CommonMark escapes any ASCII punctuation with a
#: backslash): emphasis, code, links and images, raw HTML and entities, table cells,
#: strikethrough, math, and headings' closing sequences.
_MD_SPECIAL = re.compile(r"([\\`*_\[\]<>&|~$#])")
#: GitHub's extended autolinks make a live link of ``scheme://...`` and ``www....`` in text: the
#: colon before ``//`` and the dot after ``www`` are escaped (``http\\://`` is not autolinked).
_MD_AUTOLINK = re.compile(r"(?i)(:)(?=//)|(?<=\bwww)(\.)")
#: Line starts that would open a block: lists (``-``, ``+``), thematic breaks and setext
#: underlines (``-``, ``=``), and ordered lists (``1.``, ``1)``).
_MD_BULLET_START = re.compile(r"^([-+=])")
_MD_NUMBER_START = re.compile(r"^(\d+)([.)])")


def _md_text(text: str, *, line_start: bool = False) -> str:
    escaped = _MD_AUTOLINK.sub(lambda m: "\\" + m.group(0), _MD_SPECIAL.sub(r"\\\1", _flat(text)))
    if line_start:
        escaped = _MD_NUMBER_START.sub(r"\1\\\2", _MD_BULLET_START.sub(r"\\\1", escaped))
    return escaped


def _md_code(text: str) -> str:
    flat = _flat(text)
    fence = "`" * (max((len(run) for run in re.findall(r"`+", flat)), default=0) + 1)
    pad = " " if flat.startswith("`") or flat.endswith("`") else ""
    return f"{fence}{pad}{flat}{pad}{fence}"


def _md_inline(content: Sequence[Inline]) -> str:
    """A run of inline content; white space at its ends dropped (it could open a code block or
    hide a list marker)."""
    content = _trimmed(content)
    parts = []
    for i, piece in enumerate(content):
        if isinstance(piece, Span):
            if piece.style == "code":
                parts.append(_md_code(piece.text))
            else:
                mark = "*" if piece.style == "em" else "**"
                parts.append(f"{mark}{_md_text(piece.text)}{mark}")
        else:
            parts.append(_md_text(piece, line_start=i == 0))
    return "".join(parts)


def _trimmed(content: Sequence[Inline]) -> list[Inline]:
    """The content without white space before its first and after its last character."""
    pieces = list(content)
    for index, strip in ((0, str.lstrip), (-1, str.rstrip)):
        if pieces:
            piece = pieces[index]
            pieces[index] = Span(strip(piece.text), piece.style) if isinstance(piece, Span) else strip(piece)
    return pieces


def to_markdown(blocks: Iterable[Block]) -> str:
    """The document as Markdown (CommonMark with GitHub's tables); figures as relative links."""
    out: list[str] = []
    for block in blocks:
        if isinstance(block, Heading):
            out.append(f"{'#' * block.level} {_md_inline(block.content)}")
        elif isinstance(block, Paragraph):
            out.append(_md_inline(block.content))
        elif isinstance(block, Bullets):
            out.append("\n".join(f"- {_md_inline(item)}" for item in block.items))
        elif isinstance(block, Table):
            lines = [
                "| " + " | ".join(_md_text(c.strip()) for c in block.header) + " |",
                "|" + "|".join("---" for _ in block.header) + "|",
            ]
            lines += ["| " + " | ".join(_md_text(c.strip()) for c in row) + " |" for row in block.rows]
            out.append("\n".join(lines))
        elif isinstance(block, Figure):
            out.append(f"![{_md_text(block.caption.strip())}](figures/{block.name}.png)")
    return "\n\n".join(out) + "\n"


# --------------------------------------------------------------------------- HTML

_HTML_TAGS = {"em": "em", "strong": "strong", "code": "code"}
_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem; line-height: 1.45; }
table { border-collapse: collapse; margin: 0.5rem 0; } td, th { border: 1px solid #ccc; padding: 0.2rem 0.5rem; }
th { background: #f3f3f3; } img { max-width: 100%; } li { margin: 0.2rem 0; } figure { margin: 1rem 0; }
figcaption { color: #555; font-size: 0.9rem; }
"""
#: No script, no remote resource, no form, no frame: the page may only show itself and its
#: embedded images.
_POLICY = "default-src 'none'; img-src data:; style-src 'unsafe-inline'; base-uri 'none'; form-action 'none'"
#: The largest figure file embedded (bytes).
_MAX_FIGURE = 50 << 20


def _h(text: str) -> str:
    return html.escape(_flat(text), quote=True)


def _cell(text: str) -> str:
    return _h(text.strip())


def _html_inline(content: Sequence[Inline]) -> str:
    content = _trimmed(content)
    return "".join(
        f"<{_HTML_TAGS[p.style]}>{_h(p.text)}</{_HTML_TAGS[p.style]}>" if isinstance(p, Span) else _h(p)
        for p in content
    )


def _figure_data(folder: Path, name: str) -> str | None:
    """The PNG ``folder/figures/<name>.png`` as base64, if it is a regular file of ours."""
    path = folder / "figures" / f"{name}.png"
    if path.parent.is_symlink():  # a folder of figures elsewhere: none is ours
        return None
    try:
        info = os.lstat(path)
    except OSError:
        return None
    if not stat.S_ISREG(info.st_mode) or info.st_size > _MAX_FIGURE:  # never follow a planted link
        return None
    data = path.read_bytes()
    return base64.b64encode(data).decode("ascii") if data.startswith(b"\x89PNG\r\n\x1a\n") else None


def html_fragment(blocks: Iterable[Block], *, folder: Path | None = None) -> str:
    """The blocks as HTML elements (no page around them); figures from ``folder``, if given."""
    body: list[str] = []
    for block in blocks:
        if isinstance(block, Heading):
            body.append(f"<h{block.level}>{_html_inline(block.content)}</h{block.level}>")
        elif isinstance(block, Paragraph):
            body.append(f"<p>{_html_inline(block.content)}</p>")
        elif isinstance(block, Bullets):
            items = "".join(f"<li>{_html_inline(item)}</li>" for item in block.items)
            body.append(f"<ul>{items}</ul>")
        elif isinstance(block, Table):
            head = "".join(f"<th>{_cell(c)}</th>" for c in block.header)
            rows = "".join("<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in row) + "</tr>" for row in block.rows)
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>")
        elif isinstance(block, Figure):
            data = None if folder is None else _figure_data(folder, block.name)
            if data is None:
                body.append(f"<p><em>(figure {_h(block.name)} missing)</em></p>")
            else:
                body.append(
                    f'<figure><img src="data:image/png;base64,{data}" alt="{_h(block.caption)}">'
                    f"<figcaption>{_h(block.caption)}</figcaption></figure>"
                )
    return "\n".join(body)


def to_html(blocks: Iterable[Block], *, folder: Path, title: str) -> str:
    """One self-contained HTML page; the run folder's figures embedded as data URIs."""
    body = html_fragment(blocks, folder=folder)
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{_POLICY}">'
        f"<title>{_cell(title)}</title><style>{_STYLE}</style></head><body>\n" + body + "\n</body></html>\n"
    )
