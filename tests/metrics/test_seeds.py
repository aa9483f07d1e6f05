"""The undetermined frame's kernel gives the bits of the Python procedure it replaces.

Oracles: Python's own ``math.dist``, ``math.fsum`` and ``round`` for :mod:`._pyfloat`, and the
procedure as it was written in Python (seeds of known pairs, hypotheses of a base pair, the
best seed refined; below) for :func:`._align.undetermined_fit`.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.metrics import _kernels, _pyfloat, _seeds
from pytest_emrd.metrics._align import (
    COINCIDENT_M,
    MAX_HYPOTHESES,
    Motion,
    Problem,
    assign,
    digits,
    layout_of,
    procrustes,
    refine,
    undetermined_fit,
)

Point = tuple[float, float]
anything = st.floats(allow_nan=True, allow_infinity=True)
wide = st.floats(-1e300, 1e300) | st.floats(-1e-300, 1e-300) | st.sampled_from([0.0, -0.0])


@given(anything, anything, anything, anything)
def test_dist_is_math_dist(px: float, pz: float, qx: float, qz: float) -> None:
    want = math.dist((px, pz), (qx, qz))
    got = _pyfloat.dist(px, pz, qx, qz)
    assert got == want or (math.isnan(got) and math.isnan(want))
    assert math.copysign(1.0, got) == math.copysign(1.0, want)


@given(st.lists(wide, min_size=1, max_size=40))
def test_fsum_is_math_fsum(values: list[float]) -> None:
    assert _pyfloat.fsum(np.array(values)) == math.fsum(values)


@pytest.mark.parametrize(
    "values", [[math.inf, 1.0], [math.nan, 2.0], [1e308, 1e308], [math.inf, -math.inf]]
)
def test_fsum_of_infinities_nan_and_overflow_is_pythons(values: list[float]) -> None:
    try:
        want: object = math.fsum(values)
    except (ValueError, OverflowError) as exc:
        with pytest.raises(type(exc), match=re.escape(str(exc))):
            _pyfloat.fsum(np.array(values))
        return
    got = _pyfloat.fsum(np.array(values))
    assert repr(got) == repr(want)


@given(wide | anything, st.integers(-4, 25))
def test_round_half_even_is_pythons_round(x: float, ndigits: int) -> None:
    got, want = _pyfloat.round_half_even(x, ndigits), round(x, ndigits)
    assert got == want or (math.isnan(got) and math.isnan(want))
    assert math.copysign(1.0, got) == math.copysign(1.0, want)


@given(st.integers(-(10**12), 10**12), st.integers(0, 12), st.sampled_from([-1, 0, 1]))
def test_round_half_even_at_decimal_ties_and_their_neighbours(
    k: int, ndigits: int, step: int
) -> None:
    x = (k + 0.5) / 10**ndigits  # the double nearest a decimal tie
    x = math.nextafter(x, math.inf * step) if step else x
    assert _pyfloat.round_half_even(x, ndigits) == round(x, ndigits)


def test_round_half_even_worked_examples() -> None:
    # 2.675 is stored below 2.675 and 0.125 is exact: Python rounds by the binary value
    assert _pyfloat.round_half_even(2.675, 2) == 2.67 != float(np.round(2.675, 2))
    assert _pyfloat.round_half_even(0.125, 2) == 0.12
    assert _pyfloat.round_half_even(1e300, 9) == 1e300


# --- the procedure as it was written in Python: the oracle --------------------------------


def _two_point(pa: Point, pb: Point, qa: Point, qb: Point) -> Motion:
    ux, uz = pb[0] - pa[0], pb[1] - pa[1]
    vx, vz = qb[0] - qa[0], qb[1] - qa[1]
    theta = math.atan2(ux * vz - uz * vx, ux * vx + uz * vz)
    c, s = math.cos(theta), math.sin(theta)
    mx, mz = (pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2
    nx, nz = (qa[0] + qb[0]) / 2, (qa[1] + qb[1]) / 2
    return Motion(c, s, nx - (c * mx - s * mz), nz - (s * mx + c * mz))


def _hypotheses(problem: Problem) -> list[Motion]:
    pred, cand = problem.points, problem.candidates
    true = [tuple(p) for p in problem.layout.true.tolist()]
    d1 = digits(problem.layout.scale, 1)
    n = len(pred)
    centre = (math.fsum([p[0] for p in pred]) / n, math.fsum([p[1] for p in pred]) / n)
    sizes = [len(cols) for cols in cand]
    fewest = min(sizes)
    a, far = -1, 0.0
    for i, size in enumerate(sizes):
        if size == fewest:
            g = round(math.dist(pred[i], centre), d1)
            if a < 0 or g > far:
                a, far = i, g
    b, best, gap = -1, (math.inf, 0.0), 0.0
    for i, cols in enumerate(cand):
        size = sizes[i]
        if size > best[0] or (size == 1 and cols == cand[a]):
            continue
        g = round(math.dist(pred[i], pred[a]), d1)
        if g > COINCIDENT_M and (size, -g) < best:
            b, best, gap = i, (size, -g), g
    if b < 0:
        return [Motion(1.0, 0.0, true[o][0] - pred[a][0], true[o][1] - pred[a][1]) for o in cand[a]]
    options = sorted(
        (round(abs(math.dist(true[oa], true[ob]) - gap), d1), oa, ob)
        for oa in cand[a]
        for ob in cand[b]
        if oa != ob
    )
    return [
        _two_point(pred[a], pred[b], true[oa], true[ob]) for _, oa, ob in options[:MAX_HYPOTHESES]
    ]


def _known_seed(problem: Problem, pairs: list[tuple[int, int]]) -> Motion | None:
    written = [problem.points[r] for r, _ in pairs]
    if len(pairs) == 1 or not any(math.dist(written[0], p) > COINCIDENT_M for p in written):
        if len({c for _, c in pairs}) != 1:
            return None
        r, c = pairs[0]
        return Motion(1.0, 0.0, *(problem.layout.true[c] - problem.pred[r]).tolist())
    return procrustes(problem.pred, problem.layout.true, pairs)


def _undetermined_fit_python(
    problem: Problem, kept: list[tuple[int, int]], named: list[tuple[int, int]]
) -> tuple[tuple[int, int], ...]:
    known = [_known_seed(problem, pairs) for pairs in (kept, named) if pairs]
    seeds = [*(m for m in known if m is not None), *_hypotheses(problem)]
    if not seeds:
        return ()
    best = seeds[0]
    if len(seeds) > 1 and all(problem.candidates):
        best = seeds[
            _kernels.best_seed_index(
                np.array(seeds), problem.pred, problem.open, digits(problem.layout.scale, 2)
            )
        ]
    return refine(problem, best)


# coordinates on a half-metre grid plant exact ties (equal distances, coincident points)
coord = st.sampled_from([k / 2 for k in range(-8, 9)]) | st.floats(-20, 20)
point = st.tuples(coord, coord)


@st.composite
def maps(draw: st.DrawFn) -> tuple[Problem, list[tuple[int, int]], list[tuple[int, int]]]:
    """A layout of 1-12 objects of 1-4 types, a map of 1-12 entries of those types, and
    known pairs of entries with objects of their type (kept, named)."""
    m = draw(st.integers(1, 12))
    kinds = [draw(st.integers(0, 3)) for _ in range(m)]
    layout = layout_of([draw(point) for _ in range(m)], kinds, draw(st.sampled_from([1.0, 12.0])))
    n = draw(st.integers(1, 12))
    entry_kinds = [draw(st.sampled_from(sorted(set(kinds)))) for _ in range(n)]
    problem = Problem([draw(point) for _ in range(n)], entry_kinds, layout)

    def known() -> list[tuple[int, int]]:
        rows = draw(st.lists(st.integers(0, n - 1), unique=True, max_size=n))
        return [(r, draw(st.sampled_from(layout.cols_of[entry_kinds[r]]))) for r in sorted(rows)]

    return problem, known(), known()


@given(maps())
def test_undetermined_fit_is_the_python_procedure(
    case: tuple[Problem, list[tuple[int, int]], list[tuple[int, int]]],
) -> None:
    problem, kept, named = case
    assert undetermined_fit(problem, kept, named) == _undetermined_fit_python(problem, kept, named)


@given(maps(), st.floats(0, 2 * math.pi), st.floats(-500, 500), st.floats(-500, 500))
def test_undetermined_fit_is_the_python_procedure_in_any_frame(
    case: tuple[Problem, list[tuple[int, int]], list[tuple[int, int]]],
    theta: float,
    dx: float,
    dz: float,
) -> None:
    problem, kept, named = case
    c, s = math.cos(theta), math.sin(theta)
    points = [(c * x - s * z + dx, s * x + c * z + dz) for x, z in problem.points]
    moved = Problem(points, problem.kinds, problem.layout)
    assert undetermined_fit(moved, kept, named) == _undetermined_fit_python(moved, kept, named)


def test_undetermined_fit_of_a_point_not_finite_is_the_python_procedure() -> None:
    layout = layout_of([(0.0, 0.0), (1.0, 0.0), (0.0, 2.0)], [0, 0, 1], 2.0)
    for bad in (math.inf, -math.inf, math.nan):
        problem = Problem([(bad, 0.0), (1.0, 0.5), (0.0, 2.0)], [0, 0, 1], layout)
        assert undetermined_fit(problem) == _undetermined_fit_python(problem, [], [])


@given(maps(), st.data())
def test_anchored_is_the_anchors_fit_then_the_assignment(
    case: tuple[Problem, list[tuple[int, int]], list[tuple[int, int]]], data: st.DataObject
) -> None:
    problem, known, _ = case
    layout = problem.layout
    anchors = data.draw(
        st.lists(st.tuples(point, st.integers(0, len(layout.true) - 1)), min_size=1, max_size=4)
    )
    held = sorted({c for _, c in known})
    points = np.array([p for p, _ in anchors] + problem.points, dtype=float)
    finite, found, motion = _seeds.anchored(
        points, np.array([c for _, c in anchors], dtype=np.intp),
        np.array(problem.kinds, dtype=np.intp), np.array(held, dtype=np.intp),
        layout.starts, layout.cols, layout.true, digits(layout.scale, 2),
    )  # fmt: skip
    want = procrustes(
        np.array([p for p, _ in anchors]), layout.true, list(enumerate(c for _, c in anchors))
    )
    assert motion == tuple(want)
    assert finite
    pairs = assign(Problem(problem.points, problem.kinds, layout, held), want)
    assert tuple((i, c) for i, c in enumerate(found.tolist()) if c >= 0) == pairs
