"""A format-neutral document (sections of paragraphs, bullet lists, tables, figures), its
number formatting, and its rendering as GitHub-flavoured Markdown or as one self-contained
HTML page (figures inlined as base64 PNG) (pure text)."""

from __future__ import annotations

import base64
import html
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Cell:
    text: str
    shade: float | None = None
    """Heat in [0, 1] for the paper's shaded tables (HTML background); None: plain."""
    bold: bool = False


Row = Sequence[Cell | str]


@dataclass(frozen=True)
class Table:
    table_id: str
    """Stable id (HTML ``id``; tests look tables up by it)."""
    caption: str
    header: Sequence[str]
    rows: Sequence[Row]


@dataclass(frozen=True)
class Paragraph:
    text: str


@dataclass(frozen=True)
class Bullets:
    items: Sequence[str]


@dataclass(frozen=True)
class FigureRef:
    name: str
    """PNG file name (``tbs.png``)."""
    title: str
    caption: str
    missing: str | None = None
    """Why the figure was not drawn; None when it was."""


Block = Paragraph | Bullets | Table | FigureRef


@dataclass(frozen=True)
class Section:
    anchor: str
    title: str
    blocks: Sequence[Block]


@dataclass(frozen=True)
class Document:
    title: str
    sections: Sequence[Section]


def num(x: float | None, digits: int = 3) -> str:
    """Fixed decimals; ``n/a`` for None, ``inf`` for an unbounded value; never ``-0.000`` (a
    negative value that rounds to zero is printed unsigned)."""
    if x is None:
        return "n/a"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    text = f"{x:.{digits}f}"
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text


def pct(x: float | None) -> str:
    """A fraction in [0, 1] as a percentage with one decimal (``59.4``)."""
    return "n/a" if x is None else f"{100 * x:.1f}"


def pval(p: float | None) -> str:
    """p-values: three decimals, or ``< 0.001`` / scientific below that."""
    if p is None:
        return "n/a"
    return f"{p:.1e}" if p < 1e-3 else f"{p:.3f}"


def mean_sd(mean: float | None, sd: float | None, *, scale: float = 1.0, digits: int = 1) -> str:
    """``59.4 ± 23.9`` (``scale=100`` for fractions shown in %); sd omitted when None."""
    if mean is None:
        return "n/a"
    shown = f"{mean * scale:.{digits}f}"
    return shown if sd is None else f"{shown} ± {sd * scale:.{digits}f}"


def _md_cell(c: Cell | str) -> str:
    c = Cell(c) if isinstance(c, str) else c
    text = c.text.replace("|", "\\|").replace("\n", " ")
    return f"**{text}**" if c.bold and text else text


def _md_row(cells: Iterable[str]) -> str:
    return f"| {' | '.join(cells)} |"


def _md_table(t: Table) -> list[str]:
    rule = "|".join([" --- "] * len(t.header))
    rows = [_md_row(map(_md_cell, row)) for row in t.rows] or [_md_row(["—"] * len(t.header))]
    return [f"*{t.caption}*", "", _md_row(map(_md_cell, t.header)), f"|{rule}|", *rows]


def render_markdown(doc: Document) -> str:
    """Markdown of ``doc``; figures link to their PNG file names (same folder)."""
    lines = [f"# {doc.title}", ""]
    for section in doc.sections:
        lines += [f"## {section.title}", ""]
        for block in section.blocks:
            if isinstance(block, Paragraph):
                lines.append(block.text)
            elif isinstance(block, Bullets):
                lines += [f"- {item}" for item in block.items]
            elif isinstance(block, Table):
                lines += _md_table(block)
            elif block.missing is not None:
                lines.append(f"**{block.title}**: not drawn ({block.missing}).")
            else:
                lines += [
                    f"![{block.title}]({block.name})",
                    "",
                    f"*{block.title}.* {block.caption}",
                ]
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"


_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 2rem auto;
       max-width: 1200px; color: #222; line-height: 1.4; }
h1 { border-bottom: 2px solid #1f5fbf; padding-bottom: .3rem; }
h2 { margin-top: 2.2rem; border-bottom: 1px solid #ddd; }
nav a { margin-right: 1rem; }
table { border-collapse: collapse; margin: .6rem 0 1.4rem; font-size: .88rem; }
caption { caption-side: top; text-align: left; font-style: italic; padding: .3rem 0; }
th, td { border: 1px solid #ccc; padding: .25rem .5rem; text-align: right; }
th { background: #f0f3f8; }
td:first-child, th:first-child { text-align: left; }
td.strong { font-weight: bold; }
td.text { text-align: left; }
#figures { display: grid; grid-template-columns: repeat(auto-fill, minmax(540px, 1fr));
           gap: 0 1.5rem; align-items: start; }
#figures h2 { grid-column: 1 / -1; }
figure { margin: 1rem 0 2rem; }
figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: .9rem; color: #555; }
.missing { color: #8a5a00; }
"""


def _inline(text: str) -> str:
    return re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", html.escape(text))


_NUMERIC = re.compile(r"^([-+]?[\d.$\[]|n/a$|—$|-?inf)")


def _td(c: Cell | str) -> str:
    c = Cell(c) if isinstance(c, str) else c
    classes = [] if _NUMERIC.match(c.text) else ["text"]
    if c.bold:
        classes.append("strong")
    attr = f' class="{" ".join(classes)}"' if classes else ""
    style = ""
    if c.shade is not None and c.shade > 0:
        fg = "#fff" if c.shade > 0.5 else "#000"
        style = f' style="background: rgba(31, 95, 191, {c.shade:.2f}); color: {fg}"'
    return f"<td{attr}{style}>{html.escape(c.text)}</td>"


def _html_table(t: Table) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in t.header)
    body = "".join(f"<tr>{''.join(map(_td, row))}</tr>" for row in t.rows)
    return (
        f'<table id="{html.escape(t.table_id)}"><caption>{html.escape(t.caption)}</caption>'
        f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
    )


def _html_figure(f: FigureRef, pngs: Mapping[str, bytes]) -> str:
    title = html.escape(f.title)
    if f.missing is not None or f.name not in pngs:
        why = html.escape(f.missing or "no image")
        return f'<p class="missing"><strong>{title}</strong>: not drawn ({why}).</p>'
    data = base64.b64encode(pngs[f.name]).decode("ascii")
    return (
        f'<figure id="{html.escape(f.name)}"><img src="data:image/png;base64,{data}" '
        f'alt="{title}"><figcaption><strong>{title}.</strong> '
        f"{html.escape(f.caption)}</figcaption></figure>"
    )


def render_html(doc: Document, pngs: Mapping[str, bytes]) -> str:
    """A standalone HTML5 page of ``doc``; every figure is a ``data:`` URI, no external file."""
    nav = " ".join(f'<a href="#{s.anchor}">{html.escape(s.title)}</a>' for s in doc.sections)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(doc.title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(doc.title)}</h1><nav>{nav}</nav>",
    ]
    for section in doc.sections:
        parts.append(f'<section id="{section.anchor}"><h2>{html.escape(section.title)}</h2>')
        for block in section.blocks:
            if isinstance(block, Paragraph):
                parts.append(f"<p>{_inline(block.text)}</p>")
            elif isinstance(block, Bullets):
                items = "".join(f"<li>{_inline(i)}</li>" for i in block.items)
                parts.append(f"<ul>{items}</ul>")
            elif isinstance(block, Table):
                parts.append(_html_table(block))
            else:
                parts.append(_html_figure(block, pngs))
        parts.append("</section>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
