"""``thresholds.yaml``: the release gates (schema: docs/user-guide/ci.md), parsed and validated
with line numbers (pure). A condition key is the bare condition for the paper protocol and
``<condition>@generated`` for ``--emrd-layouts=generated`` cells. Every mistake is a one-line
ConfigError naming the file, line, field and allowed values; a bound lies in its metric's
:func:`domain`. A file with no gate is an error (a run given it would pass with nothing
checked)."""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, Final

import yaml

from pytest_emrd import _yaml
from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import CONDITIONS, LAYOUTS, MAX_STEPS

BOUND_KINDS: Final = ("min", "max")
CI_SIDES: Final = ("lower", "upper")
#: Metrics counted in actions of one episode: bounded by the action budget.
BUDGET_METRICS: Final = frozenset({"te"})


@dataclass(frozen=True)
class Domain:
    """The values a metric can take (``text``: in words); a bound outside never/always passes."""

    low: float
    high: float
    text: str

    def __contains__(self, value: float) -> bool:
        return self.low <= value <= self.high


#: Metric unit -> its domain (a metric of no listed unit: any finite number).
_UNIT_DOMAINS: Final = {
    "fraction": Domain(0.0, 1.0, "a fraction in [0, 1]"),
    "steps": Domain(0.0, math.inf, "steps >= 0"),
    "R^2": Domain(-math.inf, 1.0, "an R^2 <= 1"),
}


def domain(metric: str, unit: str | None) -> Domain:
    """The domain of ``metric`` from its unit (``fraction``, ``steps``, ``R^2``)."""
    if unit == "steps" and metric in BUDGET_METRICS:
        return Domain(0.0, float(MAX_STEPS), f"steps in [0, {MAX_STEPS}] (the action budget)")
    return _UNIT_DOMAINS.get(unit, Domain(-math.inf, math.inf, "a finite number"))


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
    layouts: str = "paper"
    """The cells it gates: ``paper`` (key ``baseline``), ``generated`` (``baseline@generated``)."""


@dataclass(frozen=True)
class Thresholds:
    """All gates of one file, in file order."""

    source: str
    bounds: tuple[Bound, ...]

    def for_cell(self, model: str, condition: str, layouts: str = "paper") -> tuple[Bound, ...]:
        cell = (model, condition, layouts)
        return tuple(b for b in self.bounds if (b.model, b.condition, b.layouts) == cell)


@dataclass(frozen=True)
class _Reader:
    source: str

    def fail(self, node: yaml.Node, message: str) -> ConfigError:
        return ConfigError(f"{self.source}, line {node.start_mark.line + 1}: {message}")

    def mapping(self, node: yaml.Node, what: str) -> Iterator[tuple[str, yaml.Node, yaml.Node]]:
        if not isinstance(node, yaml.MappingNode):
            raise self.fail(
                node, f"{what} must be a mapping of name: value, got {_yaml.describe(node)}."
            )
        # a duplicate key never gets here: _yaml.compose refuses it, naming the line
        for key, value in node.value:
            if not isinstance(key, yaml.ScalarNode):
                raise self.fail(key, f"{what} keys must be plain names.")
            yield key.value, key, value

    def number(self, node: yaml.Node, what: str, allowed: Domain) -> float:
        data = _yaml.scalar(node) if isinstance(node, yaml.ScalarNode) else None
        if isinstance(data, bool) or not isinstance(data, int | float):
            raise self.fail(
                node, f"{what} must be a number ({allowed.text}), got {_yaml.describe(node)}."
            )
        value = float(data)
        if not math.isfinite(value) or value not in allowed:
            raise self.fail(
                node, f"{what}={node.value} is outside the metric's domain; write {allowed.text}."
            )
        return value

    def choice(
        self, node: yaml.Node, what: str, value: str, allowed: Collection[str], hint: str = ""
    ) -> None:
        if value not in allowed:
            listed = ", ".join(sorted(allowed))
            raise self.fail(node, f"unknown {what} {value!r}; allowed: {listed}.{hint}")


def parse_thresholds(
    text: str,
    *,
    source: str,
    is_model: Callable[[str], bool],
    model_names: Collection[str],
    metrics: Collection[str],
    unknown_model_hint: str = "",
) -> Thresholds:
    """Parse and validate thresholds YAML text (``source`` names the file in messages). When
    ``metrics`` maps names to objects with a ``unit`` (``GATE_METRICS``), each bound is checked
    against its :func:`domain`; ``unknown_model_hint`` ends an unknown model's message.

    :param text: The YAML.
    :param source: The file's name for messages.
    :param is_model: Whether a model name is known (parametric names included).
    :param model_names: Known names, for the did-you-mean hint.
    :param metrics: Metric names, or name -> metric with a ``unit``.
    :param unknown_model_hint: The sentence ending an unknown model's message.
    :returns: The validated :class:`Thresholds`.
    """
    reader = _Reader(source)
    root = _yaml.compose(text, source)
    bounds: list[Bound] = []
    for model, model_key, conditions in (
        reader.mapping(root, "the top level (models)") if root else ()
    ):
        if not is_model(model):
            reader.choice(model_key, "model", model, model_names, unknown_model_hint)
        for key, cond_key, metric_map in reader.mapping(conditions, f"model {model!r}"):
            condition, at, layouts = key.partition("@")
            reader.choice(cond_key, "condition", condition, CONDITIONS)
            if at:  # the paper protocol is the bare condition; only other layouts are named
                reader.choice(cond_key, "layouts after '@'", layouts, LAYOUTS[1:])
            for metric, metric_key, spec in reader.mapping(metric_map, f"{model}.{key}"):
                reader.choice(metric_key, "metric", metric, metrics)
                allowed = domain(metric, _unit(metrics, metric))
                where = f"{model}.{condition}.{metric}"
                kind, value, ci = _bound(reader, where, metric_key, spec, allowed)
                line = metric_key.start_mark.line + 1
                bounds.append(
                    Bound(model, condition, metric, kind, value, ci, line, layouts or "paper")
                )
    if not bounds:
        raise ConfigError(
            f"{source} holds no gate, so a run would pass with nothing checked; write one "
            "(<model>: <condition>: <metric>: {min: 0.5}); to run without gates, delete the "
            "file and pass no --emrd-thresholds."
        )
    return Thresholds(source, tuple(bounds))


def _unit(metrics: Collection[str], name: str) -> str | None:
    return getattr(metrics.get(name), "unit", None) if isinstance(metrics, Mapping) else None


def _bound(
    reader: _Reader, where: str, key: yaml.Node, spec: Any, allowed: Domain
) -> tuple[str, float, str | None]:
    """The bound ``spec`` of metric ``where`` (``model.condition.metric``): kind, value and
    the CI end it compares (None: the value)."""
    fields = {name: (k, v) for name, k, v in reader.mapping(spec, where)}
    for name, (k, _) in fields.items():
        reader.choice(k, f"key in {where}", name, (*BOUND_KINDS, "ci"))
    kinds = [k for k in BOUND_KINDS if k in fields]
    if len(kinds) != 1:
        raise reader.fail(key, f"{where} needs exactly one of min or max, got {kinds or 'none'}.")
    kind = kinds[0]
    value = reader.number(fields[kind][1], f"{where}.{kind}", allowed)
    ci = None
    if "ci" in fields:
        ci_node = fields["ci"][1]
        if not isinstance(ci_node, yaml.ScalarNode):
            raise reader.fail(ci_node, f"{where}.ci must be one of lower, upper.")
        ci = str(ci_node.value)
        reader.choice(ci_node, f"ci side in {where}", ci, CI_SIDES)
    return kind, value, ci
