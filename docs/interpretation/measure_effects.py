"""Measure the effect of each interpretation rule of docs/interpretation on a committed run.

Usage, from the repository root::

    PYTHONPATH=$PWD python -m pytest benchmarks -q -p no:cacheprovider --emrd-results=RUN
    PYTHONPATH=$PWD python docs/interpretation/measure_effects.py RUN [GEN]

``RUN`` holds the 240 scout and 80 mimic episodes replayed from the committed cassettes; the
optional ``GEN`` a scout baseline run with ``--emrd-layouts=generated`` (compared with the
paper's office). Every number the pages under docs/interpretation quote for the committed runs
is printed here, each rule with and without it. A rule the metric functions take no parameter
for is switched off by an ablation written out below, never by patching the metrics. About a
minute on one core.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import random
import statistics
import sys
from collections import Counter
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Final

import numpy as np

from pytest_emrd.metrics import (
    GATE_METRICS,
    EpisodeMetrics,
    MatchedPair,
    Matching,
    aec_score,
    anova_conditions,
    as_episode_metrics,
    candidate_types,
    discovery_thirds,
    efc,
    fpsg,
    match_map,
    positional_accuracy_score,
    precision_score,
    random_reframe,
    reframe,
    serial_position_bins,
    step_matchings,
    tbs_curve,
)
from pytest_emrd.metrics._match import (
    TIE_M2,
    Matcher,
    Motion,
    _hypotheses,
    _Problem,
    _refine,
    assign_rows,
)
from pytest_emrd.metrics._tracking import discovered, first_spells, track_episode
from pytest_emrd.metrics._vocab import _exact, _fuzzy, _lookup, _singulars, head_words, noun_phrase
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.reference._phrasing import PHRASES
from pytest_emrd.run import load_run_dirs
from pytest_emrd.trajectory import GroundTruthObject, MapEntry, Trajectory
from pytest_emrd.validate._mimic import _sir_ratio_planted
from pytest_emrd.world._catalog import KINDS

LABELS = Path(__file__).resolve().parents[2] / "tests" / "metrics" / "vocab_labels.csv"


def mean(values: Iterable[float]) -> float:
    return statistics.fmean(values)


def estimate(name: str, ms: Sequence[EpisodeMetrics]) -> str:
    """A gate metric's value and seeded bootstrap 95 % CI, as ``emrd gate`` reports it."""
    e = GATE_METRICS[name].compute(ms)
    return f"{e.value:.4f} [{e.ci_low:.3f}, {e.ci_high:.3f}]"


# --- ablations of the matcher (same frame search, one rule off) ---------------------------


def without_charge(m: Matching) -> Matching:
    """The matching with no unmatched entry: Eq. PA's coverage factor without the charge."""
    return dataclasses.replace(m, unmatched=())


def without_gate(entries: Sequence[MapEntry], objects: Sequence[GroundTruthObject]) -> Matching:
    """The matcher's frame, then every recognised entry paired with an object of its type
    however far it lies (most pairs, then least summed squared distance): the gate off."""
    matcher = Matcher(objects)
    found = matcher.step(entries)
    gated = matcher.matching(found)
    labels = [lb for lb, k in found.kind_of.items() if k >= 0]
    if not labels:
        return gated
    c, s, tx, tz = found.motion or Motion(1.0, 0.0, 0.0, 0.0)
    if found.motion is None and found.identity:  # no rotation read: translate onto a pair
        lb, j = next(iter(found.identity.items()))
        e = found.entries[lb]
        tx, tz = matcher.objects[j].x - e.x, matcher.objects[j].z - e.z
    pred = np.array([(found.entries[lb].x, found.entries[lb].z) for lb in labels])
    x, z = pred[:, 0], pred[:, 1]
    moved = np.stack([c * x - s * z + tx, s * x + c * z + tz], axis=1)
    true = np.array([(o.x, o.z) for o in matcher.objects])
    kinds = np.array([found.kind_of[lb] for lb in labels])[:, None]
    same = kinds == np.array([matcher.types.index[o.object_type] for o in matcher.objects])
    cost = np.round(np.sum((moved[:, None, :] - true[None, :, :]) ** 2, axis=2) / TIE_M2)
    pairs = assign_rows(cost, same)
    return _matching(matcher, found.entries, [(labels[i], j) for i, j in pairs], labels, gated)


