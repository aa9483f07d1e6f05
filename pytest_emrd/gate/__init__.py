"""Gates: the thresholds file, per-cell verdicts and the gate table (pure over metrics)."""

from pytest_emrd.gate._files import load_thresholds
from pytest_emrd.gate._starter import starter_thresholds
from pytest_emrd.gate._table import UsageRow, gate_tables, render_table, usage_table
from pytest_emrd.gate._thresholds import Bound, Thresholds, parse_thresholds
from pytest_emrd.gate._verdict import GateCell, Verdict, evaluate_all, evaluate_cell, judge

__all__ = [
    "Bound",
    "GateCell",
    "Thresholds",
    "UsageRow",
    "Verdict",
    "evaluate_all",
    "evaluate_cell",
    "gate_tables",
    "judge",
    "load_thresholds",
    "parse_thresholds",
    "render_table",
    "starter_thresholds",
    "usage_table",
]
