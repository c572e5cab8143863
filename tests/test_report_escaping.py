"""User text in reports is text: never HTML, never Markdown, never a path to a file.

A case file full of payloads (script tags, event handlers, ``javascript:`` links, an image path
that climbs out of the run folder, Markdown emphasis and lists, Rich markup) is run through the
command; the rendered ``report.html`` must hold no tag, attribute or URL that the text brought,
and embed the run's own four figures and nothing else; ``report.md``, rendered by a CommonMark
renderer, must show the payloads as text.
"""

import base64
import html
import tomllib
from html.parser import HTMLParser
from pathlib import Path

import pytest
import tomli_w
from hypothesis import given
from hypothesis import strategies as st
from markdown_it import MarkdownIt
from typer.testing import CliRunner

from oscillator import load_case
from oscillator.cli.app import app
from oscillator.io.cases import case_to_toml
from oscillator.report.markup import Bullets, Heading, Paragraph, Span, Table, to_html, to_markdown

TITLE = "<script>alert(1)</script> [l](javascript:alert(2)) **bold** [/nope] $x$"
DESCRIPTION = (
    '<img src=x onerror=alert(3)> <iframe src="javascript:alert(4)"></iframe> '
    "![p](figures/../../../../PLANTED) <a href='javascript:alert(5)'>x</a> &lt;b&gt; \n- a list item\n# a heading\n"
    "see https://evil.example/x, WWW.evil.example and ftp://evil.example/f"
)
LABEL = "<script>alert(6)</script> [/x] bad"
NOTE = "<svg onload=alert(7)> [y](javascript:alert(8)) `code` _em_"
PAYLOADS = (TITLE, LABEL)

#: The tags and attributes the report's HTML may hold: its own, nothing from the text.
ALLOWED_TAGS = {"html", "head", "meta", "title", "style", "body", "h1", "h2", "p", "ul", "li", "table", "thead",
                "tbody", "tr", "th", "td", "em", "strong", "code", "figure", "img", "figcaption"}  # fmt: skip
ALLOWED_ATTRIBUTES = {"html": {"lang"}, "meta": {"charset", "http-equiv", "content"}, "img": {"src", "alt"}}


