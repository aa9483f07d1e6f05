"""Episode summaries: tokens, cost from registry prices, progress lines, usage per model."""

from __future__ import annotations

from pytest_emrd.run import EpisodeSummary, StoredEpisode, usage_rows
from pytest_emrd.trajectory import EpisodeSpec

from .conftest import make_trajectory


def _summary(model: str, price: float | None) -> EpisodeSummary:
    stored = StoredEpisode.of(
        make_trajectory(EpisodeSpec(model, "baseline", "office", 0)),
        session="s",
        recorded=True,
        frame_drift=0,
        seconds=1.25,
    )
    return EpisodeSummary.of(stored, price_in=price, price_out=price)


def test_summary_round_trips_and_prints_one_progress_line():
    s = _summary("gpt", 2.0)
    assert EpisodeSummary.from_dict(s.to_dict()) == s
    assert s.progress_line(3) == (
        "emrd [3] gpt-baseline-office-ep00: budget after 0 steps, chose -, 0 tokens, $0.000, 1.2 s"
    )


def test_usage_rows_add_up_and_lose_the_cost_when_a_price_is_unknown():
    rows = usage_rows([_summary("gpt", 2.0), _summary("gpt", 2.0), _summary("scout", None)])
    assert [(r.model, r.episodes, r.cost_usd) for r in rows] == [
        ("gpt", 2, 0.0),
        ("scout", 1, None),
    ]
