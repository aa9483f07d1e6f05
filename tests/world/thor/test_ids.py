"""The THOR-id <-> EMRD-id table."""

from __future__ import annotations

import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.world.thor import IdTable


def test_table_maps_thor_ids_to_ours() -> None:
    table = IdTable({"Desk|1|0": "Desk_1", "door|1|2": "Doorway_1"})
    assert table.emrd("door|1|2") == "Doorway_1"
    assert table.emrd("Desk|1|0") == "Desk_1"
    assert table.emrd("Floor|1") is None


@pytest.mark.parametrize(
    "house",
    [{}, {"metadata": {}}, {"metadata": {"emrd": {}}}, {"metadata": None}],
    ids=["no-metadata", "no-emrd", "no-ids", "metadata-null"],
)
def test_house_without_table_is_rejected(house: dict) -> None:
    with pytest.raises(ConfigError, match="build_house"):
        IdTable.from_house(house)


def test_two_thor_objects_for_one_emrd_id_is_rejected() -> None:
    with pytest.raises(ConfigError, match="two THOR objects"):
        IdTable({"Desk|1|0": "Desk_1", "Desk|1|1": "Desk_1"})