class Page(HTMLParser):
    """The tags, attributes and text of an HTML page."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []
        self.text: list[str] = []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


@pytest.fixture(scope="module")
def hostile_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hostile-report")
    planted = folder / "planted.png"
    planted.write_bytes(b"\x89PNG\r\n\x1a\n" + b"SECRET-PLANTED-BYTES")
    data = tomllib.loads(case_to_toml(load_case("instance-3")))
    data["title"] = TITLE
    data["description"] = DESCRIPTION.replace("PLANTED", str(planted).lstrip("/"))
    data["expected"][0]["label"] = LABEL
    data["expected"][0]["note"] = NOTE
    path = folder / "<b>hostile<i>.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    out = folder / "run"
    result = CliRunner().invoke(app, ["run", str(path), "--out", str(out)])
    assert result.exit_code == 0, result.stderr
    return out, planted


def test_the_html_report_holds_no_tag_attribute_or_url_from_the_text(hostile_run):
    folder, _ = hostile_run
    page = Page((folder / "report.html").read_text(encoding="utf-8"))
    for tag, attributes in page.tags:
        assert tag in ALLOWED_TAGS, tag
        assert set(attributes) <= ALLOWED_ATTRIBUTES.get(tag, set()), (tag, attributes)
        if tag == "img":
            assert attributes["src"].startswith("data:image/png;base64,")
    text = "".join(page.text)
    for payload in (*PAYLOADS, "<img src=x onerror=alert(3)>", '<iframe src="javascript:alert(4)"></iframe>',
                    "<svg onload=alert(7)>", "<b>hostile<i>"):  # fmt: skip
        assert payload in text, payload  # shown to the reader, as text
    assert "&lt;b&gt;" in text  # an entity in the text is not decoded either


def test_the_html_report_embeds_exactly_the_runs_own_figures(hostile_run):
    folder, planted = hostile_run
    page = Page((folder / "report.html").read_text(encoding="utf-8"))
    embedded = [base64.b64decode(a["src"].split(",", 1)[1]) for tag, a in page.tags if tag == "img"]
    own = sorted((folder / "figures").glob("*.png"))
    assert len(own) == 4 and sorted(embedded) == sorted(p.read_bytes() for p in own)
    assert planted.read_bytes() not in embedded


def test_the_html_report_forbids_scripts_and_remote_resources(hostile_run):
    folder, _ = hostile_run
    (policy,) = [a["content"] for tag, a in Page((folder / "report.html").read_text()).tags
                 if tag == "meta" and a.get("http-equiv") == "Content-Security-Policy"]  # fmt: skip
    assert "default-src 'none'" in policy and "img-src data:" in policy and "script-src" not in policy


def _rendered(markdown: str) -> tuple[list, str]:
    renderer = MarkdownIt("commonmark").enable("table")
    return renderer.parse(markdown), renderer.render(markdown)


def test_the_markdown_report_rendered_by_commonmark_shows_the_text_and_links_nothing(hostile_run):
    folder, _ = hostile_run
    tokens, rendered = _rendered((folder / "report.md").read_text(encoding="utf-8"))
    inline = [child for token in tokens for child in (token.children or [])]
    assert not [t for t in tokens + inline if t.type.startswith("html")]
    assert not [t for t in inline if t.type == "link_open"]
    images = [t.attrGet("src") for t in inline if t.type == "image"]
    assert sorted(images) == sorted(f"figures/{p.name}" for p in (folder / "figures").glob("*.png"))
    text = html.unescape(rendered)
    for payload in (*PAYLOADS, "- a list item # a heading", "**bold**", "`code` _em_"):
        assert payload in text, payload


def test_the_markdown_report_rendered_as_on_github_makes_no_live_link(hostile_run):
    """GitHub's own renderer (cmark-gfm, with its extended autolinks) shows the URLs of a
    description as text: no link to them.  (An e-mail address it links whatever the escapes,
    github/cmark-gfm#278: docs/robustness.md.)"""
    import cmarkgfm

    folder, _ = hostile_run
    rendered = cmarkgfm.github_flavored_markdown_to_html((folder / "report.md").read_text(encoding="utf-8"))
    page = Page(rendered)
    assert not [attributes for tag, attributes in page.tags if tag == "a"]
    text = html.unescape("".join(page.text))
    assert "see https://evil.example/x, WWW.evil.example and ftp://evil.example/f" in text


def test_the_svg_figures_escape_the_case_name(hostile_run):
    folder, _ = hostile_run
    for svg in (folder / "figures").glob("*.svg"):
        assert "<b>" not in svg.read_text(encoding="utf-8"), svg.name


# ----------------------------------------------------------------------------- the writers


#: Text without control characters (a case file cannot hold them).
TEXT = st.text(st.characters(blacklist_categories=("Cc", "Cs")), min_size=1, max_size=80).filter(lambda s: s.split())


@given(text=TEXT)
def test_any_text_comes_out_of_markdown_as_the_same_text(text):
    flat = " ".join(text.split())
    tokens, rendered = _rendered(to_markdown([Paragraph((text,))]))
    assert [t.type for t in tokens] == ["paragraph_open", "inline", "paragraph_close"], (text, tokens)
    assert {child.type for child in tokens[1].children} == {"text"}, tokens[1].children
    assert html.unescape(rendered) == f"<p>{flat}</p>\n"


@given(text=TEXT)
def test_any_text_comes_out_of_every_block_of_html_as_the_same_text(text):
    flat = " ".join(text.split())
    blocks = [Heading(1, (text,)), Paragraph((Span(text, "strong"),)), Bullets(((text,),)), Table((text,), ((text,),))]
    page = Page(to_html(blocks, folder=Path("."), title=text))
    assert {tag for tag, _ in page.tags} <= ALLOWED_TAGS
    assert all(attributes == {} for tag, attributes in page.tags if tag not in ALLOWED_ATTRIBUTES)
    assert [chunk for chunk in page.text if chunk.strip()].count(flat) >= 5  # title, heading, strong, item, th, td


def test_a_figure_is_named_by_the_package_never_by_a_path():
    from oscillator.report.markup import Figure

    for name in ("../x", "figures/../../x", "/etc/passwd", "a b", ""):
        with pytest.raises(ValueError, match="plain file name"):
            Figure(name, "caption")
