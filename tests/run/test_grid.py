"""The episode grid: explicit sorted ids, and shards that partition it."""

from __future__ import annotations

from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.gate import Bound, Thresholds
from pytest_emrd.run import episode_specs, gate_cells, resolve_settings, shard


def _settings(**cli):
    return resolve_settings(cli, {}, rootdir=Path("/r"), env={})


def test_grid_order_and_ids():
    specs = episode_specs(_settings(model=["scout", "gemini"], episodes="2"), lambda m: "vision")
    assert len(specs) == 2 * 3 * 4 * 2
    assert specs[0].case_id == "gemini-baseline-office-ep00"
    assert specs[1].case_id == "gemini-baseline-office-ep01"
    assert specs[-1].case_id == "scout-texture-entrance-ep01"
    assert len({s.case_id for s in specs}) == len(specs)


def test_registry_modality_applies_unless_overridden():
    assert episode_specs(_settings(episodes="1"), lambda m: "both")[0].modality == "both"
    assert (
        episode_specs(_settings(episodes="1", modality="text"), lambda m: "both")[0].modality
        == "text"
    )


def test_default_grid_is_scout_everywhere_and_mimic_under_baseline():
    specs = episode_specs(_settings(episodes="1"), lambda m: "both")
    cells = sorted({(s.model, s.condition) for s in specs})
    assert cells == [("mimic", "baseline"), ("scout", "baseline"), ("scout", "low_light"),
                     ("scout", "texture")]  # fmt: skip
    assert specs[0].case_id == "mimic-baseline-office-ep00" and len(specs) == 4 * 4


def test_variant_enters_the_ids():
    spec = episode_specs(_settings(episodes="1", variant="B3", model=["scout"]), lambda m: "both")
    assert spec[0].case_id == "scout-baseline-B3-office-ep00"


@given(st.integers(1, 30), st.integers(1, 7))
def test_shards_partition_the_grid(episodes, n):
    specs = episode_specs(_settings(episodes=str(episodes), spawn=["kitchen"]), lambda m: "vision")
    parts = [shard(specs, k, n) for k in range(1, n + 1)]
    assert sorted(s.case_id for p in parts for s in p) == sorted(s.case_id for s in specs)
    assert max(map(len, parts)) - min(map(len, parts)) <= 1


def test_gate_cells_follow_selected_models_and_conditions():
    bounds = (
        Bound("scout", "baseline", "aec", "min", 0.5),
        Bound("scout", "texture", "aec", "min", 0.5),
        Bound("gemini", "baseline", "aec", "min", 0.5),
    )
    cells = gate_cells(_settings(condition=["baseline"]), Thresholds("t", bounds))
    assert [c.gate_id for c in cells] == ["scout-baseline-aec"]


def test_generated_layouts_form_their_own_episodes_and_gate_cells():
    bounds = (
        Bound("scout", "baseline", "aec", "min", 0.9),
        Bound("scout", "baseline", "aec", "min", 0.7, layouts="generated"),
    )
    thresholds = Thresholds("t.yaml", bounds)
    paper = _settings(episodes="1", condition=["baseline"], model=["scout"])
    generated = _settings(
        episodes="1", condition=["baseline"], layouts="generated", model=["scout"]
    )
    spec = episode_specs(generated, lambda m: "both")[0]
    assert spec.layouts == "generated"
    assert spec.case_id == "scout-baseline-generated-office-ep00"
    assert episode_specs(paper, lambda m: "both")[0].case_id == "scout-baseline-office-ep00"
    assert [c.gate_id for c in gate_cells(paper, thresholds)] == ["scout-baseline-aec"]
    assert [c.gate_id for c in gate_cells(generated, thresholds)] == [
        "scout-baseline-generated-aec"
    ]
