"""Live progress: each step and retry of a running episode, as it happens.

* :class:`EpisodeWatch` -- around one episode: logs each step on the ``pytest_emrd``
  logger (``pytest --log-cli-level=INFO`` shows them), counts retries from their log
  records, and publishes a live episode's state to its process's :class:`StatusFile`.
* :class:`LiveBoard` / :class:`Ticker` -- on the controller: one concise live line from
  every worker's status file.

Only observation: what the model is sent, and every trajectory, stay exactly the same.
"""

from pytest_emrd.progress._board import LiveBoard, Ticker, render_line
from pytest_emrd.progress._status import StatusFile, WorkerStatus, read_statuses, worker_name
from pytest_emrd.progress._watch import EpisodeWatch, run_watched, watch_episode

__all__ = [
    "EpisodeWatch",
    "LiveBoard",
    "StatusFile",
    "Ticker",
    "WorkerStatus",
    "read_statuses",
    "render_line",
    "run_watched",
    "watch_episode",
    "worker_name",
]
