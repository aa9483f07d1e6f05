"""Re-derive the vendored provider request schemas (run by hand; the tests never touch the network).

OpenAI: ``CreateChatCompletionRequest`` and every schema it references, cut out of the published
OpenAPI document (github:openai/openai-openapi, ``openapi.yaml``) into one JSON Schema 2020-12
file; OpenAPI's ``nullable: true`` becomes a ``"null"`` alternative.

Anthropic: the official Python SDK's ``MessageCreateParamsNonStreaming`` TypedDict, turned into
JSON Schema by pydantic (the SDK's own dependency). Every TypedDict forbids unknown keys, as
the API does ("Extra inputs are not permitted"); ``user_profile_id`` and ``workspace_id`` are
dropped because the SDK sends them as headers, not in the body.

    python derive.py openai  PATH/TO/openapi.yaml  > openai_create_chat_completion_request.json
    python derive.py anthropic                     > anthropic_message_create_params.json
    (the second needs ``pip install anthropic==<version>`` in a scratch environment)
"""

from __future__ import annotations

import json
import sys
from typing import Any

_REF = "#/components/schemas/"


def _nullable(node: Any) -> Any:
    if isinstance(node, list):
        return [_nullable(v) for v in node]
    if not isinstance(node, dict):
        return node
    out = {k: _nullable(v) for k, v in node.items() if k != "nullable"}
    if "$ref" in out:
        out["$ref"] = out["$ref"].replace(_REF, "#/$defs/")
    if node.get("nullable") is True:
        kind = out.get("type")
        if isinstance(kind, str):
            out["type"] = [kind, "null"]
        elif isinstance(kind, list) and "null" not in kind:
            out["type"] = [*kind, "null"]
        elif kind is None:
            out = {"anyOf": [out, {"type": "null"}]}
    return out


def _refs(node: Any) -> set[str]:
    if isinstance(node, list):
        return set().union(*(_refs(v) for v in node)) if node else set()
    if not isinstance(node, dict):
        return set()
    found = {node["$ref"].removeprefix(_REF)} if "$ref" in node else set()
    return found.union(*(_refs(v) for v in node.values()))


def openai(spec_path: str) -> dict[str, Any]:
    import yaml

    with open(spec_path) as spec:
        schemas = yaml.safe_load(spec)["components"]["schemas"]
    todo, defs = ["CreateChatCompletionRequest"], {}
    while todo:
        name = todo.pop()
        if name not in defs:
            defs[name] = schemas[name]
            todo.extend(_refs(schemas[name]))
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$ref": "#/$defs/CreateChatCompletionRequest",
        "$defs": {k: _nullable(v) for k, v in sorted(defs.items())},
    }


def _closed(node: Any) -> Any:
    if isinstance(node, list):
        return [_closed(v) for v in node]
    if not isinstance(node, dict):
        return node
    out = {k: _closed(v) for k, v in node.items() if k not in ("description", "title")}
    if out.get("type") == "object" and "properties" in out:
        out.setdefault("additionalProperties", False)
    return out


def anthropic() -> dict[str, Any]:
    import pydantic
    from anthropic.types import message_create_params

    params = message_create_params.MessageCreateParamsNonStreaming
    schema = pydantic.TypeAdapter(params).json_schema()
    for header in ("user_profile_id", "workspace_id"):
        schema["properties"].pop(header, None)
    schema = _closed(schema)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    return schema


if __name__ == "__main__":
    which = sys.argv[1]
    result = openai(sys.argv[2]) if which == "openai" else anthropic()
    json.dump(result, sys.stdout, indent=1, sort_keys=True)
    sys.stdout.write("\n")
