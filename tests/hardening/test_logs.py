"""Probe: ``pytest --log-cli-level=DEBUG`` (and a DEBUG log file) with the plugin loaded prints
no planted secret, raw, URL-encoded or base64: httpx's request line, httpcore's traces and a
user's own log call all pass the scrub filter. Without the plugin the same run leaks (the
probe can see a leak)."""

from __future__ import annotations

import logging

from pytest_emrd._scrub import REDACTED, SCRUB_FILTER, watch_env
from tests._sandbox import Sandbox

from .conftest import KEY_ENV, PLANTED_FORMS, PLANTED_KEY, PLANTED_QUERY, text_leaks

#: A credential-like name: scrubbed without a registry (this session has no EMRD test).
LOG_KEY_ENV = "HARDENING_LOG_API_KEY"

TEST_FILE = """
import base64, logging, os
import httpx

def test_posts_with_secrets():
    url = "{url}/chat/completions?key={query}&api-version=1"
    key = os.environ["{env}"]
    with httpx.Client() as client:
        client.post(url, json={{"m": 1}}, headers={{"Authorization": f"Bearer {{key}}"}})
    log = logging.getLogger("user.code")
    log.warning("calling %s with %s", url, key)
    log.debug("encoded %s", base64.b64encode(key.encode()).decode())
    try:
        raise RuntimeError(f"failed for {{url}}")
    except RuntimeError:
        log.exception("boom")
"""


def _run(sandbox: Sandbox, json_server, monkeypatch, *plugin: str) -> str:
    monkeypatch.setenv(LOG_KEY_ENV, PLANTED_KEY)
    server = json_server(lambda method, path, body: (200, {"ok": True}))
    sandbox.makepyfile(
        test_leak=TEST_FILE.format(url=server.rstrip("/"), query=PLANTED_QUERY, env=LOG_KEY_ENV)
    )
    log_file = sandbox.path / "debug.log"
    result = sandbox.runpytest(
        "-p", "no:cacheprovider", *plugin, "--log-cli-level=DEBUG",
        f"--log-file={log_file}", "--log-file-level=DEBUG", "-rA",
    )  # fmt: skip
    result.assert_outcomes(passed=1)
    return result.stdout.str() + result.stderr.str() + log_file.read_text()


def test_debug_logs_carry_no_planted_secret(sandbox, json_server, monkeypatch):
    printed = _run(sandbox, json_server, monkeypatch)
    assert "HTTP Request: POST" in printed and f"key={REDACTED}" in printed
    assert "Traceback" in printed and "receive_response_headers" in printed
    assert text_leaks(printed) == []


def test_without_the_plugin_the_same_run_leaks(sandbox, json_server, monkeypatch):
    printed = _run(sandbox, json_server, monkeypatch, "-p", "no:emrd")
    assert PLANTED_QUERY in printed


def test_the_filter_scrubs_arguments_tracebacks_and_keeps_every_record(monkeypatch):
    monkeypatch.setenv(KEY_ENV, PLANTED_KEY)
    watch_env([KEY_ENV])
    try:
        raise ValueError(f"bad key {PLANTED_KEY}")
    except ValueError as exc:
        error = exc
    args = ("http://h/x?key=abcdefgh1", PLANTED_KEY)
    exc_info = (ValueError, error, error.__traceback__)
    record = logging.LogRecord("httpx", logging.INFO, __file__, 1, "POST %s key %s", args, exc_info)
    assert SCRUB_FILTER.filter(record) is True
    text = logging.Formatter().format(record)
    assert f"POST http://h/x?key={REDACTED} key {REDACTED}" in text and "ValueError" in text
    assert [form for form in PLANTED_FORMS if form in text] == []
