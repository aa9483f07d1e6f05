"""The user's YAML files read the same through libyaml's parser as through PyYAML's own."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from pytest_emrd import _yaml
from pytest_emrd.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
FILES = [ROOT / "thresholds.yaml", ROOT / "pytest_emrd" / "agent" / "models.yaml"]


def _nodes(node: yaml.Node) -> Iterator[tuple[object, ...]]:
    value = node.value if isinstance(node, yaml.ScalarNode) else None
    yield type(node).__name__, node.tag, node.start_mark.line, node.start_mark.column, value
    children = node.value if not isinstance(node, yaml.ScalarNode) else []
    for child in children:
        for part in child if isinstance(child, tuple) else (child,):
            yield from _nodes(part)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_fast_parser_reads_the_same_nodes_marks_and_values(path):
    text = path.read_text()
    fast = _yaml.compose(text, str(path))
    slow = yaml.compose(text, Loader=_yaml.Loader)
    assert fast is not None and slow is not None
    assert list(_nodes(fast)) == list(_nodes(slow))
    assert _yaml.load(text, str(path)) == yaml.load(text, Loader=_yaml.Loader)


def test_yaml_12_floats_and_pyyaml_error_wording():
    assert _yaml.load("a: 1e9\nb: 5E-3\nc: 3", "x.yaml") == {"a": 1e9, "b": 5e-3, "c": 3}
    with pytest.raises(yaml.YAMLError) as slow:
        yaml.load("a: b: c", Loader=_yaml.Loader)
    with pytest.raises(ConfigError, match=r"x\.yaml, line 1, column 5: malformed YAML") as fast:
        _yaml.load("a: b: c", "x.yaml")
    assert str(slow.value.problem) in str(fast.value)


def test_anchors_asterisks_in_text_and_nesting_up_to_the_cap_are_read():
    nested = "[" * (_yaml.MAX_DEPTH - 1) + "]" * (_yaml.MAX_DEPTH - 1)  # under the root mapping
    text = f"a: &kept {{x: 1}}\nb: '*not an alias'\nc: {nested}\n"
    data = _yaml.load(text, "x.yaml")
    assert data["a"] == {"x": 1} and data["b"] == "*not an alias"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a: &x 1\nb: *x\n", r"x\.yaml, line 2: YAML alias \*x is not allowed"),
        ("a: " + "[" * 40 + "]" * 40, r"x\.yaml, line 1: YAML nested more than 32 levels deep"),
    ],
    ids=["alias", "too-deep"],
)
def test_aliases_and_deep_nesting_are_refused_before_composing(text, message):
    with pytest.raises(ConfigError, match=message):
        _yaml.compose(text, "x.yaml")


def test_a_file_over_the_cap_is_refused_unread(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_bytes(b"#" * (_yaml.MAX_FILE_BYTES + 1))
    with pytest.raises(ConfigError, match="is larger than 1000 KB"):
        _yaml.read_text(path, what="thresholds file", flag="--emrd-thresholds")
    path.write_bytes(b"#" * _yaml.MAX_FILE_BYTES)
    assert len(_yaml.read_text(path, what="thresholds file", flag="--emrd-thresholds")) == (
        _yaml.MAX_FILE_BYTES
    )
