"""Render a :class:`Document` as GitHub-flavoured Markdown (pure text)."""

from __future__ import annotations

from pytest_emrd.report._document import Bullets, Cell, Document, FigureRef, Paragraph, Table


def _cell(c: Cell) -> str:
    text = c.text.replace("|", "\\|").replace("\n", " ")
    return f"**{text}**" if c.bold and text else text


def _table(t: Table) -> list[str]:
    lines = [f"*{t.caption}*", ""]
    lines.append("| " + " | ".join(h.replace("|", "\\|") for h in t.header) + " |")
    lines.append("|" + "|".join([" --- "] * len(t.header)) + "|")
    lines += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in t.rows]
    if not t.rows:
        lines.append("| " + " | ".join(["—"] * len(t.header)) + " |")
    return lines


def _figure(f: FigureRef) -> list[str]:
    if f.missing is not None:
        return [f"**{f.title}**: not drawn ({f.missing})."]
    return [f"![{f.title}]({f.name})", "", f"*{f.title}.* {f.caption}"]


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
                lines += _table(block)
            else:
                lines += _figure(block)
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"
