"""Statistics rows: the paper's intervention tables, recomputed with :mod:`pytest_emrd.metrics`.

Inputs are the counts the paper prints (Table "Inventory-Free Controlled Interventions",
Appendix E, Appendix F); where it prints percentages, counts are ``round(% x n / 100)``. Each
printed statistic is compared at the precision it is printed with. A printed value the
printed counts do not give is a ``finding`` (never a loosened tolerance); for Appendix E the
row also states the counts that do reproduce every printed statistic, found by searching
the neighbourhood of the printed percentages with the same metric functions.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Final

from pytest_emrd.metrics import chi_square, cramers_v, fisher_exact_2x2
from pytest_emrd.validate._check import Check

#: Inventory-Free table: chosen room (Conference, Kitchen, Entrance, Office) x with / without.
INVENTORY_FREE: Final = ((70, 3, 6, 0), (22, 31, 21, 6))
#: Appendix E Baseline row: n and printed Conference %.
APPENDIX_E_BASELINE: Final = ("Baseline", 79, 59.5)
#: Appendix E B1-B4 rows: condition, n, printed Conference %, printed Fisher p vs Baseline.
APPENDIX_E: Final = (
    ("B1", 80, 52.5, 0.338),
    ("B2", 80, 53.8, 0.522),
    ("B3", 80, 78.8, 0.009),
    ("B4", 80, 70.0, 0.246),
)
#: Appendix E's Neutral row (Room A = the Conference Room), compared with Baseline alone.
NEUTRAL: Final = ("Neutral", 19, 68.4, 0.607)
APPENDIX_E_CHI2: Final = (17.81, 4, 0.001)
#: Appendix F per-spawn breakdown: spawn -> chosen (Conference, Kitchen, Entrance, Office).
APPENDIX_F: Final = {
    "Conference Room": (16, 1, 4, 0),
    "Office": (2, 13, 4, 1),
    "Kitchen": (4, 11, 1, 4),
    "Entrance": (0, 6, 13, 1),
}
APPENDIX_F_COLUMNS: Final = ("Conference Room", "Kitchen", "Entrance", "Office")
APPENDIX_F_SPAWN_SHARE: Final = 50.6
#: How far (counts) around the printed percentages the reproducing counts are searched.
SEARCH_RADIUS: Final = 3

Printed = Callable[[float], bool]


def _row(name: str, printed: str, value: float | None, same: Printed, note: str) -> Check:
    return Check(
        section="Statistics",
        name=name,
        planted=printed,
        recovered="n/a" if value is None else f"{value:.4g}",
        tolerance="printed precision",
        verdict="fail" if value is None else "pass" if same(value) else "finding",
        note=note,
        data={} if value is None else {"printed": printed, "recovered": value},
    )


def _printed_row(name: str, printed: float, digits: int, value: float | None, note: str) -> Check:
    """A row whose printed value is compared at the ``digits`` decimals it is printed with."""
    return _row(
        name, f"{printed}", value, lambda v: round(v, digits) == round(printed, digits), note
    )


def inventory_free_checks() -> list[Check]:
    """Chi-square, p and Cramer's V of the 2 x 4 Inventory-Free table."""
    chi = chi_square(INVENTORY_FREE)
    counts = "counts 70/3/6/0 vs 22/31/21/6 (C/K/E/O)"
    p = chi.p_value
    p_note = f"Pearson test, df = {chi.dof}, gives p = {p:.2e}" if p is not None else ""
    if p is not None and p >= 1e-13:
        p_note += ": the printed bound p < 1e-13 does not follow from the printed counts"
    return [
        _printed_row(
            "Inventory-Free chi-square", 62.4, 1, chi.statistic, f"{counts}; df = {chi.dof}"
        ),
        _row("Inventory-Free p", "< 1e-13", p, lambda v: v < 1e-13, p_note),
        _printed_row("Inventory-Free Cramer's V", 0.63, 2, cramers_v(INVENTORY_FREE), counts),
    ]


@dataclass(frozen=True)
class _Counts:
    """Conference choices per Appendix E row (Baseline first), with the row sizes."""

    conference: tuple[int, ...]
    n: tuple[int, ...]

    def table(self) -> list[list[int]]:
        return [[c, n - c] for c, n in zip(self.conference, self.n, strict=True)]

    def fisher(self, i: int) -> float:
        table = self.table()
        return fisher_exact_2x2([table[0], table[i]]).p_value


def _count(n: int, percent: float) -> int:
    return round(percent * n / 100)


def _reproducing(printed: _Counts) -> _Counts:
    """Counts within :data:`SEARCH_RADIUS` of ``printed`` that give every printed Fisher p
    (3 dp) and the printed chi-square (2 dp); the one closest to ``printed``."""
    spans = [range(c - SEARCH_RADIUS, c + SEARCH_RADIUS + 1) for c in printed.conference]
    matches: list[_Counts] = []
    for base in spans[0]:
        per_row = [
            [
                c
                for c in spans[i]
                if round(_Counts((base, c), (printed.n[0], printed.n[i])).fisher(1), 3) == row[3]
            ]
            for i, row in enumerate(APPENDIX_E, start=1)
        ]
        for combo in itertools.product(*per_row):
            counts = _Counts((base, *combo), printed.n)
            stat = chi_square(counts.table()).statistic
            if stat is not None and round(stat, 2) == APPENDIX_E_CHI2[0]:
                matches.append(counts)
    return min(
        matches,
        key=lambda c: sum(
            abs(x - y) for x, y in zip(c.conference, printed.conference, strict=True)
        ),
    )


