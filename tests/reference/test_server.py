"""The reference server over real loopback sockets: routes, errors, determinism."""

from __future__ import annotations

import json
from collections.abc import Iterator

import httpx
import pytest

from pytest_emrd.agent import REFERENCE_VERSION, build_system_prompt, parse_reply, step_text
from pytest_emrd.reference import ReferenceServer, reference_base_url
from pytest_emrd.trajectory import Pose
from pytest_emrd.world import VisibleObject
from pytest_emrd.world._feedback import with_pose


@pytest.fixture(scope="module")
def server() -> Iterator[ReferenceServer]:
    with ReferenceServer() as running:
        yield running


def _body(inventory, model: str = "scout", *, symbolic: bool = True) -> dict:
    visible = [
        VisibleObject("DiningTable_1", "DiningTable", 0.0, 3.0),
        VisibleObject("Chair_3", "Chair", -20.0, 2.5),
        VisibleObject("Doorway_1", "Doorway", 30.0, 4.0),
    ]
    text = step_text(
        step=1,
        max_steps=50,
        feedback=with_pose("Episode started.", Pose(0.0, 0.0, 0.0)),
        visible=visible if symbolic else None,
    )
    return {
        "model": model,
        "messages": [
            {"role": "system", "content": build_system_prompt(inventory, "default")},
            {
                "role": "user",
                "content": [
                    {"type": "text", "text": text},
                    {"type": "image_url", "image_url": {"url": "data:image/jpeg;base64,QUJD"}},
                ],
            },
        ],
        "temperature": 0.0,
        "max_tokens": 4096,
    }


def test_models_route_lists_reference_agents(server) -> None:
    data = httpx.get(f"{server.base_url}/models").json()
    ids = {m["id"] for m in data["data"]}
    assert {f"{n}@{REFERENCE_VERSION}" for n in ("scout", "scout-serial", "prior")} <= ids
    assert not any(i.startswith("gemini") for i in ids)


@pytest.mark.parametrize(
    "model", [f"scout@{REFERENCE_VERSION}", "scout"], ids=["versioned", "bare-name"]
)
def test_current_version_and_bare_names_are_served(server, inventory, model) -> None:
    response = httpx.post(f"{server.base_url}/chat/completions", json=_body(inventory, model))
    assert response.status_code == 200
    assert response.json()["model"] == model


def test_bare_and_versioned_names_get_the_same_reply(server, inventory) -> None:
    url = f"{server.base_url}/chat/completions"
    bare = httpx.post(url, json=_body(inventory, "scout-decay-3")).json()
    versioned = httpx.post(url, json=_body(inventory, f"scout-decay-3@{REFERENCE_VERSION}")).json()
    assert bare["choices"] == versioned["choices"]


def test_scout_first_reply_is_a_compact_protocol_reply(server, inventory) -> None:
    response = httpx.post(f"{server.base_url}/chat/completions", json=_body(inventory))
    assert response.status_code == 200
    data = response.json()
    content = data["choices"][0]["message"]["content"]
    assert content == json.dumps(json.loads(content), separators=(",", ":"))
    reply = parse_reply(content)
    assert reply.error is None and reply.action == "Turn(Right)"
    assert {e.label for e in reply.cognitive_map} == {"DiningTable_1", "Chair_3", "Doorway_1"}
    table = next(e for e in reply.cognitive_map if e.label == "DiningTable_1")
    assert (table.x, table.z, table.room) == (0.0, 3.0, "Conference Room")
    assert data["usage"]["prompt_tokens"] > 255 and data["usage"]["completion_tokens"] > 0


def test_same_request_same_bytes(server, inventory) -> None:
    body = _body(inventory, "scout-decay-3")
    first = httpx.post(f"{server.base_url}/chat/completions", json=body)
    second = httpx.post(f"{server.base_url}/chat/completions", json=body)
    assert first.content == second.content


@pytest.mark.parametrize(
    ("model", "symbolic", "raw", "status", "needle"),
    [
        ("gpt-9", True, None, 404, "not in the registry"),
        ("gemini", True, None, 404, "not a reference agent"),
        ("scout@ref-1", True, None, 404, f"this pytest-emrd runs {REFERENCE_VERSION!r}"),
        ("scout", False, None, 400, "modality 'text' or 'both'"),
        ("scout", True, b"{not json", 400, "not JSON"),
        ("scout", True, b'{"model": "scout"}', 400, "'messages' list"),
    ],
    ids=[
        "unknown-model",
        "vlm-name",
        "stale-version",
        "vision-only",
        "garbage-body",
        "no-messages",
    ],
)
def test_bad_requests(server, inventory, model, symbolic, raw, status, needle) -> None:
    url = f"{server.base_url}/chat/completions"
    if raw is None:
        response = httpx.post(url, json=_body(inventory, model, symbolic=symbolic))
    else:
        response = httpx.post(url, content=raw, headers={"Content-Type": "application/json"})
    assert response.status_code == status
    assert needle in response.json()["error"]["message"]


def test_unknown_route(server) -> None:
    assert httpx.get(f"{server.base_url}/nope").status_code == 404


def test_shared_server_is_started_once() -> None:
    url = reference_base_url()
    assert url == reference_base_url()
    assert url.startswith("http://127.0.0.1:") and url.endswith("/v1")
    assert json.loads(httpx.get(f"{url}/models").content)["object"] == "list"
