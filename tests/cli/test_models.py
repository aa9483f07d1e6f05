"""``emrd models`` and ``emrd --version``: what a new user asks first."""

from __future__ import annotations

import json

import pytest

from pytest_emrd import __version__
from pytest_emrd.cli import main

FAKE_KEY = "sk-planted-0123456789abcdef"


def test_models_lists_the_registry_with_key_state_never_the_key(capsys, monkeypatch):
    monkeypatch.setenv("GEMINI_API_KEY", FAKE_KEY)
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    assert FAKE_KEY not in out
    rows = {line.split()[0]: line for line in out.splitlines()[1:] if line.strip()}
    assert "GEMINI_API_KEY set" in rows["gemini"]
    assert "OPENAI_API_KEY missing" in rows["gpt"]
    assert rows["scout"].split()[1:3] == ["reference", "both"]
    assert "anthropic" in rows["claude"] and "$5" in rows["claude"]
    assert "scout-decay-<mean steps>" in out


def test_models_json_and_a_user_registry(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("MY_VLM_KEY", FAKE_KEY)
    user = tmp_path / "models.yaml"
    user.write_text(
        "models:\n  my-vlm:\n    provider: openai\n    base_url: http://127.0.0.1:9/v1\n"
        "    model_id: org/my-vlm\n    api_key_env: MY_VLM_KEY\n    modality: text\n",
        encoding="utf-8",
    )
    assert main(["models", "--models", str(user), "--json"]) == 0
    out = capsys.readouterr().out
    assert FAKE_KEY not in out
    row = next(r for r in json.loads(out) if r["name"] == "my-vlm")
    assert (row["provider"], row["modality"], row["key"]) == ("openai", "text", "set")
    assert row["price_per_mtok_in"] is None


@pytest.mark.parametrize("as_json", [False, True], ids=["table", "json"])
def test_models_prints_endpoints_without_their_keys(capsys, monkeypatch, tmp_path, as_json):
    monkeypatch.setenv("MY_VLM_KEY", FAKE_KEY)
    monkeypatch.setenv("MY_VLM_HOST", f"http://127.0.0.1:9/v1?key={FAKE_KEY}")
    user = tmp_path / "models.yaml"
    user.write_text(
        "models:\n"
        "  google: {provider: openai, model_id: g, base_url: 'https://g.example/v1?key=AIzaQUERY1'}\n"
        "  azure: {provider: openai, model_id: a, base_url: '${MY_VLM_HOST}',"
        " env: [MY_VLM_HOST]}\n",
        encoding="utf-8",
    )
    assert main(["models", "--models", str(user), *(["--json"] if as_json else [])]) == 0
    out = capsys.readouterr().out
    assert FAKE_KEY not in out and "AIzaQUERY1" not in out
    assert "https://g.example/v1?key=<redacted>" in out
    assert "http://127.0.0.1:9" not in out  # a declared variable's whole value is a secret


def test_version_names_the_package_and_the_protocol(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"emrd {__version__} (protocol builtin-")
    assert "reference agents ref-" in out