def _describe(counts: _Counts, names: Sequence[str]) -> str:
    return ", ".join(
        f"{name} {c}/{n} ({100 * c / n:.1f} %)"
        for name, c, n in zip(names, counts.conference, counts.n, strict=True)
    )


def appendix_e_checks() -> list[Check]:
    """Chi-square (5 x 2), df, p and pairwise Fisher p of Appendix E, from the printed %."""
    names = [APPENDIX_E_BASELINE[0], *(r[0] for r in APPENDIX_E)]
    percentages = [APPENDIX_E_BASELINE[1:], *(r[1:3] for r in APPENDIX_E)]  # (n, %) per row
    printed = _Counts(
        tuple(_count(n, pc) for n, pc in percentages), tuple(n for n, _ in percentages)
    )
    fit = _reproducing(printed)
    source = f"counts from the printed %: {_describe(printed, names)}"
    diff = [n for n, a, b in zip(names, printed.conference, fit.conference, strict=True) if a != b]
    why = (
        f"all printed statistics are reproduced by {_describe(fit, names)}, which differ "
        f"from the printed percentages in {', '.join(diff) or 'no row'}"
    )
    chi = chi_square(printed.table())
    statistic, dof, p_value = APPENDIX_E_CHI2
    rows = [
        _printed_row(
            "Appendix E chi-square (5 x 2)", statistic, 2, chi.statistic, f"{source}; {why}"
        ),
        _printed_row("Appendix E df", dof, 0, float(chi.dof), source),
        _printed_row(
            "Appendix E p (chi-square)",
            p_value,
            3,
            chi.p_value,
            f"p = {chi.p_value:.4f} from the printed %",
        ),
    ]
    for i, (name, n, _, target) in enumerate(APPENDIX_E, start=1):
        p = printed.fisher(i)
        note = (
            f"Conference vs other: Baseline {printed.conference[0]}/{printed.n[0]} vs "
            f"{name} {printed.conference[i]}/{n}"
        )
        if round(p, 3) != target:
            note += (
                f"; the printed p needs Baseline {fit.conference[0]}/{fit.n[0]} vs "
                f"{name} {fit.conference[i]}/{n}"
            )
        rows.append(_printed_row(f"Appendix E Fisher p, {name}", target, 3, p, note))
    label, n, pc, target = NEUTRAL
    neutral = _Counts((printed.conference[0], _count(n, pc)), (printed.n[0], n))
    p = neutral.fisher(1)
    note = f"Room A chosen {neutral.conference[1]}/{n} vs Baseline {neutral.conference[0]}/79"
    if round(p, 3) != target:
        fixed = _Counts((fit.conference[0], neutral.conference[1]), neutral.n).fisher(1)
        note += f"; with Baseline {fit.conference[0]}/79 it is {fixed:.3f}"
    rows.append(_printed_row(f"Appendix E Fisher p, {label}", target, 3, p, note))
    return rows


def appendix_f_checks() -> list[Check]:
    """Appendix F's per-spawn breakdown against the Inventory-Free table it breaks down."""
    totals = [sum(row[j] for row in APPENDIX_F.values()) for j in range(4)]
    n = sum(totals)
    stayed = sum(row[APPENDIX_F_COLUMNS.index(spawn)] for spawn, row in APPENDIX_F.items())
    share = 100.0 * stayed / n
    table = INVENTORY_FREE[1]
    printed_n = sum(table)
    chi = chi_square(list(APPENDIX_F.values()))
    mismatch = [
        f"{room} {got} vs {want}"
        for room, got, want in zip(APPENDIX_F_COLUMNS, totals, table, strict=True)
        if got != want
    ]
    note = (
        f"the per-spawn breakdown sums to {n} episodes "
        f"(the Inventory-Free table prints {printed_n})"
        + (f"; column totals differ: {', '.join(mismatch)}" if mismatch else "")
        + f"; spawn x chosen chi-square = {chi.statistic:.2f} (df {chi.dof}, not printed)"
    )
    return [
        _printed_row(
            "Appendix F spawn-room share (%)",
            APPENDIX_F_SPAWN_SHARE,
            1,
            share,
            f"{stayed}/{n} choices name the spawn room",
        ),
        Check(
            section="Statistics",
            name="Appendix F totals vs Inventory-Free table",
            planted=f"n = {printed_n}",
            recovered=f"n = {n}",
            tolerance="exact",
            verdict="pass" if n == printed_n and not mismatch else "finding",
            note=note,
            data={"printed": printed_n, "recovered": n},
        ),
    ]


def statistics_checks() -> list[Check]:
    """Every statistics row, in table order.

    :returns: The statistics :class:`Check` rows.
    """
    return [*inventory_free_checks(), *appendix_e_checks(), *appendix_f_checks()]
