"""The matcher's float fast paths give numpy's bits: oracles are the numpy expressions they
replace (``pytest_emrd.metrics._align``), so a numpy that sums or rounds differently fails here
before it moves any metric."""

from __future__ import annotations

import math
import subprocess
import sys
from random import Random

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import _kernels
from pytest_emrd.metrics._align import (
    MAX_ROUNDS,
    Motion,
    Problem,
    _distance_matrix,
    assign,
    fit,
    layout_of,
    moved,
    procrustes,
    refine,
    zero_below,
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
def test_compiled_sum_is_numpys_pairwise_sum(values: list[float]) -> None:
    array = np.array(values, dtype=float)
    assert 0.0 + _kernels._pairwise(array) == float(np.add.reduce(array))


def test_compiled_sum_splits_long_runs_as_numpy_does() -> None:
    # past 128 values numpy splits in halves at a multiple of 8: sizes around each split
    rng = np.random.default_rng(7)
    for n in (127, 128, 129, 136, 255, 256, 257, 1000, 4099):
        values = rng.normal(size=n) * 10.0 ** rng.uniform(-6, 6, size=n)
        assert _kernels._pairwise(values) == float(np.add.reduce(values))


def test_compiled_sum_of_nothing_and_of_negative_zero_is_zero() -> None:
    assert math.copysign(1.0, 0.0 + _kernels._pairwise(np.array([]))) == 1.0
    negative_zero = 0.0 + _kernels._pairwise(np.array([-0.0]))
    assert math.copysign(1.0, negative_zero) == math.copysign(1.0, float(np.sum([-0.0])))


@given(st.lists(st.tuples(point, point), min_size=1, max_size=45), st.booleans(), st.randoms())
def test_procrustes_and_its_residual_are_the_numpy_fit_bitwise(
    pairs: list[tuple[tuple[float, float], tuple[float, float]]], coincide: bool, rnd: Random
) -> None:
    pred = [p for p, _ in pairs]
    if coincide:
        pred = [pred[0]] * len(pred)
    true = [q for _, q in pairs]
    # the kernel gathers the points through index pairs: shuffle the rows it reads from
    rows, cols = list(range(len(pred))), list(range(len(true)))
    rnd.shuffle(rows)
    rnd.shuffle(cols)
    stored_pred, stored_true = np.empty((len(pred), 2)), np.empty((len(true), 2))
    stored_pred[rows], stored_true[cols] = pred, true
    index = list(zip(rows, cols, strict=True))
    motion = _procrustes_numpy(np.array(pred), np.array(true))
    assert procrustes(stored_pred, stored_true, index) == motion
    squares = (moved(np.array(pred), motion) - np.array(true)) ** 2
    assert fit(stored_pred, stored_true, index)[4] == float(np.add.reduce(squares.ravel()))


@given(st.floats(0, 1e12, allow_nan=False), st.integers(-4, 12))
def test_compiled_round_is_np_round(x: float, decimals: int) -> None:
    assert _kernels._round(x, decimals) == float(np.round(np.float64(x), decimals))


def test_compiled_round_worked_example() -> None:
    # half to even after scaling, as numpy does (Python's round(x, 1) gives 0.3 here)
    assert _kernels._round(0.25, 1) == float(np.round(0.25, 1)) == 0.2
    assert _kernels._round(1250.0, -2) == 1200.0


@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=6), st.floats(0, 2 * math.pi))
def test_compiled_turn_is_numpys_matmul(rows: list[tuple[float, float]], theta: float) -> None:
    # OpenBLAS's dgemm fuses the multiply-add of two or more rows; one row is numpy's own loop
    c, s = math.cos(theta), math.sin(theta)
    points = np.array(rows)
    want = (points @ np.array(((c, s), (-s, c)))).tolist()
    fused = len(rows) >= 2
    assert [list(_kernels._turn(x, z, c, s, fused)) for x, z in rows] == want


