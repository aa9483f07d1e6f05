"""Which episodes of a session are live, and node ids back to EMRD parameters."""

from __future__ import annotations

from pytest_emrd.preflight import live_grid, params_of_node_ids
from pytest_emrd.trajectory import EpisodeSpec

SPECS = [EpisodeSpec("gpt", "baseline", "office", i) for i in range(3)]


def test_live_grid_leaves_out_cassettes_and_stored_episodes(tmp_path):
    recorded = tmp_path / "gpt" / "baseline" / "default" / "office" / "ep00.json.xz"
    recorded.parent.mkdir(parents=True)
    recorded.write_bytes(b"")
    grid = live_grid(
        SPECS + SPECS, cassettes=tmp_path, record_mode="once", holds=lambda s: s.episode == 1
    )
    assert grid == {"gpt": [SPECS[2]]}
    assert live_grid(SPECS, cassettes=tmp_path, record_mode="none", holds=lambda s: False) == {}
    everything = live_grid(SPECS, cassettes=tmp_path, record_mode="all", holds=lambda s: False)
    assert everything == {"gpt": SPECS}


def test_node_ids_map_back_to_specs_and_cells_without_touching_other_sessions():
    table = {s.case_id: s for s in SPECS} | {"gpt-baseline-aec": "cell"}
    ids = [
        "test_emrd.py::test_episode[gpt-baseline-office-ep02]",
        "test_emrd.py::test_gate[gpt-baseline-aec]",
        "test_mine.py::test_fast[gpt-baseline-office-ep00-fast]",
        "test_other.py::test_plain",
    ]
    assert params_of_node_ids(ids, lambda: table) == [SPECS[2], "cell", SPECS[0]]

    def untouched() -> dict:
        raise AssertionError("no EMRD-shaped id: the registry is never loaded")

    assert params_of_node_ids(["t.py::test_x[1-2]", "t.py::test_y"], untouched) == []
