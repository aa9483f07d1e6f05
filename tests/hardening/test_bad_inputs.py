"""Probes 4 and 6: hostile registry files, thresholds files and options. Each ends in one line
naming the file (and line) or the option and the fix, in the library and in ``emrd``; no line
echoes a planted secret, and no line is changed by the scrubber (it would hide the fix)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from pytest_emrd._files import check_inside
from pytest_emrd._scrub import scrub, watch_env
from pytest_emrd._yaml import MAX_DEPTH, MAX_FILE_BYTES
from pytest_emrd.agent import load_registry
from pytest_emrd.cli import main as emrd
from pytest_emrd.errors import ConfigError
from pytest_emrd.gate import load_thresholds
from pytest_emrd.metrics import GATE_METRICS
from pytest_emrd.run import resolve_settings

from .conftest import KEY_ENV, PLANTED_FORMS, PLANTED_KEY, PLANTED_PASSWORD, PLANTED_QUERY

OK = "provider: openai, model_id: x, base_url: 'http://h.example/v1'"
BOMB = "models:\n  m:\n    provider: reference\n    planted: &a [1, 1]\n    x: &b [*a, *a]\n"

#: Credential headers a registry once accepted with a literal value.
CREDENTIAL_HEADERS = (
    "Cookie",
    "Proxy-Authorization",
    "X-Auth-Token",
    "X-API-Token",
    "Ocp-Apim-Subscription-Key",
    "X-Amz-Security-Token",
)
YAML_TAGS = [
    ("local", "!foo", "!foo"),
    ("python-object", "!!python/object/apply:os.system", "!!python/object/apply:os.system"),
    ("binary", "!!binary", "!!binary"),
]

REGISTRY_PROBES = [
    pytest.param(
        f"models:\n  m: {{provider: openai, model_id: x, "
        f"base_url: 'http://user:{PLANTED_PASSWORD}@h.example/v1?key={PLANTED_QUERY}'}}\n",
        "line 2: model 'm': base_url carries a user name or password before '@' "
        "(http://<redacted>@h.example/v1?key=<redacted>); remove it: the key goes in the "
        "environment variable named by api_key_env, which is sent in the Authorization header, "
        "as a Bearer token.",
        id="userinfo-in-base-url",
    ),
    pytest.param(
        "models:\n  m: {provider: anthropic, model_id: x, base_url: 'https://u:p@h.example'}\n",
        "sent in the x-api-key header.",
        id="userinfo-anthropic",
    ),
    pytest.param(
        "models:\n  m: {provider: openai, model_id: x, base_url: 'ftp://h.example/v1'}\n",
        "line 2: model 'm': base_url='ftp://h.example/v1' must be an http:// or https:// URL "
        "with a host, e.g. https://api.example.com/v1.",
        id="base-url-not-http",
    ),
    *(
        pytest.param(
            f"models:\n  '{name}': {{{OK}}}\n",
            f"line 2: name {name!r} is not a plain name (a model name is a cassette folder and "
            "part of every episode file name); use 1-100 letters, digits, '.', '_' or '-', "
            "starting with a letter or digit.",
            id=f"name-{ident}",
        )
        for ident, name in [
            ("parent-traversal", "../../evil"),
            ("absolute", "/tmp/evil"),
            ("separator", "a/b"),
            ("backslash", "a\\\\b"),
            ("dot-dot", ".."),
            ("hidden", ".git"),
            ("space", "my model"),
        ]
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: {{api_key: sk-literal-value-1234}}}}\n",
        "line 2: model 'm': extra_body.api_key looks like a credential and is written out; a "
        "request body is stored in every cassette, so write the value as an environment "
        "variable reference, ${MY_SECRET}, and export MY_SECRET (its value is then removed "
        "from every file and log).",
        id="extra-body-api-key",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: {{auth: {{client_secret: s3cr3t-lit}}}}}}\n",
        "extra_body.auth looks like a credential",
        id="extra-body-nested-secret",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: {{password: '${{PW:-hunter2-default}}'}}}}\n",
        "extra_body.password looks like a credential and is written out",
        id="extra-body-secret-as-a-default",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: {{options: [{{access_token: tok-lit-1}}]}}}}\n",
        "extra_body.options[0].access_token looks like a credential",
        id="extra-body-secret-in-list",
    ),
    pytest.param(
        "models:\n  m: {provider: openai, model_id: x, base_url: '${EMRD_UNSET_BASE}/v1', "
        "env: [EMRD_UNSET_BASE]}\n",
        "line 2: model 'm': base_url needs the environment variable EMRD_UNSET_BASE, which is "
        "not set; export EMRD_UNSET_BASE=..., or write ${EMRD_UNSET_BASE:-default} for a "
        "fallback.",
        id="unset-env-var",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_headers: {{X-Org: 12345678901234}}}}\n",
        "line 2: model 'm': extra_headers.X-Org must be a string, got int; quote the value in "
        "the registry file.",
        id="header-not-string",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_headers: {{x-api-key: '{PLANTED_KEY}'}}}}\n",
        "line 2: model 'm': extra_headers may not carry the credential header x-api-key; keys "
        "come only from the environment variable named by api_key_env.",
        id="credential-header",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: [{PLANTED_KEY}]}}\n",
        "line 2: model 'm': extra_body must be a mapping of name -> value, got list.",
        id="extra-body-not-mapping",
    ),
    pytest.param(
        BOMB,
        "line 5: YAML alias *a is not allowed in this file (aliases can expand a small file "
        "without bound); write the value out in full.",
        id="alias-bomb",
    ),
    pytest.param(
        "models:\n  m: " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1) + "\n",
        f"line 2: YAML nested more than {MAX_DEPTH} levels deep; flatten it (a thresholds file "
        "or model registry needs five levels).",
        id="deep-nesting",
    ),
    pytest.param(
        "models:\n  m: [" + "[" * 200_000 + "\n",
        f"YAML nested more than {MAX_DEPTH} levels deep",
        id="crash-deep-nesting",
    ),
    *(
        pytest.param(
            f"models:\n  m: {{{OK}, extra_headers: {{{header}: '{PLANTED_KEY}'}}}}\n",
            f"line 2: model 'm': extra_headers.{header} looks like a credential and is written "
            "out; write it as a reference to a declared variable, ${MY_SECRET} with "
            "env: [MY_SECRET], and export MY_SECRET (its value is then removed from every "
            "file and log).",
            id=f"literal-header-{header}",
        )
        for header in CREDENTIAL_HEADERS
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_headers: {{X-Exfil: '${{{KEY_ENV}}}'}}}}\n",
        f"line 2: model 'm': extra_headers.X-Exfil uses ${{{KEY_ENV}}}, which the model does not "
        f"declare; add env: [{KEY_ENV}] to the model (an entry reads only the variables it "
        "declares, and their values are then removed from every file and log).",
        id="undeclared-variable",
    ),
    *(
        pytest.param(
            f"models:\n  m:\n    provider: openai\n    model_id: x\n    timeout_s: {tag} 3\n",
            f"line 5: YAML tag {shown} is not allowed in this file (it holds plain data); "
            "remove the tag and write the value itself.",
            id=f"tag-{ident}",
        )
        for ident, tag, shown in YAML_TAGS
    ),
    pytest.param(
        'models:\n  m: {provider: openai, model_id: x, base_url: "http://h.example/v1\\r\\nX"}\n',
        "line 2: model 'm': base_url holds the control character '\\r' at offset 19; remove it",
        id="crlf-in-base-url",
    ),
    *(
        pytest.param(
            f'models:\n  m: {{provider: openai, base_url: "http://h", model_id: "gpt{char}x"}}\n',
            f"line 2: model 'm': model_id holds the control character {shown} at offset 3",
            id=f"control-in-model-id-{ident}",
        )
        for ident, char, shown in [("nul", "\\0", "'\\x00'"), ("esc", "\\e", "'\\x1b'")]
    ),
    pytest.param(
        f"models:\n  m: {{{OK}}}\n  m: {{{OK}, model_id: y}}\n",
        "line 3: 'm' appears twice in one mapping (the last would win unseen); keep one.",
        id="duplicate-model",
    ),
    pytest.param(
        f"models:\n  m: {{{OK}, extra_body: {{since: 2026-01-01}}}}\n",
        "line 2: model 'm': extra_body is not JSON (Object of type date is not JSON serializable)",
        id="extra-body-date",
    ),
    pytest.param(
        "# " + "x" * MAX_FILE_BYTES + "\n",
        "is larger than 1000 KB, more than such a file ever needs; pass the right file with "
        "--emrd-models (emrd gate --models).",
        id="huge-file",
    ),
]


def _one_line(message: str, path: Path, fragment: str) -> None:
    assert "\n" not in message and str(path) in message and fragment in message, message
    assert scrub(message) == message, "the scrubber would change the line"
    assert [form for form in PLANTED_FORMS if form in message] == []


@pytest.mark.parametrize(("content", "fragment"), REGISTRY_PROBES)
def test_a_hostile_registry_is_one_line_in_the_library_and_in_emrd(
    tmp_path, capsys, monkeypatch, content, fragment
):
    monkeypatch.delenv("EMRD_UNSET_BASE", raising=False)
    monkeypatch.setenv(KEY_ENV, PLANTED_KEY)
    watch_env([KEY_ENV])
    path = tmp_path / "models.yaml"
    path.write_text(content)
    with pytest.raises(ConfigError) as info:
        load_registry(path)
    _one_line(str(info.value), path, fragment)
    assert emrd(["models", "--models", str(path)]) == 2
    assert capsys.readouterr().err == f"emrd models: error: {info.value}\n"


def test_a_credential_in_extra_body_is_accepted_as_a_reference_and_then_watched(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("EMRD_BODY_REF", "body-secret-value-77")
    path = tmp_path / "models.yaml"
    path.write_text(
        f"models:\n  m: {{{OK}, extra_body: {{api_key: '${{EMRD_BODY_REF}}'}}, "
        "env: [EMRD_BODY_REF]}\n"
    )
    assert load_registry(path).get("m").extra_body == {"api_key": "body-secret-value-77"}
    assert scrub("sent body-secret-value-77") == "sent <redacted>"


THRESHOLD_PROBES = [
    pytest.param("", "holds no gate, so a run would pass with nothing checked", id="empty"),
    pytest.param("# later\n", "holds no gate", id="only-comments"),
    pytest.param(
        "scout: &s\n  baseline:\n    aec: {min: 0.5}\nmimic: *s\n",
        "line 4: YAML alias *s is not allowed",
        id="alias",
    ),
    *(
        pytest.param(
            f"scout:\n  baseline:\n    aec: {{min: {tag} 0.5}}\n",
            f"line 3: YAML tag {shown} is not allowed in this file",
            id=f"tag-{ident}",
        )
        for ident, tag, shown in YAML_TAGS
    ),
    pytest.param(
        "scout:\n  baseline:\n    aec: {min: 0.5}\n  baseline:\n    aec: {min: 0.1}\n",
        "line 4: 'baseline' appears twice in one mapping",
        id="duplicate-condition",
    ),
    pytest.param(
        "scout:\n  baseline:\n    aec: {min: 0.5}\n" + "#" * (50 * MAX_FILE_BYTES),
        "is larger than 1000 KB",
        id="50-mb-file",
    ),
]


@pytest.mark.parametrize(("content", "fragment"), THRESHOLD_PROBES)
def test_a_hostile_thresholds_file_is_one_line_quickly(tmp_path, capsys, content, fragment):
    path = tmp_path / "thresholds.yaml"
    path.write_text(content)
    start = time.perf_counter()
    with pytest.raises(ConfigError) as info:
        load_thresholds(path, registry=load_registry(), metrics=GATE_METRICS)
    assert time.perf_counter() - start < 1.0
    _one_line(str(info.value), path, fragment)
    run = tmp_path / "run"
    (run / "episodes").mkdir(parents=True)
    assert emrd(["gate", str(run), "--thresholds", str(path)]) == 2
    assert capsys.readouterr().err == f"emrd gate: error: {info.value}\n"


OPTION_PROBES = [
    pytest.param(
        {"concurrency": "1000"},
        "--emrd-concurrency=1000 is more than 32 threads per process; pass at most 32, and add "
        "processes with -n N for more.",
        id="concurrency-unbounded",
    ),
    pytest.param(
        {"shard": "0/0"},
        "--emrd-shard='0/0' splits the episodes into N=0 slices; N must be at least 1, e.g. "
        "--emrd-shard=1/4 for the first of four slices.",
        id="shard-0-of-0",
    ),
    pytest.param(
        {"shard": "3/2"},
        "--emrd-shard='3/2' needs 1 <= K <= N; the slices of N=2 are --emrd-shard=1/2 to "
        "--emrd-shard=2/2.",
        id="shard-beyond-n",
    ),
    pytest.param(
        {"model": ["../../evil"]},
        "--emrd-model: name '../../evil' is not a plain name (a model name is a cassette "
        "folder); use 1-100 letters, digits, '.', '_' or '-', starting with a letter or digit.",
        id="model-traversal",
    ),
    pytest.param(
        {"model": ["/etc"]}, "--emrd-model: name '/etc' is not a plain name", id="model-absolute"
    ),
]


@pytest.mark.parametrize(("cli", "message"), OPTION_PROBES)
def test_a_hostile_option_is_one_line_naming_it(tmp_path, cli, message):
    with pytest.raises(ConfigError) as info:
        resolve_settings(cli, {}, rootdir=tmp_path, env={})
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("root", "path", "inside"),
    [
        ("cassettes", "cassettes/scout/baseline/ep00.yaml.xz", True),
        ("cassettes", "cassettes/../elsewhere/ep00.yaml.xz", False),
        ("cassettes", "cassettes/../../etc/passwd", False),
        ("cassettes", "/etc/passwd", False),
        ("run", "run/episodes/a..b-baseline-office-ep00.json", True),
    ],
    ids=["inside", "sibling", "above", "absolute", "dots-in-a-name"],
)
def test_every_path_resolves_inside_its_root_or_is_refused(tmp_path, root, path, inside):
    base, full = tmp_path / root, tmp_path / path if not path.startswith("/") else Path(path)
    if inside:
        assert check_inside(base, full, what="cassette") == full
    else:
        with pytest.raises(ConfigError, match=f"^cassette {full} lies outside {base}; "):
            check_inside(base, full, what="cassette")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["gate", "{file}"],
            "emrd gate: error: RUN_DIR {file} is a file, not a run directory; pass the folder a "
            "pytest run wrote (--emrd-results DIR, or one under .emrd/runs); a thresholds file "
            "goes after --thresholds.",
        ),
        (["view", "{file}"], "emrd view: error: RUN_DIR {file} is a file, not a run directory"),
        (
            ["report", "{missing}"],
            "emrd report: error: RUN_DIR {missing} does not exist; pass the folder a pytest run "
            "wrote (--emrd-results DIR, or one under .emrd/runs).",
        ),
        (
            ["view", "{run}", "--out", "{file}/pages"],
            "emrd view: error: cannot write {file}/pages: a part of the path is a file, not a "
            "folder; move that file away or use another folder (--out DIR).",
        ),
    ],
    ids=["gate-given-a-file", "view-given-a-file", "report-missing-dir", "view-out-under-a-file"],
)
def test_emrd_commands_end_a_bad_path_in_one_line(tmp_path, capsys, argv, message):
    names = {"file": tmp_path / "thresholds.yaml", "missing": tmp_path / "gone",
             "run": tmp_path / "run"}  # fmt: skip
    names["file"].write_text("scout: {}\n")
    (names["run"] / "episodes").mkdir(parents=True)
    args = [a.format(**names) for a in argv]
    assert emrd(args) == 2
    err = capsys.readouterr().err
    assert err.startswith(message.format(**names)) and err.count("\n") == 1, err
