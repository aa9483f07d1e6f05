"""Every entry counts (issue 34): same-label copies and invented instances of present types."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import (
    hallucination_score,
    match_map,
    positional_accuracy_score,
    precision_score,
)
from pytest_emrd.trajectory import GroundTruthObject, MapEntry
from pytest_emrd.world import paper_office

OFFICE = [
    GroundTruthObject(o.object_id, o.object_type, o.room, o.category, o.x, o.z)
    for o in paper_office().objects
]


def _far_copy(o: GroundTruthObject, rng: np.random.Generator) -> MapEntry:
    """An entry labelled by ``o``'s id, 3-8 m from ``o``, in a random direction."""
    angle, distance = rng.uniform(0, 2 * np.pi), rng.uniform(3, 8)
    x, z = o.x + distance * np.cos(angle), o.z + distance * np.sin(angle)
    return MapEntry(o.object_id, o.object_type, float(x), float(z))


@pytest.mark.parametrize("copies_first", [False, True], ids=["copies-after", "copies-first"])
def test_same_label_garbage_copies_lower_precision_and_pa(copies_first: bool) -> None:
    rng = np.random.default_rng(34)
    written: list[MapEntry] = []
    for o in OFFICE:
        true, copy = MapEntry(o.object_id, o.object_type, o.x, o.z), _far_copy(o, rng)
        written += [copy, true] if copies_first else [true, copy]
    m = match_map(written, OFFICE)
    assert m.entries == 2 * len(OFFICE)
    assert m.duplicates == tuple(sorted(o.object_id for o in OFFICE))
    assert precision_score(m) <= 0.6
    assert positional_accuracy_score(m, len(OFFICE)) < 0.9


def test_a_copy_is_an_entry_of_its_own_and_aec_counts_the_label_once() -> None:
    truth = [
        GroundTruthObject("Chair_1", "Chair", "Office", "salient", 0, 0),
        GroundTruthObject("Chair_2", "Chair", "Office", "salient", 3, 0),
    ]
    written = [MapEntry("chair", "Chair", 0, 0), MapEntry("chair", "Chair", 3, 0)]
    m = match_map(written, truth)
    assert m.label_of == {"Chair_1": "chair", "Chair_2": "chair #2"}
    assert m.covered == 1  # Eq. AEC: |M_k| counts distinct labels ("unique recorded instances")
    assert precision_score(m) == 1.0


def test_a_grid_of_every_type_is_nearly_all_hallucination() -> None:
    types = sorted({o.object_type for o in OFFICE})
    xs, zs = [o.x for o in OFFICE], [o.z for o in OFFICE]
    grid = [
        (x, z) for x in np.linspace(min(xs), max(xs), 9) for z in np.linspace(min(zs), max(zs), 7)
    ]
    written = [
        MapEntry(f"{t} {i}", t, float(x), float(z)) for t in types for i, (x, z) in enumerate(grid)
    ]
    m = match_map(written, OFFICE)
    assert len(written) == 1008
    assert hallucination_score(m) >= 0.9
    assert precision_score(m) + hallucination_score(m) == pytest.approx(1.0)


@given(st.integers(1, 5), st.floats(6.0, 30.0), st.floats(0, 2 * np.pi))
def test_an_invented_instance_of_a_present_type_is_a_hallucination(
    n: int, distance: float, angle: float
) -> None:
    exact = [MapEntry(o.object_id, o.object_type, o.x, o.z) for o in OFFICE]
    fridge = next(o for o in OFFICE if o.object_type == "Fridge")
    x, z = fridge.x + distance * np.cos(angle), fridge.z + distance * np.sin(angle)
    invented = [MapEntry(f"fridge {i}", "Fridge", float(x), float(z)) for i in range(n)]
    m = match_map(exact + invented, OFFICE)
    assert hallucination_score(m) == pytest.approx(n / (len(OFFICE) + n))