def _matching(
    matcher: Matcher,
    entries: dict[str, MapEntry],
    pairs: Sequence[tuple[str, int]],
    labels: Sequence[str],
    like: Matching,
) -> Matching:
    objs = matcher.objects
    matched = sorted(
        (
            MatchedPair(lb, objs[j].object_id, objs[j].object_type, entries[lb].x, entries[lb].z,
                        objs[j].x, objs[j].z)
            for lb, j in pairs
        ),
        key=lambda p: p.object_id,
    )  # fmt: skip
    held = {lb for lb, _ in pairs}
    unmatched = tuple(lb for lb in labels if lb not in held)
    return dataclasses.replace(like, pairs=tuple(matched), unmatched=unmatched)


def untruncated(entries: Sequence[MapEntry], objects: Sequence[GroundTruthObject]) -> Matching:
    """The frame rule without its truncation: the pair hypotheses scored by plain least squares
    (every entry's squared distance to the nearest object of its type, uncapped), then the same
    gated assignment and inlier refit."""
    matcher = Matcher(objects)
    found = matcher.step(entries)
    gated = matcher.matching(found)
    labels = [lb for lb, _, _, _ in found.key]
    if len(labels) < 2:
        return gated
    problem = _Problem(found.key, matcher._layout)
    motions, read = _hypotheses(problem)
    c, s, tx, tz = (motions[:, k : k + 1] for k in range(4))
    rows, cols = problem.candidates
    x, z = problem.pred[rows, 0], problem.pred[rows, 1]
    true = problem.layout.true
    d2 = (c * x - s * z + tx - true[cols, 0]) ** 2 + (s * x + c * z + tz - true[cols, 1]) ** 2
    score = np.minimum.reduceat(d2, problem.starts, axis=1).sum(axis=1)
    pairs, _, _ = _refine(problem, Motion(*motions[int(np.argmin(score))].tolist()), None, read)
    return _matching(matcher, found.entries, [(labels[i], j) for i, j in pairs], labels, gated)


# --- ablation of "what counts as forgetting" ----------------------------------------------


def unmatched_forgetting(traj: Trajectory) -> list[tuple[int, bool]]:
    """First spells (duration, event) with forgetting read as "no longer matched": the spell of
    object ``o`` ends in an event at the first out-of-view step where no entry is paired with
    ``o``, whichever label still stands for it (the rule this page replaces by label)."""
    held = track_episode(traj).held
    open_at: dict[str, int] = {}
    first: dict[str, tuple[int, bool]] = {}
    before: frozenset[str] = frozenset()
    for i, step in enumerate(traj.steps):
        visible, t = frozenset(step.visible_ids), step.index
        if i:
            for oid in (before - visible) & held[i - 1].keys():
                open_at.setdefault(oid, t)
        for oid, start in list(open_at.items()):
            if oid in visible or oid not in held[i]:
                first.setdefault(oid, (t - start + (oid not in visible), oid not in visible))
                del open_at[oid]
        before = visible
    for oid, start in open_at.items():
        first.setdefault(oid, (traj.steps[-1].index - start + 1, False))
    return list(first.values())


# --- ablations of the vocabulary ------------------------------------------------------------


def first_word_types(text: str) -> tuple[str, ...]:
    """The head-noun rule off: the candidates of the leftmost run of words (longest first,
    qualifiers not cut off) that is a key of the vocabulary, e.g. ``exit`` of ``exit sign``;
    when none is, the fuzzy step on the head noun, as with the rule on."""
    words = head_words(text)
    for start in range(len(words)):
        for size in range(min(4, len(words) - start), 0, -1):
            run = words[start : start + size]
            for last in _singulars(run[-1]):
                hit = _lookup("".join(run[:-1]) + last)
                if hit:
                    return hit
    phrase = noun_phrase(words)
    return _fuzzy(phrase) if phrase else ()


def exact_types(text: str) -> tuple[str, ...]:
    """The fuzzy step off: the head-noun rule with exact keys only."""
    phrase = noun_phrase(head_words(text))
    return _exact(phrase) if phrase else ()


def resolved(entry: MapEntry, reader: Callable[[str], tuple[str, ...]], held: set[str]) -> str:
    """An entry's type as :class:`~pytest_emrd.metrics._vocab.TypeResolver` reads it (type
    field first, then label), with ``reader`` for the candidates; '' for none."""
    for text in (entry.object_type, entry.label):
        if text in held:
            return text
        hit = next((c for c in reader(text) if c in held), None)
        if hit:
            return hit
    return ""


