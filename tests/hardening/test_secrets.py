"""Probe 1 and 6 end to end: credentials planted in the URL query, a header, ``extra_body`` and
an echoed 401 body never reach a cassette, the results, junit, a report or the terminal (DEBUG
live logs of httpx and httpcore included), raw, URL-encoded or base64; the printed record
command works verbatim for a model of a user registry."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd._scrub import (
    REDACTED,
    encoded_forms,
    scrub,
    scrub_bytes,
    scrub_uri,
    secret_values,
    watch_env,
)
from pytest_emrd.agent import load_registry
from pytest_emrd.cli import main as emrd
from pytest_emrd.episode import capped_reply, run_episode
from pytest_emrd.trajectory import EpisodeSpec

from .conftest import (
    HUGE_CHARS,
    KEY_ENV,
    PLANTED_HEADER,
    PLANTED_KEY,
    PLANTED_PASSWORD,
    PLANTED_QUERY,
    leaks,
    leaky_registry,
    text_leaks,
)

ROOT = Path(__file__).resolve().parents[2]
GRID = ["-p", "no:cacheprovider", "--emrd-condition=baseline", "--emrd-spawn=office"]


def _outputs(*results: pytest.RunResult) -> str:
    return "\n".join(r.stdout.str() + r.stderr.str() for r in results)


@pytest.mark.slow
def test_a_recorded_run_leaks_no_planted_credential(
    sandbox, provider, planted_env, capsys, monkeypatch
):
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    sandbox.makefile(".yaml", thresholds="leaky:\n  baseline:\n    errored_rate: {max: 0.0}\n")
    registry = sandbox.path / "user-models.yaml"
    leaky_registry(registry, provider, leaky="ok", denied="deny", rejected="fail")
    models = f"--emrd-models={registry}"

    # Replay only, nothing recorded: one summary and one command, which works verbatim.
    missing = sandbox.runpytest(
        *GRID, models, "--emrd-model=leaky", "--emrd-episodes=1", "--emrd-record-mode=none"
    )
    assert missing.ret != 0
    (line,) = [x for x in _outputs(missing).splitlines() if "have no cassette" in x]
    command = line.split("Record them all with: ", 1)[1]
    assert f"--emrd-models={registry}" in command and "--emrd-modality=text" in command
    args = shlex.split(command)
    assert args[0] == "pytest"
    recorded = sandbox.run(sys.executable, "-m", *args, "--log-cli-level=DEBUG")
    assert recorded.ret == 0, _outputs(recorded)
    recorded.stdout.fnmatch_lines(["*1 passed, 1 deselected*"])
    cassette = sandbox.path / "cassettes/leaky/baseline/default/office/ep00.json.xz"
    assert cassette.is_file()

    # Replay the recording, and a model whose endpoint answers 401 echoing the key.
    summary = sandbox.path / "step-summary.md"
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(summary))
    run = sandbox.runpytest(
        *GRID,
        models,
        "--emrd-model=leaky",
        "--emrd-model=denied",
        "--emrd-model=rejected",
        "--emrd-episodes=1",
        "--emrd-preflight=off",  # here: what an episode that meets a 401 writes
        f"--emrd-results={sandbox.path / 'run'}",
        f"--junitxml={sandbox.path / 'junit.xml'}",
        "--log-cli-level=DEBUG",
        f"--log-file={sandbox.path / 'debug.log'}",
        "--log-file-level=DEBUG",
    )
    run.assert_outcomes(passed=2, failed=2)
    failures = [x for x in run.stdout.lines if x.startswith("FAILED test_emrd.py")]
    assert [x.split("[")[1].split("]")[0] for x in failures] == [
        "denied-baseline-office-ep00",
        "rejected-baseline-office-ep00",
    ]
    for name, status in (("denied", 401), ("rejected", 500)):
        stored = (sandbox.path / f"run/episodes/{name}-baseline-office-ep00.json").read_text()
        assert f"HTTP {status}" in stored and "token <redacted>" in stored
    on_the_wire = "\n".join(provider.seen)
    assert f"Bearer {PLANTED_KEY}" in on_the_wire and f"key={PLANTED_QUERY}" in on_the_wire
    assert PLANTED_HEADER in on_the_wire
    assert "Basic " not in on_the_wire  # no userinfo: the Bearer key is what is sent
    assert "HTTP Request: POST http://127.0.0.1" in _outputs(recorded)  # httpx logged, scrubbed

    capsys.readouterr()
    run_dir, thresholds = str(sandbox.path / "run"), str(sandbox.path / "thresholds.yaml")
    report = ["report", run_dir, "--out", str(sandbox.path / "report"), "--models", str(registry)]
    assert emrd(report) == 0
    assert emrd(["gate", run_dir, "--thresholds", thresholds, "--models", str(registry)]) == 0
    printed = capsys.readouterr()

    assert (sandbox.path / "report").is_dir() and (sandbox.path / "junit.xml").is_file()
    assert "denied" in summary.read_text()
    assert leaks(sandbox.path, skip=(registry,)) == []
    assert text_leaks(_outputs(missing, recorded, run) + printed.out + printed.err) == []


def test_scrub_removes_each_kind_of_credential(planted_env):
    watch_env([KEY_ENV])
    text = (
        f"POST http://u:{PLANTED_PASSWORD}@h.example/v1/x?alt=sse&key={PLANTED_QUERY} failed: "
        f'{{"error": "bad key {PLANTED_KEY}"}} headers {{"x-api-key": "sk-other-123456789"}} '
        "Authorization: Bearer sk-another-abcdefgh"
    )
    assert scrub(text) == (
        f"POST http://{REDACTED}@h.example/v1/x?alt=sse&key={REDACTED} failed: "
        f'{{"error": "bad key {REDACTED}"}} headers {{"x-api-key": "{REDACTED}"}} '
        f"Authorization: Bearer {REDACTED}"
    )
    uri = f"https://u:{PLANTED_PASSWORD}@h.example/v1/m?key={PLANTED_QUERY}&sig=s&alt=sse"
    assert scrub_uri(uri) == "https://h.example/v1/m?alt=sse"
    assert scrub_bytes(b"\xff" + PLANTED_KEY.encode()) == b"\xff" + REDACTED.encode()


@given(st.lists(st.text(min_size=1, max_size=9), max_size=4), st.data())
def test_scrub_bytes_replaces_each_key_value_in_turn(secrets, data):
    pieces = st.sampled_from([s.encode() for s in secrets]) | st.binary(max_size=6)
    raw = b"".join(data.draw(st.lists(pieces if secrets else st.binary(max_size=6))))
    expected = raw
    for secret in secrets:
        expected = expected.replace(secret.encode(), REDACTED.encode())
    assert scrub_bytes(raw, literal_only=True, secrets=secrets) == expected


def test_only_values_long_enough_to_be_keys_are_scrubbed():
    env = {"A_API_KEY": "1", "B_TOKEN": "tok-123456", "PATH": "/usr/bin:/bin", "MY": "x" * 20}
    assert set(secret_values(env)) == set(encoded_forms("tok-123456"))
    assert set(encoded_forms("tok-123456")) >= {"tok-123456", "dG9rLTEyMzQ1Ng==", "dG9rLTEyMzQ1Ng"}
    assert scrub("see https://example.com/a?b=c#d, x=1.00 z=2.00") == (
        "see https://example.com/a?b=c#d, x=1.00 z=2.00"
    )


def test_a_20_mb_reply_is_a_parse_failure_with_a_truncated_copy(tmp_path, provider, planted_env):
    registry = load_registry(leaky_registry(tmp_path / "m.yaml", provider, huge="huge"))
    spec = EpisodeSpec("huge", "baseline", "office", 0, modality="text", max_steps=2)
    trajectory = run_episode(spec, registry=registry)
    assert trajectory.status == "budget" and len(trajectory.steps) == 2
    for step in trajectory.steps:
        assert step.parse_error == f"reply of {HUGE_CHARS} characters exceeds 200000"
        assert step.raw_reply == capped_reply("x" * HUGE_CHARS)
        assert step.raw_reply.endswith(f"[... truncated: the reply had {HUGE_CHARS} characters]")
        assert len(step.raw_reply) < 200_100


def test_a_fallback_url_is_redacted_like_the_variable_it_stands_for(tmp_path, monkeypatch):
    """Recorded with ``MY_VLM_BASE_URL`` set, replayed in CI without it: both requests must
    read ``<redacted>/chat/completions``, or the replay matches nothing."""
    registry = tmp_path / "models.yaml"
    registry.write_text(
        "models:\n  mine:\n    provider: openai\n    model_id: m\n"
        '    base_url: "${MY_VLM_BASE_URL:-https://vlm.example.com/v1}"\n'
        "    env: [MY_VLM_BASE_URL]\n    api_key_env: MY_KEY\n    api_key_required: false\n"
    )
    monkeypatch.setenv("MY_VLM_BASE_URL", "http://127.0.0.1:9/v1")
    recorded = load_registry(registry).get("mine").base_url
    recorded_uri = scrub_uri(f"{recorded}/chat/completions")
    monkeypatch.delenv("MY_VLM_BASE_URL")
    replayed = load_registry(registry).get("mine").base_url
    assert replayed == "https://vlm.example.com/v1"
    assert scrub_uri(f"{replayed}/chat/completions") == recorded_uri
    assert recorded_uri == f"{REDACTED}/chat/completions"
