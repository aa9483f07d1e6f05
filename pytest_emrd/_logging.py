"""Logger names and log-record attributes the package shares (no handlers are installed).

Everything logs under the ``pytest_emrd`` logger: ``pytest --log-cli-level=INFO`` shows
each step of a live episode as it happens, and retries at WARNING. A record that reports
one retry of a model request carries the attribute :data:`RETRY_ATTR` (the 1-based retry
number), which is how :mod:`pytest_emrd.progress` counts retries per episode.
"""

from __future__ import annotations

from typing import Final

ROOT_LOGGER: Final = "pytest_emrd"
RETRY_ATTR: Final = "emrd_retry"