def retyped(
    entries: Sequence[MapEntry], reader: Callable[[str], tuple[str, ...]], held: set[str]
) -> list[MapEntry]:
    """``entries`` with each type written out as ``reader`` reads it, so that the matcher sees
    that reading: the type name itself, or a label naming nothing (``#3``) when it reads none."""
    out = []
    for i, e in enumerate(entries):
        kind = resolved(e, reader, held)
        out.append(dataclasses.replace(e, object_type=kind, label=e.label if kind else f"#{i}"))
    return out


#: The phrases of issue 23 that a first-word reading takes for an office object.
PHRASES_OF_ISSUE: Final = (
    "exit sign",
    "table lamp",
    "lamp on the desk",
    "picture of a plant",
    "fridge magnet",
    "chair leg",
    "sofa",
)
#: One misspelling per type (one edit each, two for ``bookshelfs``' plural).
TYPOS: Final = {
    "Chair": "chiar",
    "Laptop": "labtop",
    "Fridge": "refridgerator",
    "Television": "televsion",
    "Microwave": "microwve",
    "ShelvingUnit": "bookshelfs",
}


def vlm_maps(trajs: Sequence[Trajectory]) -> None:
    """Scout maps relabelled the way a VLM writes (the mimic's phrasings, no type field),
    with the issue's phrases added as hallucinations, or with six types misspelt; mean AEC and
    PA as read by the head-noun rule, with the head-noun rule off, and with the fuzzy step off.
    """
    readers = {"head noun": candidate_types, "head noun off": first_word_types,
               "fuzzy off": exact_types}  # fmt: skip
    for when in ("final", "third"):
        scores: dict[tuple[str, str], list[tuple[float, float]]] = {}
        for traj in trajs:
            step = traj.steps[-1] if when == "final" else traj.steps[len(traj.steps) // 3]
            cmap, objs = step.cognitive_map, list(traj.ground_truth.objects)
            held = {o.object_type for o in objs}
            rng = random.Random(f"{traj.spec.spawn}{traj.spec.episode}")
            phrase = [rng.choice(PHRASES.get(e.object_type, (e.object_type.lower(),)))
                      for e in cmap]  # fmt: skip
            relabelled = [MapEntry(f"{p} {i}", "", e.x, e.z)
                          for i, (p, e) in enumerate(zip(phrase, cmap, strict=True))]  # fmt: skip
            maps = {
                "relabelled": relabelled,
                "relabelled + 7 hallucinations": relabelled
                + [
                    MapEntry(p, "", e.x + rng.gauss(0, 0.3), e.z + rng.gauss(0, 0.3))
                    # a map of fewer than 7 entries gets one hallucination per entry
                    for p, e in zip(
                        PHRASES_OF_ISSUE, rng.sample(cmap, min(7, len(cmap))), strict=False
                    )
                ],
                "misspelt": [
                    MapEntry(f"{TYPOS.get(e.object_type, p)} {i}", "", e.x, e.z)
                    for i, (p, e) in enumerate(zip(phrase, cmap, strict=True))
                ],
            }
            g_base = len(traj.ground_truth.discoverable_ids)
            for name, entries in maps.items():
                for reading, reader in readers.items():
                    m = match_map(retyped(entries, reader, held), objs)
                    got = (aec_score(m, len(objs)) or 0.0, positional_accuracy_score(m, g_base))
                    scores.setdefault((name, reading), []).append((got[0], got[1] or 0.0))
        for name in ("relabelled", "relabelled + 7 hallucinations", "misspelt"):
            cells = "; ".join(
                f"{r}: AEC {mean(a for a, _ in scores[name, r]):.3f}"
                f" PA {mean(p for _, p in scores[name, r]):.3f}"
                for r in readers
            )
            print(f"{when} | {name} | {cells}")


def label_table() -> None:
    """The 202 labels of ``tests/metrics/vocab_labels.csv`` read with each rule on and off:
    accepted per kind, and the labels whose office type differs from the table's."""
    rows = list(csv.DictReader(LABELS.open()))
    office = {kind.object_type for kind in KINDS.values()}
    readers = {"head noun": candidate_types, "head noun off": first_word_types,
               "fuzzy off": exact_types}  # fmt: skip
    for name, reader in readers.items():
        read = {r["label"]: next((c for c in reader(r["label"]) if c in office), "") for r in rows}
        accepted = Counter(r["kind"] for r in rows if read[r["label"]])
        shares = ", ".join(f"{k} {accepted[k]}" for k in dict.fromkeys(r["kind"] for r in rows))
        wrong = [f"{r['label']} -> {read[r['label']] or '-'}" for r in rows
                 if read[r["label"]] != r["in_office"]]  # fmt: skip
        print(f"{name}: accepted {sum(accepted.values())} of {len(rows)} ({shares});"
              f" {len(wrong)} differ from the table: {'; '.join(wrong)}")  # fmt: skip


# --- the random maps of the gate table ------------------------------------------------------


def uniform(truth: list[GroundTruthObject], n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points uniform over the office's bounding box widened by 1 m."""
    xy = np.array([(o.x, o.z) for o in truth])
    return rng.uniform(xy.min(axis=0) - 1.0, xy.max(axis=0) + 1.0, size=(n, 2))


def random_map(truth: list[GroundTruthObject], n: int, rng: np.random.Generator) -> list[MapEntry]:
    """``n`` entries of the layout's types (drawn by object) at uniform positions."""
    kinds = [truth[i].object_type for i in rng.integers(0, len(truth), n)]
    return [
        MapEntry(f"guess {i}", k, *p.tolist())
        for i, (k, p) in enumerate(zip(kinds, uniform(truth, n, rng), strict=True))
    ]


def noisy_map(truth: list[GroundTruthObject], sigma: float, rng: np.random.Generator) -> list:
    return [
        MapEntry(f"{o.object_type} {i}", o.object_type, *rng.normal((o.x, o.z), sigma).tolist())
        for i, o in enumerate(truth)
    ]


def gate_table(trajs: Sequence[Trajectory]) -> None:
    rows: dict[str, Callable[[list[GroundTruthObject], np.random.Generator], list[MapEntry]]] = {
        "inventory copied, random positions": lambda t, r: [
            MapEntry(f"copy {i}", o.object_type, *p.tolist())
            for i, (o, p) in enumerate(zip(t, uniform(t, len(t), r), strict=True))
        ],
        "41 random guesses": lambda t, r: random_map(t, 41, r),
        "1,000 random guesses": lambda t, r: random_map(t, 1000, r),
        "every object, sigma 2 m": lambda t, r: noisy_map(t, 2.0, r),
        "the same plus 500 random guesses": lambda t, r: [
            *noisy_map(t, 2.0, r),
            *random_map(t, 500, r),
        ],
        "every object, sigma 0.3 m": lambda t, r: noisy_map(t, 0.3, r),
        "every object, sigma 0.5 m": lambda t, r: noisy_map(t, 0.5, r),
        "every object, sigma 1.0 m": lambda t, r: noisy_map(t, 1.0, r),
    }
    print("map | AEC | PA | PA charge off | PA gate off | PA both off | precision")
    for name, make in rows.items():
        got: list[tuple[float, ...]] = []
        for seed, traj in enumerate(trajs):
            truth = list(traj.ground_truth.objects)
            g_base = len(traj.ground_truth.discoverable_ids)
            entries = make(truth, np.random.default_rng(seed))
            m, open_ = match_map(entries, truth), without_gate(entries, truth)
            got.append(
                (
                    aec_score(m, len(truth)) or 0.0,
                    positional_accuracy_score(m, g_base) or 0.0,
                    positional_accuracy_score(without_charge(m), g_base) or 0.0,
                    positional_accuracy_score(open_, g_base) or 0.0,
                    positional_accuracy_score(without_charge(open_), g_base) or 0.0,
                    precision_score(m) or 0.0,
                )
            )
        cells = " | ".join(f"{mean(g[k] for g in got):.3f}" for k in range(6))
        print(f"{name} | {cells}")


def with_maps(traj: Trajectory, change: Callable[[int, tuple[MapEntry, ...]], tuple]) -> Trajectory:
    steps = tuple(
        dataclasses.replace(s, cognitive_map=tuple(change(i, s.cognitive_map)))
        for i, s in enumerate(traj.steps)
    )
    return dataclasses.replace(traj, steps=steps)


def frame_invariance(trajs: Sequence[Trajectory], ms: Sequence[EpisodeMetrics]) -> None:
    """Every map re-expressed in a seeded random proper rigid frame: the largest change."""
    moved = as_episode_metrics(
        random_reframe(t, np.random.default_rng(i)) for i, t in enumerate(trajs)
    )
    pa = max(abs((a.pa or 0.0) - (b.pa or 0.0)) for a, b in zip(ms, moved, strict=True))
    same = Counter()
    for a, b in zip(ms, moved, strict=True):
        same["AEC"] += a.aec == b.aec
        same["SIR"] += a.sir == b.sir
        same["FPSG"] += (a.fpsg_local, a.fpsg_global) == (b.fpsg_local, b.fpsg_global)
        same["spells"] += a.spells == b.spells
        same["serial position"] += a.serial_position == b.serial_position
    print(f"max |dPA| {pa:.1e}; episodes unchanged of {len(ms)}: {dict(same)}")


def step_map(entries: Iterable[MapEntry]) -> dict[str, MapEntry]:
    """Label -> its first entry, in the model's order (how the matcher reads a map)."""
    seen: dict[str, MapEntry] = {}
    for e in entries:
        seen.setdefault(e.label, e)
    return seen


def serial_ties(trajs: Sequence[Trajectory]) -> None:
    """Discovery ties broken by the model's write order (the rule) or by id string."""
    shared = changed = found = 0
    bins: dict[str, list[tuple[float | None, ...]]] = {"write order": [], "id string": []}
    for t in trajs:
        track = track_episode(t)
        written = [step_map(s.cognitive_map) for s in t.steps]
        first = {oid: when[0] for oid, when in discovered(list(track.held), written).items()}
        by_step = Counter(first.values())
        shared += sum(1 for oid in first if by_step[first[oid]] > 1)
        found += len(first)
        ordered = sorted(track.discovery, key=track.discovery.__getitem__)
        by_id = sorted(first, key=lambda o: (first[o], o))
        third = discovery_thirds(len(ordered))
        changed += sum(third[ordered.index(o)] != third[i] for i, o in enumerate(by_id))
        ttf = {s.object_id: float(s.duration) for s in first_spells(track.spells)}
        bins["write order"].append(serial_position_bins([ttf.get(o) for o in ordered]))
        bins["id string"].append(serial_position_bins([ttf.get(o) for o in by_id]))
    means = {
        name: " / ".join(
            f"{mean(v for b in rows if (v := b[k]) is not None):.2f}" for k in range(3)
        )
        for name, rows in bins.items()
    }
    print(f"{shared} of {found} discovered objects share their step, {changed} change third;"
          f" E/M/L {means}")  # fmt: skip


def label_identity_sir(traj: Trajectory) -> float | None:
    """SIR's ratio read as label identity alone (copies not excluded): the ablation of the
    deduplication rule of :func:`~pytest_emrd.metrics.sir_score`."""
    track = track_episode(traj)
    room_of = {o.object_id: o.room for o in traj.ground_truth.objects}
    ratios = []
    for v in track.visits:
        if v.return_end is None:
            continue
        first = {o: lb for o, lb in track.held[v.first_end].items() if room_of[o] == v.room}
        if first:
            room_by_label = {lb: room_of[o] for o, lb in track.held[v.return_end].items()}
            ratios.append(
                sum(room_by_label.get(lb) == v.room for lb in first.values()) / len(first)
            )
    return mean(ratios) if ratios else None


def pooled_efc(ms: Sequence[EpisodeMetrics]) -> float:
    """Eq. SMLE over the first spells of ``ms`` pooled: ``sum t_j / d``."""
    return sum(m.retained_steps for m in ms) / sum(m.forget_events for m in ms)


def memory(m: EpisodeMetrics) -> tuple:
    return m.spells, m.memory_strength, m.forget_events, m.serial_position, m.sir


def main(run_dir: Path) -> None:
    trajs = load_run_dirs([run_dir])
    ms = as_episode_metrics(trajs)
    cells: dict[tuple[str, str], list[int]] = {}
    for i, t in enumerate(trajs):
        cells.setdefault((t.spec.model, t.spec.condition), []).append(i)
    scout_base = [trajs[i] for i in cells["scout", "baseline"]]
    mimic = [trajs[i] for i in cells["mimic", "baseline"]]

    print("== committed runs: value [95% CI] as emrd gate computes it")
    for (model, cond), idx in sorted(cells.items()):
        cm = [ms[i] for i in idx]
        print(
            f"{model} {cond} n={len(idx)} AEC {estimate('aec', cm)} PA {estimate('pa', cm)}"
            f" precision {estimate('precision', cm)}"
            f" hallucination {estimate('hallucination_rate', cm)}"
        )

    print("\n== terminal map on its own vs the last step of the per-step matching (history)")
    for (model, cond), idx in sorted(cells.items()):
        diffs = []
        for i in idx:
            t = trajs[i]
            last = step_matchings([s.cognitive_map for s in t.steps], t.ground_truth.objects)[-1]
            pa = positional_accuracy_score(last, len(t.ground_truth.discoverable_ids)) or 0.0
            diffs.append(pa - (ms[i].pa or 0.0))
        moved = [d for d in diffs if abs(d) > 1e-9]
        print(
            f"{model} {cond}: mean PA alone {mean(ms[i].pa or 0.0 for i in idx):.4f},"
            f" with history {mean(ms[i].pa or 0.0 for i in idx) + mean(diffs):.4f};"
            f" {len(moved)} of {len(idx)} episodes differ, by up to"
            f" {max((abs(d) for d in moved), default=0.0):.3f}"
        )

    print("\n== gate and charge on the committed runs (mean PA, mean precision)")
    for (model, cond), idx in sorted(cells.items()):
        got = []
        for i in idx:
            t = trajs[i]
            final, truth = t.steps[-1].cognitive_map, t.ground_truth.objects
            g = len(t.ground_truth.discoverable_ids)
            m, open_ = match_map(final, truth), without_gate(final, truth)
            got.append(
                (
                    positional_accuracy_score(m, g) or 0.0,
                    positional_accuracy_score(without_charge(m), g) or 0.0,
                    positional_accuracy_score(open_, g) or 0.0,
                    positional_accuracy_score(without_charge(open_), g) or 0.0,
                    precision_score(m) or 0.0,
                    precision_score(open_) or 0.0,
                    len(m.unmatched),
                )
            )
        print(
            f"{model} {cond}: PA {mean(g[0] for g in got):.4f}, charge off"
            f" {mean(g[1] for g in got):.4f}, gate off {mean(g[2] for g in got):.4f},"
            f" both off {mean(g[3] for g in got):.4f}; precision {mean(g[4] for g in got):.4f},"
            f" gate off {mean(g[5] for g in got):.4f}; unmatched entries"
            f" {sum(g[6] for g in got)} in {sum(1 for g in got if g[6])} episodes"
        )

    print("\n== maps written to game the score (first 40 scout baseline episodes)")
    gate_table(scout_base[:40])

    print("\n== frame rule: an 'exit sign' of type Door added from step 2 on (scout baseline)")
    base = [ms[i] for i in cells["scout", "baseline"]]
    signed, open_pa, plain_pa = [], [], []
    for t in scout_base:
        first = t.steps[-1].cognitive_map[0]
        sign = MapEntry("exit sign", "Door", first.x + 4.0, first.z - 3.0)
        signed.append(with_maps(t, lambda i, m, sign=sign: (*m, sign) if i else m))
        final, truth = signed[-1].steps[-1].cognitive_map, t.ground_truth.objects
        g = len(t.ground_truth.discoverable_ids)
        open_pa.append(positional_accuracy_score(untruncated(final, truth), g) or 0.0)
        plain_pa.append(positional_accuracy_score(without_charge(without_gate(final, truth)), g))
    sm = as_episode_metrics(signed)
    pas = [m.pa or 0.0 for m in sm]
    moved = [(a, b) for a, b in zip(base, sm, strict=True) if memory(a) != memory(b)]
    shift = max(
        (abs(x - y) for a, b in moved
         for x, y in zip(a.serial_position, b.serial_position, strict=True)
         if x is not None and y is not None),
        default=0.0,
    )  # fmt: skip
    print(
        f"PA without the sign {mean(m.pa or 0.0 for m in base):.4f}"
        f" (worst {min(m.pa or 0.0 for m in base):.4f}); with it {mean(pas):.4f}"
        f" (worst {min(pas):.4f}); largest move"
        f" {max(abs((a.pa or 0.0) - (b.pa or 0.0)) for a, b in zip(base, sm, strict=True)):.2e};"
        f" finite EFC with it {sum(1 for m in sm if m.memory_strength != math.inf)};"
        f" episodes whose spells or serial position move {len(moved)}, largest bin shift"
        f" {shift:.2f} steps"
    )
    print(
        f"truncation off: PA with the sign {mean(open_pa):.4f} (worst {min(open_pa):.4f});"
        f" gate and charge off (sign paired with the door where it is free):"
        f" {mean(p or 0.0 for p in plain_pa):.4f} (worst {min(p or 0.0 for p in plain_pa):.4f})"
    )
    untr = []
    for i in cells["mimic", "baseline"]:
        t = trajs[i]
        g = len(t.ground_truth.discoverable_ids)
        untr.append(
            positional_accuracy_score(untruncated(t.steps[-1].cognitive_map,
                                                  t.ground_truth.objects), g) or 0.0
        )  # fmt: skip
    mm = [ms[i] for i in cells["mimic", "baseline"]]
    print(
        f"mimic baseline PA {mean(m.pa or 0.0 for m in mm):.4f}, truncation off"
        f" {mean(untr):.4f}; episodes that differ"
        f" {sum(abs((m.pa or 0.0) - u) > 1e-9 for m, u in zip(mm, untr, strict=True))}"
    )

    print("\n== what counts as forgetting (label dropped or relabelled away vs 'not matched')")
    mirrored = [reframe(t, 0.7, 3.0, -2.0, mirror=True) for t in trajs if t.spec.model == "scout"]
    for name, group in (("mimic baseline", mimic), ("scout mirrored", mirrored)):
        gm = as_episode_metrics(group)
        finite = sum(1 for m in gm if m.memory_strength and math.isfinite(m.memory_strength))
        ablated = [unmatched_forgetting(t) for t in group]
        events = [sum(e for _, e in spells) for spells in ablated]
        pooled = [(d, e) for spells in ablated for d, e in spells]
        strength = efc([d for d, _ in pooled], [e for _, e in pooled]) if pooled else None
        print(
            f"{name}: by label {sum(m.forget_events for m in gm)} events, finite EFC in {finite}"
            f" of {len(gm)}; as 'not matched' {sum(events)} events in"
            f" {sum(1 for e in events if e)} episodes, pooled EFC {strength}"
        )

    print("\n== time-to-forget: first spells, censored when back in view")
    for (model, cond), idx in sorted(cells.items()):
        cm = [ms[i] for i in idx]
        spells = [s for m in cm for s in m.spells]
        first = [(m, s) for m in cm for s in m.ttf_spells]
        back = sum(1 for m, s in first if not s.forgotten and s.start + s.duration <= m.steps)
        later = [s for m in cm for s in m.spells if s not in first_spells(m.spells)]
        print(
            f"{model} {cond}: {len(spells)} spells, {len(first)} first spells, {back} censored"
            f" back in view, {len(first) - back - sum(s.forgotten for _, s in first)} at the"
            f" episode's end, {sum(s.forgotten for _, s in first)} events;"
            f" later spells {len(later)}, events among them {sum(s.forgotten for s in later)}"
        )

    print("\n== ANOVA over episodes with no forgetting event")
    for (model, cond), idx in sorted(cells.items()):
        cm = [ms[i] for i in idx]
        print(
            f"{model} {cond}: finite EFC in"
            f" {sum(1 for m in cm if m.memory_strength and math.isfinite(m.memory_strength))}"
            f" of {len(cm)}"
        )
    print("committed ANOVA:", anova_conditions(ms).groups, anova_conditions(ms).reason)
    grid = as_episode_metrics(synthetic_grid(episodes=10, mean_memory=80.0))
    a = anova_conditions(grid)
    print(
        f"synthetic, planted mean 80 steps: {sum(m.memory_strength == math.inf for m in grid)}"
        f" of {len(grid)} without an event; groups {a.groups}; F {a.statistic}"
    )
    for cond in sorted({m.spec.condition for m in grid}):
        cg = [m for m in grid if m.spec.condition == cond]
        kept = [m for m in cg if m.memory_strength != math.inf]
        print(
            f"  {cond}: pooled EFC (sum t / d) over the {len(kept)} kept {pooled_efc(kept):.1f},"
            f" over all {len(cg)} {pooled_efc(cg):.1f}"
        )

    print("\n== frame invariance (seeded random proper rigid frames)")
    for model in ("scout", "mimic"):
        idx = [i for i, t in enumerate(trajs) if t.spec.model == model]
        print(model, end=": ")
        frame_invariance([trajs[i] for i in idx], [ms[i] for i in idx])

    print("\n== FPSG with and without doorways in O_F; TBS at t = 50; PA's cap")
    for (model, cond), idx in sorted(cells.items()):
        cm = [ms[i] for i in idx]
        f = fpsg(cm)
        tbs = [m.tbs for m in cm if m.tbs]
        running = [v[49] for v in tbs if len(v) >= 50]
        print(
            f"{model} {cond}: FPSG local {f.local_mean:.3f} / ex doorways"
            f" {f.local_mean_ex_doorways:.3f}, global {f.global_mean:.3f} /"
            f" {f.global_mean_ex_doorways:.3f}, any-bias {f.any_bias:.3f};"
            f" TE {mean(m.te or 0 for m in cm):.1f}; TBS(50) carried"
            f" {tbs_curve(cm).mean[49]:.3f}, running only {len(running)} episodes"
            f" {mean(running) if running else float('nan'):.3f}, zero-filled"
            f" {mean(v[49] if len(v) >= 50 else 0.0 for v in tbs):.3f};"
            f" cap binds in {sum(m.matched > m.g_base for m in cm)}"
        )
    synth = as_episode_metrics(synthetic_grid())
    print(
        f"synthetic grid: cap binds in {sum(m.matched > m.g_base for m in synth)} of {len(synth)}"
    )

    print("\n== serial position: ties in discovery order (scout)")
    for cond in ("baseline", "low_light"):
        print(cond, end=": ")
        serial_ties([trajs[i] for i in cells["scout", cond]])

    print("\n== SIR / AEC: label identity alone, with copies excluded, planted (mimic)")
    for model, cond in (("mimic", "baseline"), ("scout", "low_light"), ("scout", "baseline")):
        rows = []
        for i in cells[model, cond]:
            m, t = ms[i], trajs[i]
            if m.sir is not None and m.aec:
                reentries = sum(v.return_end is not None for v in track_episode(t).visits)
                planted = _sir_ratio_planted(t) if model == "mimic" else None
                rows.append((label_identity_sir(t) or 0.0, m.sir / m.aec, planted, reentries))
        line = f"{model} {cond}: {len(rows)} episodes with a re-entry"
        if rows:
            line += (
                f", {sum(r[3] for r in rows)} re-entered rooms: label identity"
                f" {mean(r[0] for r in rows):.3f}, with copies {mean(r[1] for r in rows):.3f}"
            )
        if rows and model == "mimic":
            line += (
                f", planted {mean(r[2] or 0.0 for r in rows):.3f}; equal to planted in"
                f" {sum(abs(r[1] - (r[2] or 0.0)) < 1e-9 for r in rows)}"
            )
        print(line)

    print("\n== the label table, each vocabulary rule on and off")
    label_table()

    print("\n== VLM-style maps of 20 scout baseline episodes (4 spawns x episodes 0-4)")
    vlm_maps([t for t in scout_base if t.spec.episode < 5])

    print("\n== vocabulary and positions on the committed runs")
    for model in ("scout", "mimic"):
        group = [t for t in trajs if t.spec.model == model]
        count: Counter[str] = Counter()
        for t in group:
            held = {o.object_type for o in t.ground_truth.objects}
            for s in t.steps:
                count["replies"] += 1
                count["parse failures"] += s.parse_error is not None
                for r in s.repairs or ():
                    count[f"repair {r}"] += 1
                for e in s.cognitive_map:
                    count["entries"] += 1
                    now = resolved(e, candidate_types, held)
                    count["hallucinated"] += not now
                    count["first-word differs"] += resolved(e, first_word_types, held) != now
                    count["fuzzy only"] += resolved(e, exact_types, held) != now
        print(model, dict(sorted(count.items())))


def paper_vs_generated(paper: Sequence[EpisodeMetrics], generated: Path) -> None:
    """Scout baseline in the paper's office against per-episode generated offices."""
    other = as_episode_metrics(
        t
        for t in load_run_dirs([generated])
        if (t.spec.model, t.spec.condition) == ("scout", "baseline")
    )
    for name, group in (("paper office", paper), ("generated", other)):
        rooms = Counter(m.chosen_letter for m in group)
        print(
            f"{name} ({len(group)}): AEC {estimate('aec', group)}, TE {estimate('te', group)},"
            f" PA {estimate('pa', group)}; chosen C/O/K/E/X"
            f" {'/'.join(str(rooms[r]) for r in 'COKEX')}"
        )


if __name__ == "__main__":
    main(Path(sys.argv[1]))
    if len(sys.argv) > 2:  # a run with --emrd-layouts=generated (scout, baseline)
        print("\n== scout baseline: the paper's office vs generated offices")
        base = [
            m
            for m in as_episode_metrics(load_run_dirs([Path(sys.argv[1])]))
            if (m.spec.model, m.spec.condition) == ("scout", "baseline")
        ]
        paper_vs_generated(base, Path(sys.argv[2]))
