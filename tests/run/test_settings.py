"""Option precedence (command line > ini > default) and validation, resolved in one place."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.run import MatchingWarning, resolve_settings

ROOT = Path("/repo")


def _resolve(cli=None, ini=None, env=None):
    return resolve_settings(cli or {}, ini or {}, rootdir=ROOT, env=env or {})


def test_defaults_are_the_papers_grid_for_the_reference_agents():
    s = _resolve()
    assert s.models == ("scout", "mimic")
    assert s.conditions == ("baseline", "low_light", "texture")
    assert s.cells == (
        ("scout", "baseline"),
        ("scout", "low_light"),
        ("scout", "texture"),
        ("mimic", "baseline"),
    )
    assert s.spawns == ("office", "conference", "kitchen", "entrance")
    assert (s.episodes, s.variant, s.backend, s.modality) == (20, "default", "builtin", None)
    assert (s.record_mode, s.matching, s.shard) == ("once", "strict", None)
    assert s.thresholds is None, "/repo/thresholds.yaml does not exist: no gates"
    assert s.cassettes == ROOT / "cassettes"


def test_thresholds_default_to_the_rootdir_file_only_when_it_exists(tmp_path: Path):
    assert resolve_settings({}, {}, rootdir=tmp_path, env={}).thresholds is None
    (tmp_path / "thresholds.yaml").write_text("", encoding="utf-8")
    assert resolve_settings({}, {}, rootdir=tmp_path, env={}).thresholds == (
        tmp_path / "thresholds.yaml"
    )
    given = resolve_settings({"thresholds": "gates/x.yaml"}, {}, rootdir=tmp_path, env={})
    assert given.thresholds == tmp_path / "gates" / "x.yaml", "a given file is kept (and checked)"


@pytest.mark.parametrize(
    ("cli", "cells"),
    [
        pytest.param({"condition": ["low_light"]}, (("scout", "low_light"),), id="default-models"),
        pytest.param({"condition": ["baseline"]}, (("scout", "baseline"), ("mimic", "baseline")),
                     id="default-models-baseline"),
        pytest.param({"model": ["mimic"]}, (("mimic", "baseline"), ("mimic", "low_light"),
                                            ("mimic", "texture")), id="a-model-every-condition"),
        pytest.param({"model": ["gpt"], "condition": ["texture"]}, (("gpt", "texture"),),
                     id="explicit"),
    ],
)  # fmt: skip
def test_cells_are_the_product_of_what_was_selected(cli, cells):
    assert _resolve(cli).cells == cells


def test_ci_environment_defaults_to_replay_only():
    assert _resolve(env={"CI": "true"}).record_mode == "none"
    assert _resolve(cli={"record_mode": "once"}, env={"CI": "1"}).record_mode == "once"


@pytest.mark.parametrize(
    ("cli", "ini", "expected"),
    [
        ({}, {}, 20),
        ({}, {"episodes": "3"}, 3),
        ({"episodes": "2"}, {"episodes": "3"}, 2),
    ],
    ids=["default", "ini-over-default", "cli-over-ini"],
)
def test_precedence(cli, ini, expected):
    assert _resolve(cli, ini).episodes == expected


def test_concurrency_defaults_to_one_episode_at_a_time():
    assert _resolve().concurrency == 1
    assert _resolve({"concurrency": "16"}, {"concurrency": "4"}).concurrency == 16
    assert _resolve({}, {"concurrency": "4"}).concurrency == 4


def test_repeatable_and_comma_separated_models_are_deduplicated_in_order():
    s = _resolve({"model": ["gemini,gpt", "gemini", "scout"]})
    assert s.models == ("gemini", "gpt", "scout")


def test_paths_resolve_against_the_rootdir():
    s = _resolve(ini={"results": "runs/a", "cassettes": "/abs/c"})
    assert s.results == ROOT / "runs/a" and s.cassettes == Path("/abs/c")


@pytest.mark.parametrize(
    ("cli", "message"),
    [
        ({"condition": ["fog"]}, "--emrd-condition='fog' is not one of"),
        ({"spawn": ["attic"]}, "--emrd-spawn='attic'"),
        ({"episodes": "0"}, "--emrd-episodes=0 must be a whole number >= 1"),
        ({"episodes": "many"}, "--emrd-episodes='many'"),
        ({"record_mode": "sometimes"}, "--emrd-record-mode='sometimes'"),
        ({"matching": "fuzzy"}, "--emrd-matching='fuzzy'"),
        ({"shard": "3/2"}, "needs 1 <= K <= N"),
        ({"shard": "half"}, "must look like K/N"),
        ({"backend_option": ["gpu_device"]}, "--emrd-backend-option='gpu_device' must look like"),
        ({"backend_option": ["gpu device=1"]}, "KEY a Python identifier"),
        ({"backend_option": ["=1"]}, "--emrd-backend-option='=1'"),
        ({"concurrency": "0"}, "--emrd-concurrency=0 must be a whole number >= 1"),
        ({"concurrency": "4", "backend": "ai2thor"}, "does not support; use -n N instead"),
    ],
    ids=[
        "condition",
        "spawn",
        "episodes-zero",
        "episodes-word",
        "record-mode",
        "matching",
        "shard-order",
        "shard-shape",
        "backend-option-no-value",
        "backend-option-bad-key",
        "backend-option-no-key",
        "concurrency-zero",
        "concurrency-thor",
    ],
)
def test_bad_options_name_the_option_and_value(cli, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")):
        _resolve(cli)


@pytest.mark.parametrize(
    ("cli", "ini", "expected"),
    [
        ({}, {}, "strict"),
        ({"backend": "ai2thor"}, {}, "lenient"),
        ({}, {"backend": "ai2thor"}, "lenient"),
        ({"backend": "ai2thor", "matching": "lenient"}, {}, "lenient"),
        ({"backend": "builtin", "matching": "lenient"}, {}, "lenient"),
        ({"backend": "builtin"}, {"backend": "ai2thor", "matching": "lenient"}, "lenient"),
    ],
    ids=[
        "builtin-default",
        "ai2thor-default",
        "ai2thor-from-ini",
        "ai2thor-explicit",
        "builtin-explicit",
        "ini-matching-cli-backend",
    ],
)
def test_matching_default_follows_the_backend(cli, ini, expected, recwarn):
    assert _resolve(cli, ini).matching == expected
    assert not [w for w in recwarn if issubclass(w.category, MatchingWarning)]


def test_explicit_strict_on_ai2thor_is_allowed_and_warns():
    with pytest.warns(MatchingWarning, match="--emrd-matching=strict with --emrd-backend=ai2thor"):
        s = _resolve({"backend": "ai2thor", "matching": "strict"})
    assert s.matching == "strict"


def test_backend_options_read_json_values_and_keep_text():
    s = _resolve(
        {
            "backend_option": [
                "local_executable_path=/opt/thor/thor-Linux64",
                "gpu_device=1",
                "start_timeout=2.5",
                "allow_download=true",
                "note=a=b,c",
                "gpu_device=2",
            ]
        }
    )
    assert s.backend_options[0] == ("local_executable_path", "/opt/thor/thor-Linux64")
    assert s.backend_kwargs == {
        "local_executable_path": "/opt/thor/thor-Linux64",
        "gpu_device": 2,
        "start_timeout": 2.5,
        "allow_download": True,
        "note": "a=b,c",
    }


def test_backend_options_from_the_ini_unless_given_on_the_command_line():
    ini = {"backend_option": ["gpu_device=1", "x_display=:0"]}
    assert _resolve({}, ini).backend_kwargs == {"gpu_device": 1, "x_display": ":0"}
    assert _resolve({"backend_option": ["gpu_device=3"]}, ini).backend_kwargs == {"gpu_device": 3}
    assert _resolve().backend_options == ()
