"""A format-neutral document (sections of paragraphs, bullet lists, tables, figures) and the
number formatting shared by the Markdown and HTML renderers (pure)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Cell:
    text: str
    shade: float | None = None
    """Heat in [0, 1] for the paper's shaded tables (HTML background); None: plain."""
    bold: bool = False


@dataclass(frozen=True)
class Table:
    table_id: str
    """Stable id (HTML ``id``; tests look tables up by it)."""
    caption: str
    header: tuple[str, ...]
    rows: tuple[tuple[Cell, ...], ...]


@dataclass(frozen=True)
class Paragraph:
    text: str


@dataclass(frozen=True)
class Bullets:
    items: tuple[str, ...]


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
    blocks: tuple[Block, ...]


@dataclass(frozen=True)
class Document:
    title: str
    sections: tuple[Section, ...]


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
    if p < 1e-3:
        return f"{p:.1e}"
    return f"{p:.3f}"


def mean_sd(mean: float | None, sd: float | None, *, scale: float = 1.0, digits: int = 1) -> str:
    """``59.4 ± 23.9`` (``scale=100`` for fractions shown in %); sd omitted when None."""
    if mean is None:
        return "n/a"
    if sd is None:
        return f"{mean * scale:.{digits}f}"
    return f"{mean * scale:.{digits}f} ± {sd * scale:.{digits}f}"
