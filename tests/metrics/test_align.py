"""The matcher's float fast paths give numpy's bits: oracles are the numpy expressions they
replace (``pytest_emrd.metrics._align``), so a numpy that sums or rounds differently fails here
before it moves any metric."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics._align import (
    Layout,
    Motion,
    Problem,
    _distance_matrix,
    _nearest,
    _pair_distances,
    assign,
    best_seed,
    moved,
    numpy_sum,
    procrustes,
    round_like_numpy,
)

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
metres = st.floats(-30, 30, allow_nan=False, allow_infinity=False)
point = st.tuples(metres, metres)


def _procrustes_numpy(pred: np.ndarray, true: np.ndarray) -> Motion:
    """The numpy expression :func:`procrustes` reproduces."""
    n = len(pred)
    pc, qc = pred.sum(axis=0) / n, true.sum(axis=0) / n
    a, b = pred - pc, true - qc
    dot = float(np.sum(a * b))
    cross = float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))
    theta = math.atan2(cross, dot) if (dot or cross) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    return Motion(
        c, s, float(qc[0] - (c * pc[0] - s * pc[1])), float(qc[1] - (s * pc[0] + c * pc[1]))
    )


@given(st.lists(finite, max_size=400))
def test_numpy_sum_is_numpys_pairwise_sum(values: list[float]) -> None:
    assert numpy_sum(values) == float(np.add.reduce(np.array(values, dtype=float)))


def test_numpy_sum_of_nothing_and_of_negative_zero_is_zero() -> None:
    assert math.copysign(1.0, numpy_sum([])) == 1.0
    assert math.copysign(1.0, numpy_sum([-0.0])) == math.copysign(1.0, float(np.sum([-0.0])))


@given(st.lists(st.tuples(point, point), min_size=1, max_size=45), st.booleans())
def test_procrustes_on_floats_is_the_numpy_fit_bitwise(
    pairs: list[tuple[tuple[float, float], tuple[float, float]]], coincide: bool
) -> None:
    pred = [p for p, _ in pairs]
    if coincide:
        pred = [pred[0]] * len(pred)
    true = [q for _, q in pairs]
    assert procrustes(pred, true) == _procrustes_numpy(np.array(pred), np.array(true))


@given(st.floats(0, 1e12, allow_nan=False), st.integers(-4, 12))
def test_round_like_numpy_is_np_round(x: float, decimals: int) -> None:
    assert round_like_numpy(x, decimals) == float(np.round(np.float64(x), decimals))


def test_round_like_numpy_worked_example() -> None:
    # half to even after scaling, as numpy does (Python's round(x, 1) gives 0.3 here)
    assert round_like_numpy(0.25, 1) == float(np.round(0.25, 1)) == 0.2
    assert round_like_numpy(1250.0, -2) == 1200.0


@st.composite
def problems(draw: st.DrawFn) -> tuple[Problem, Motion]:
    """A layout of 1-12 objects of 1-4 types, a map of 1-14 entries, some objects held."""
    m = draw(st.integers(1, 12))
    true = [draw(point) for _ in range(m)]
    kinds = [draw(st.integers(0, 3)) for _ in range(m)]
    cols_of: dict[int, tuple[int, ...]] = {}
    for c, k in enumerate(kinds):
        cols_of[k] = (*cols_of.get(k, ()), c)
    arr = np.array(true, dtype=float)
    layout = Layout(arr, tuple(true), np.array(kinds), cols_of, 10.0)
    n = draw(st.integers(1, 14))
    entries = [draw(point) for _ in range(n)]
    entry_kinds = [draw(st.sampled_from(sorted(cols_of))) for _ in range(n)]
    held = draw(st.lists(st.integers(0, m - 1), unique=True, max_size=m // 2))
    theta = draw(st.floats(0, 2 * math.pi))
    motion = Motion(math.cos(theta), math.sin(theta), draw(metres), draw(metres))
    return Problem(entries, entry_kinds, layout, held), motion


def _assign_dense(problem: Problem, motion: Motion) -> tuple[tuple[int, int], ...]:
    """The matrix expression :func:`assign` reproduces: (n x m) rounded squared distances, the
    nearest open object per entry, scipy's optimum for the types where nearest objects clash."""
    from scipy.optimize import linear_sum_assignment

    p = moved(problem.pred, motion)
    q = problem.layout.true
    d = (p[:, None, 0] - q[None, :, 0]) ** 2 + (p[:, None, 1] - q[None, :, 1]) ** 2
    d = np.where(problem.blocked, np.inf, np.round(d, 7))
    nearest = [
        j if ok else -1 for j, ok in zip(d.argmin(axis=1), np.isfinite(d).any(axis=1), strict=True)
    ]
    kinds = np.array(problem.kinds)
    clash = {
        k for k in set(problem.kinds)
        if len({j for j, kk in zip(nearest, problem.kinds, strict=True) if kk == k and j >= 0})
        < sum(1 for j, kk in zip(nearest, problem.kinds, strict=True) if kk == k and j >= 0)
    }  # fmt: skip
    pairs = [(i, j) for i, j in enumerate(nearest) if j >= 0 and problem.kinds[i] not in clash]
    for k in clash:
        rows = np.flatnonzero(kinds == k)
        cols = np.array(problem.candidates[rows[0]])
        r, c = linear_sum_assignment(d[rows][:, cols])
        pairs += zip(rows[r].tolist(), cols[c].tolist(), strict=True)
    return tuple(sorted(pairs))


@given(problems())
def test_assign_on_pairs_is_the_matrix_assignment(case: tuple[Problem, Motion]) -> None:
    problem, motion = case
    p = moved(problem.pred, motion)
    d = _distance_matrix(problem, p, 7)
    want = [
        j if ok else -1 for j, ok in zip(d.argmin(axis=1), np.isfinite(d).any(axis=1), strict=True)
    ]
    assert _nearest(_pair_distances(problem, p, 7), problem.candidates) == want
    assert assign(problem, motion) == _assign_dense(problem, motion)


@given(problems(), st.lists(st.tuples(metres, metres, metres), min_size=2, max_size=6))
def test_seed_scored_over_pairs_is_the_one_the_matrix_scores_best(
    case: tuple[Problem, Motion], raw: list[tuple[float, float, float]]
) -> None:
    problem = Problem(case[0].points, case[0].kinds, case[0].layout)  # nothing held
    seeds = [Motion(math.cos(a), math.sin(a), x, z) for a, x, z in raw]
    # oracle: the dense (seeds x entries x objects) score, best seed refined
    m = np.array(seeds)
    p, q = problem.pred, problem.layout.true
    mx = m[:, :1] * p[:, 0] - m[:, 1:2] * p[:, 1] + m[:, 2:3]
    mz = m[:, 1:2] * p[:, 0] + m[:, :1] * p[:, 1] + m[:, 3:4]
    d = (mx[:, :, None] - q[None, None, :, 0]) ** 2 + (mz[:, :, None] - q[None, None, :, 1]) ** 2
    allowed = np.array(problem.kinds)[:, None] == problem.layout.kinds[None, :]
    score = np.where(allowed[None], d, np.inf).min(axis=2).sum(axis=1)
    assert best_seed(problem, seeds) == seeds[int(np.round(score, 7).argmin())]
