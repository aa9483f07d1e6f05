"""SIR's copies kernel gives the bits of the numpy and scipy expressions it replaces.

Oracles: the expressions of :func:`_meant_numpy` (what ``reentry_copies`` computed with numpy
and scipy) and the whole of ``reentry_copies`` as it was written with them
(:func:`_copies_numpy`), on random groups and on every re-entry of the synthetic grid.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from pytest_emrd.metrics import _copies, rigid_fit
from pytest_emrd.metrics._align import COINCIDENT_M, layout_of
from pytest_emrd.metrics._scores import Office, new_entries, reentry_copies
from pytest_emrd.metrics._tracking import track_episode
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.trajectory import Trajectory

coord = st.sampled_from([k / 2 for k in range(-6, 7)]) | st.floats(-40, 40)
point = st.tuples(coord, coord)


def _meant_numpy(
    pred: np.ndarray, true: np.ndarray, groups: list[np.ndarray], spots: list[np.ndarray], dec: int
) -> tuple[int, list[int]]:
    """The numpy and scipy expressions: outcome, and per new entry its index within its
    group's objects."""
    with np.errstate(all="ignore"):
        return _meant_numpy_quiet(pred, true, groups, spots, dec)


def _meant_numpy_quiet(
    pred: np.ndarray, true: np.ndarray, groups: list[np.ndarray], spots: list[np.ndarray], dec: int
) -> tuple[int, list[int]]:
    if float(np.max(np.hypot(*(pred - pred[0]).T))) <= COINCIDENT_M:
        return _copies.COINCIDENT, []
    rotation, shift = rigid_fit(pred, true)
    found: list[int] = []
    for written, spot in zip(groups, spots, strict=True):
        where = written @ rotation.T + shift
        cost = np.round(((where[:, None, :] - spot[None, :, :]) ** 2).sum(axis=2), dec)
        try:
            rows, cols = linear_sum_assignment(cost)
        except ValueError as exc:
            invalid = "invalid" in str(exc)
            return (_copies.INVALID if invalid else _copies.INFEASIBLE), []
        meant = dict(zip(rows.tolist(), cols.tolist(), strict=True))
        found += [meant[r] if r in meant else int(np.argmin(cost[r])) for r in range(len(written))]
    return _copies.OK, found


@st.composite
def cases(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]]:
    k = draw(st.integers(2, 8))
    pred = np.array([draw(point) for _ in range(k)])
    true = np.array([draw(point) for _ in range(k)])
    n_types = draw(st.integers(1, 4))
    spots = [
        np.array([draw(point) for _ in range(draw(st.integers(1, 5)))]) for _ in range(n_types)
    ]
    groups = [
        np.array([draw(point) for _ in range(draw(st.integers(1, 6)))]) for _ in range(n_types)
    ]
    return pred, true, groups, spots


def _kernel(
    pred: np.ndarray, true: np.ndarray, groups: list[np.ndarray], spots: list[np.ndarray], dec: int
) -> tuple[int, list[int]]:
    kinds = [k for k, g in enumerate(groups) for _ in g]
    points = [tuple(p) for s in spots for p in s.tolist()]
    layout = layout_of(points, [k for k, s in enumerate(spots) for _ in s], 1.0)
    outcome, found = _copies.meant(
        pred, true, np.concatenate(groups), np.array(kinds, dtype=np.intp),
        layout.starts, layout.cols, layout.true, dec, COINCIDENT_M,
    )  # fmt: skip
    first = layout.starts[np.array(kinds, dtype=np.intp)]
    return int(outcome), (found - first).tolist() if outcome == _copies.OK else []


@given(cases(), st.sampled_from([5, 7, 9]))
def test_meant_is_the_numpy_and_scipy_expression(
    case: tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]], dec: int
) -> None:
    assert _kernel(*case, dec) == _meant_numpy(*case, dec)


@given(cases(), st.sampled_from([math.inf, -math.inf, math.nan, 1e200]), st.integers(0, 3))
def test_meant_of_points_not_finite_or_huge_is_what_scipy_decides(
    case: tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]],
    bad: float,
    where: int,
) -> None:
    pred, true, groups, spots = case
    target = (pred, true, groups[0], spots[0])[where]
    target[0, 0] = bad
    assert _kernel(pred, true, groups, spots, 7) == _meant_numpy(pred, true, groups, spots, 7)


def test_one_row_and_several_rows_move_as_blas_does() -> None:
    # dgemv (one row) and dgemm (two or more) fuse different products of ``points @ R.T``
    rng = np.random.default_rng(7)
    for rows in (1, 2, 3):
        for _ in range(200):
            theta = rng.uniform(0, 2 * math.pi)
            c, s = math.cos(theta), math.sin(theta)
            points = rng.normal(size=(rows, 2)) * 30
            want = (points @ np.array([[c, -s], [s, c]]).T).tolist()
            assert [list(_copies._moved(x, z, c, s, rows)) for x, z in points.tolist()] == want


def _copies_numpy(
    traj: Trajectory, held: tuple[dict[str, str], ...], start: int, end: int
) -> set[str]:
    """``reentry_copies`` as written with numpy and scipy."""
    office = Office.of(traj)
    entries, by_type = new_entries(traj, office, start, end)
    label_of = held[end]
    if not by_type or len(label_of) < 2:
        return set()
    objects = office.objects
    pairs = sorted(label_of.items())
    pred = np.array([(entries[lb].x, entries[lb].z) for _, lb in pairs], dtype=float)
    true = np.array([(objects[o].x, objects[o].z) for o, _ in pairs], dtype=float)
    ids_of = {k: [o for o in office.ids if office.types.index[objects[o].object_type] == k]
              for k in by_type}  # fmt: skip
    groups = [np.array([(entries[lb].x, entries[lb].z) for lb in by_type[k]]) for k in by_type]
    spots = [np.array([(objects[o].x, objects[o].z) for o in ids_of[k]]) for k in by_type]
    outcome, found = _meant_numpy(pred, true, groups, spots, office.decimals)
    if outcome == _copies.COINCIDENT:
        return set()
    labels = [(k, lb) for k in by_type for lb in by_type[k]]
    return {ids_of[k][j] for (k, lb), j in zip(labels, found, strict=True)
            if ids_of[k][j] in label_of and label_of[ids_of[k][j]] != lb}  # fmt: skip


@pytest.fixture(scope="module")
def reentries() -> list[tuple[Trajectory, tuple[dict[str, str], ...], int, int]]:
    found = []
    for traj in synthetic_grid()[::4]:
        track = track_episode(traj)
        for v in track.visits:
            if v.return_end is not None and v.return_start is not None:
                found.append((traj, track.held, v.return_start, v.return_end))
    return found


def test_reentry_copies_are_those_of_numpy_and_scipy_on_the_synthetic_grid(
    reentries: list[tuple[Trajectory, tuple[dict[str, str], ...], int, int]],
) -> None:
    total = 0
    for traj, held, start, end in reentries:
        got = reentry_copies(traj, Office.of(traj), held, start, end)
        assert got == _copies_numpy(traj, held, start, end)
        total += len(got)
    assert len(reentries) > 50 and total > 0  # re-entries and copies were exercised
