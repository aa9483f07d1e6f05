"""Logger names and log-record attributes the package shares (no handlers are installed).

Everything logs under the ``pytest_emrd`` logger (``--log-cli-level=INFO`` shows each live
step, retries at WARNING). A record of one retry carries :data:`RETRY_ATTR` (the 1-based
retry number), by which :mod:`pytest_emrd.progress` counts retries per episode.
"""

from __future__ import annotations

from typing import Final

ROOT_LOGGER: Final = "pytest_emrd"
RETRY_ATTR: Final = "emrd_retry"
