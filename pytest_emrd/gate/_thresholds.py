"""``thresholds.yaml``: the release gates, parsed and validated with line numbers (pure).

Schema::

    <model>:                 # a model registry name (scout, gemini, scout-decay-8 ...)
      <condition>:           # baseline | low_light | texture
        <metric>:            # a name of pytest_emrd.metrics.GATE_METRICS
          min: 0.8           # or max: 0.1 (exactly one of the two)
          ci: lower          # optional: compare the bootstrap CI's lower/upper end, not the mean

Every mistake is a :class:`~pytest_emrd.errors.ConfigError` naming the file, the line and
the allowed values.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from typing import Any, Final

import yaml

from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import CONDITIONS

BOUND_KINDS: Final = ("min", "max")
CI_SIDES: Final = ("lower", "upper")


@dataclass(frozen=True)
class Bound:
    """One gate: ``metric`` must stay at or above ``min`` / at or below ``max``."""

    model: str
    condition: str
    metric: str
    kind: str
    """``min`` or ``max``."""
    value: float
    ci: str | None = None
    """``lower``/``upper``: compare that end of the 95 % CI instead of the point value."""
    line: int = 0
    """1-based line of the metric in the thresholds file (0 when built in code)."""


@dataclass(frozen=True)
class Thresholds:
    """All gates of one file, in file order."""

    source: str
    bounds: tuple[Bound, ...]

    def for_cell(self, model: str, condition: str) -> tuple[Bound, ...]:
        return tuple(b for b in self.bounds if b.model == model and b.condition == condition)

    def models(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(b.model for b in self.bounds))


class _Reader:
    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, node: yaml.Node | None, message: str) -> ConfigError:
        line = f", line {node.start_mark.line + 1}" if node is not None else ""
        return ConfigError(f"{self.source}{line}: {message}")

    def mapping(self, node: yaml.Node, what: str) -> Iterator[tuple[str, yaml.Node, yaml.Node]]:
        if not isinstance(node, yaml.MappingNode):
            raise self.fail(node, f"{what} must be a mapping of name: value.")
        seen: set[str] = set()
        for key, value in node.value:
            if not isinstance(key, yaml.ScalarNode):
                raise self.fail(key, f"{what} keys must be plain names.")
            if key.value in seen:
                raise self.fail(key, f"{key.value!r} appears twice in {what}.")
            seen.add(key.value)
            yield key.value, key, value

    def number(self, node: yaml.Node, what: str) -> float:
        data = yaml.safe_load(yaml.serialize(node)) if isinstance(node, yaml.ScalarNode) else None
        if isinstance(data, bool) or not isinstance(data, int | float):
            raise self.fail(node, f"{what} must be a number, got {getattr(node, 'value', node)!r}.")
        return float(data)


def _choice(
    reader: _Reader, node: yaml.Node, what: str, value: str, allowed: Collection[str]
) -> None:
    if value not in allowed:
        listed = ", ".join(sorted(allowed))
        raise reader.fail(node, f"unknown {what} {value!r}; allowed: {listed}.")


def parse_thresholds(
    text: str,
    *,
    source: str,
    is_model: Callable[[str], bool],
    model_names: Collection[str],
    metrics: Collection[str],
) -> Thresholds:
    """Parse and validate thresholds YAML text (``source`` names the file in messages)."""
    reader = _Reader(source)
    try:
        root = yaml.compose(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(f"{source}{where}: malformed YAML ({problem}).") from exc
    if root is None:
        return Thresholds(source, ())
    bounds: list[Bound] = []
    for model, model_key, conditions in reader.mapping(root, "the top level (models)"):
        if not is_model(model):
            _choice(reader, model_key, "model", model, model_names)
        for condition, cond_key, metric_map in reader.mapping(conditions, f"model {model!r}"):
            _choice(reader, cond_key, "condition", condition, CONDITIONS)
            for metric, metric_key, spec in reader.mapping(metric_map, f"{model}.{condition}"):
                _choice(reader, metric_key, "metric", metric, metrics)
                bounds.append(_bound(reader, model, condition, metric, metric_key, spec))
    return Thresholds(source, tuple(bounds))


def _bound(
    reader: _Reader, model: str, condition: str, metric: str, key: yaml.Node, spec: Any
) -> Bound:
    where = f"{model}.{condition}.{metric}"
    fields = {name: (k, v) for name, k, v in reader.mapping(spec, where)}
    for name, (k, _) in fields.items():
        _choice(reader, k, f"key in {where}", name, (*BOUND_KINDS, "ci"))
    kinds = [k for k in BOUND_KINDS if k in fields]
    if len(kinds) != 1:
        raise reader.fail(key, f"{where} needs exactly one of min or max, got {kinds or 'none'}.")
    kind = kinds[0]
    value = reader.number(fields[kind][1], f"{where}.{kind}")
    ci = None
    if "ci" in fields:
        ci_node = fields["ci"][1]
        ci = str(getattr(ci_node, "value", ""))
        _choice(reader, ci_node, f"ci side in {where}", ci, CI_SIDES)
    return Bound(model, condition, metric, kind, value, ci, key.start_mark.line + 1)
