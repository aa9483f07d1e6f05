"""Most representative terminal reasoning (paper Table "Most Representative Terminal Reasoning")."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics._embedding import minilm_embed

Embed = Callable[[Sequence[str]], np.ndarray]


@dataclass(frozen=True)
class Representative:
    """The statement closest to the semantic centroid of a group of rationales."""

    statement: str | None
    """Closest to the centroid; None when there was no rationale."""
    index: int | None
    """Its position in the input."""
    mean_cosine_distance: float | None
    """``d-bar``: mean cosine distance of the statements to the centroid (cohesion)."""
    n: int
    """Rationales used (blank and missing ones are skipped)."""
    skipped: int


def representative_reasoning(
    rationales: Sequence[str | None], *, embed: Embed | None = None
) -> Representative:
    r"""Pick the rationale closest to the centroid of all rationales' embeddings.

    Each text is embedded (default: all-MiniLM-L6-v2 from the ``nlp`` extra, offline) and
    L2-normalised; the centroid is the mean of the unit vectors;

    .. math::
        d_j = 1 - \frac{e_j \cdot \bar{e}}{\|e_j\|\,\|\bar{e}\|}, \qquad
        \bar{d} = \frac{1}{n} \sum_j d_j

    The representative statement minimises ``d_j`` (first one on ties); ``d-bar`` measures
    cohesion (lower = more homogeneous). ``embed`` maps ``n`` texts to an ``(n, k)`` array, so
    the centroid logic runs without torch. Edge cases: None or blank rationales are skipped
    and counted; none left gives a result with ``statement`` None; one gives it with
    ``d-bar = 0``; a zero embedding vector, or a zero centroid (opposite vectors), raises
    ConfigError since cosine distance is undefined. Without the extra and without ``embed``:
    MissingExtraError carrying the pip command.

    :param rationales: One rationale per episode, None where it gave none.
    :param embed: Texts -> ``(n, k)`` embeddings; None for the ``nlp`` extra's encoder.
    :returns: A :class:`Representative`: the statement, its index, ``d-bar`` and the skipped count.
    """
    kept = [(i, r) for i, r in enumerate(rationales) if r is not None and r.strip()]
    skipped = len(rationales) - len(kept)
    if not kept:
        return Representative(None, None, None, 0, skipped)
    vectors = np.asarray((embed or minilm_embed)([r for _, r in kept]), dtype=float)
    if vectors.ndim != 2 or vectors.shape[0] != len(kept):
        raise ConfigError(
            f"embed returned shape={vectors.shape}; it must return one row per text "
            f"({len(kept)} rows)."
        )
    norms = np.linalg.norm(vectors, axis=1)
    if np.any(norms == 0) or not np.all(np.isfinite(vectors)):
        raise ConfigError(
            "embed returned a zero or non-finite vector: cosine distance is undefined."
        )
    unit = vectors / norms[:, None]
    centroid = unit.mean(axis=0)
    c_norm = float(np.linalg.norm(centroid))
    if c_norm <= 1e-12:
        raise ConfigError("the embeddings cancel out (zero centroid): no representative exists.")
    distances = 1.0 - unit @ (centroid / c_norm)
    best = int(np.argmin(np.round(distances, 12)))
    return Representative(
        kept[best][1], kept[best][0], float(np.clip(distances, 0.0, 2.0).mean()), len(kept), skipped
    )
