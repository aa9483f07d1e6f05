"""Terminal tables: gate verdicts per model, token usage and cost per model (pure text)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from pytest_emrd.gate._verdict import Verdict, format_number


@dataclass(frozen=True)
class UsageRow:
    """Token usage of one model's episodes in a run."""

    model: str
    episodes: int
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float | None
    """Estimated cost from the registry's prices, ``None`` when it has none."""
    retries: int = 0
    errors: int = 0
    """Episodes that ended ``errored``."""

    def cells(self) -> tuple[str, ...]:
        """Model, episodes, prompt and completion tokens and the cost as usage tables print
        them (``n/a`` without a price)."""
        cost = "n/a" if self.cost_usd is None else f"${self.cost_usd:,.2f}"
        tokens = f"{self.prompt_tokens:,}", f"{self.completion_tokens:,}"
        return (self.model, str(self.episodes), *tokens, cost)


def render_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """Left-aligned columns two spaces apart, header first (trailing spaces stripped).

    :param header: The column titles.
    :param rows: The cells, row by row.
    :returns: The table's lines.
    """
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    line = "  ".join(f"{{:<{w}}}" for w in widths)
    return [line.format(*header).rstrip(), *(line.format(*r).rstrip() for r in rows)]


def gate_tables(verdicts: Sequence[Verdict]) -> list[str]:
    """One table per model: condition x metric, value, CI, n, bound, PASS/FAIL.

    :param verdicts: The verdicts to print.
    :returns: The tables' lines, Markdown.
    """
    lines: list[str] = []
    for model in sorted({v.model for v in verdicts}):
        mine = sorted(
            (v for v in verdicts if v.model == model),
            key=lambda v: (v.layouts != "paper", v.condition, v.variant, v.metric),
        )
        lines.append(f"{model}: {sum(v.passed for v in mine)}/{len(mine)} gates pass")
        rows = [
            [
                v.cell_label,
                v.metric,
                format_number(v.value),
                f"[{format_number(v.ci_low)}, {format_number(v.ci_high)}]",
                str(v.n),
                v.bound_text,
                "PASS" if v.passed else "FAIL",
            ]
            for v in mine
        ]
        header = ["condition", "metric", "value", "95% CI", "n", "bound", "result"]
        lines += ["  " + r for r in render_table(header, rows)]
        for v in (v for v in mine if not v.passed):
            lines += [f"  FAIL {v.gate_id}: {v.reason}", *(f"    {e}" for e in v.evidence())]
    return lines


def usage_table(rows: Sequence[UsageRow]) -> list[str]:
    """Tokens, estimated cost where known, retries and errored episodes per model.

    :param rows: One :class:`UsageRow` per model.
    :returns: The table's lines, Markdown.
    """
    body = [
        [*r.cells(), str(r.retries), str(r.errors)] for r in sorted(rows, key=lambda r: r.model)
    ]
    header = ["model", "episodes", "prompt tokens", "completion tokens", "est. cost"]
    header += ["retries", "errored"]
    return ["  " + r for r in render_table(header, body)]
