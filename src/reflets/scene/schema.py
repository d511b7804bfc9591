"""JSON schema of scene files (printed by `reflets schema`; editors can validate TOML against it)."""

from __future__ import annotations

from .model import Scene


def scene_json_schema() -> dict:
    schema = Scene.model_json_schema(mode="validation")
    schema["properties"].pop("base_dir", None)
    schema["title"] = "reflets scene file"
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    return schema
