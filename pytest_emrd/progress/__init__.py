"""Live progress of running episodes: step logs, retry counts, the controller's live line."""

from pytest_emrd.progress._live import (
    LiveBoard,
    StatusFile,
    Ticker,
    read_statuses,
    render_line,
    run_watched,
    watch_episode,
)

__all__ = [
    "LiveBoard",
    "StatusFile",
    "Ticker",
    "read_statuses",
    "render_line",
    "run_watched",
    "watch_episode",
]