@st.composite
def problems(draw: st.DrawFn) -> tuple[Problem, Motion]:
    """A layout of 1-12 objects of 1-4 types, a map of 1-14 entries, some objects held."""
    m = draw(st.integers(1, 12))
    true = [draw(point) for _ in range(m)]
    kinds = [draw(st.integers(0, 3)) for _ in range(m)]
    layout = layout_of(true, kinds, 10.0)
    n = draw(st.integers(1, 14))
    entries = [draw(point) for _ in range(n)]
    entry_kinds = [draw(st.sampled_from(sorted(set(kinds)))) for _ in range(n)]
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
    finite, nearest, distances = _kernels.nearest_open(problem.pred, *motion, problem.open, 7)
    assert finite
    assert nearest.tolist() == want
    pairs = [(i, j) for i, cols in enumerate(problem.candidates) for j in cols]
    assert distances.tolist() == [d[i, j] for i, j in pairs]
    assert assign(problem, motion) == _assign_dense(problem, motion)


costs = st.integers(1, 7).flatmap(
    lambda nr: st.integers(1, 7).flatmap(
        lambda nc: st.one_of(
            st.lists(st.integers(0, 3).map(float), min_size=nr * nc, max_size=nr * nc),
            st.lists(
                st.floats(0, 1e4, allow_nan=False).map(lambda x: round(x, 3)),
                min_size=nr * nc,
                max_size=nr * nc,
            ),
        ).map(lambda values: np.array(values).reshape(nr, nc))
    )
)


@given(costs)
def test_compiled_assignment_is_scipys_including_ties(cost: np.ndarray) -> None:
    # small integer costs tie often: scipy's choice among equal optima must be kept too
    from scipy.optimize import linear_sum_assignment

    rows, cols = _kernels.linear_sum_assignment(cost)
    want_rows, want_cols = linear_sum_assignment(cost)
    assert (rows.tolist(), cols.tolist()) == (want_rows.tolist(), want_cols.tolist())


def test_compiled_assignment_worked_example() -> None:
    # scipy's docstring example; a constant matrix gives the identity; a tall one transposes
    rows, cols = _kernels.linear_sum_assignment(np.array([[4.0, 1, 3], [2, 0, 5], [3, 2, 2]]))
    assert (rows.tolist(), cols.tolist()) == ([0, 1, 2], [1, 0, 2])
    rows, cols = _kernels.linear_sum_assignment(np.ones((3, 3)))
    assert cols.tolist() == [0, 1, 2]
    rows, cols = _kernels.linear_sum_assignment(np.array([[5.0], [1.0], [3.0]]))
    assert (rows.tolist(), cols.tolist()) == ([1], [0])


@given(problems())
def test_compiled_refine_is_the_loop_over_assign_and_fit(case: tuple[Problem, Motion]) -> None:
    problem, seed = case
    pairs = assign(problem, seed)  # oracle: the loop as written over the checked pieces
    for _ in range(MAX_ROUNDS):
        if not pairs:
            break
        c, s, tx, tz, sse = fit(problem.pred, problem.layout.true, pairs)
        if round(sse, 7) == 0.0:
            break
        again = assign(problem, Motion(c, s, tx, tz))
        if again == pairs:
            break
        pairs = again
    assert refine(problem, seed) == pairs


@given(st.integers(-3, 15))
def test_zero_below_is_where_pythons_round_leaves_zero(decimals: int) -> None:
    x = zero_below(decimals)
    assert round(x, decimals) == 0.0
    assert round(math.nextafter(x, math.inf), decimals) != 0.0


@given(problems(), st.sampled_from([math.inf, -math.inf, math.nan]))
def test_a_point_not_finite_is_assigned_by_the_matrix(
    case: tuple[Problem, Motion], bad: float
) -> None:
    # (the parser drops such entries; a non-finite distance leaves the kernel for numpy)
    problem, motion = case
    problem = Problem([(bad, 0.0)], problem.kinds[:1], problem.layout, problem.held)
    with np.errstate(invalid="ignore"):
        assert assign(problem, motion) == _assign_dense(problem, motion) == ()


def test_importing_the_metrics_imports_neither_numba_nor_scipy_optimize() -> None:
    # the kernels (numba) load on the first match and scipy.optimize on the first assignment:
    # collection validates thresholds against the metrics' names and pays for neither
    code = (
        "import sys, pytest_emrd.metrics\n"
        "print(sorted({'numba', 'scipy.optimize'} & set(sys.modules)))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


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
    best = _kernels.best_seed_index(np.array(seeds), problem.pred, problem.open, 7)
    assert best == int(np.round(score, 7).argmin())
