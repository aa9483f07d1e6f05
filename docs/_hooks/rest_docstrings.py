"""Griffe extension: the package's reST docstrings read as Markdown by mkdocstrings.

The docstrings follow Sphinx conventions (``.. math::`` blocks, ``:func:`name``` roles), as
the house style asks; the site renders Markdown with MathJax (``pymdownx.arithmatex``).
Every docstring is rewritten once when griffe loads it: a ``.. math::`` block becomes a
``$$ ... $$`` display, ``:math:`x``` becomes ``$x$`` and a cross-reference role becomes the
code span of its last dotted part (``:func:`~pytest_emrd.metrics.match_map``` -> ``match_map``).
"""

from __future__ import annotations

import re
import textwrap
from typing import Any

import griffe

_MATH_BLOCK = re.compile(
    r"^(?P<indent>[ \t]*)\.\. math::[ \t]*\n(?P<body>(?:(?P=indent)[ \t]+\S.*\n|[ \t]*\n)+)",
    re.MULTILINE,
)
_MATH_ROLE = re.compile(r":math:`([^`]+)`")
_REF_ROLE = re.compile(r":(?:py:)?(?:func|class|data|attr|meth|mod|obj|exc|const):`~?([^`]+)`")


def _display(match: re.Match[str]) -> str:
    indent = match["indent"]
    body = textwrap.dedent(match["body"]).strip("\n")
    return f"{indent}$$\n{textwrap.indent(body, indent)}\n{indent}$$\n\n"


def markdown(docstring: str) -> str:
    """``docstring`` with its reST math and cross-reference roles written as Markdown."""
    text = _MATH_BLOCK.sub(_display, docstring if docstring.endswith("\n") else docstring + "\n")
    text = _MATH_ROLE.sub(r"$\1$", text)
    return _REF_ROLE.sub(lambda m: f"`{m[1].rsplit('.', 1)[-1]}`", text).rstrip("\n")


class RestDocstrings(griffe.Extension):
    """Rewrite each object's docstring with :func:`markdown` as it is loaded."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
