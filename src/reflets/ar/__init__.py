"""Augmented reality (004): marker boards, camera intrinsics, tracking by ArUco markers and PnP, synthetic views
with known poses (the test data: real photographs are not available offline)."""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, ConfigDict, model_validator

from .. import jsonio

#: JSON's names of the values json.loads gives
_JSON_KINDS = {list: "an array", str: "a string", int: "a number", float: "a number", bool: "true / false"}


class InputFile(BaseModel):
    """The model of an ar input file (camera.json, board.json): a JSON object, no key it does not know."""

    model_config = ConfigDict(extra="forbid")

    @model_validator(mode="before")
    @classmethod
    def _an_object(cls, data):
        if not isinstance(data, dict):
            raise ValueError(f"the file holds {_JSON_KINDS.get(type(data), 'null')}; expected an object {{...}}")
        return data


def write_json(path: str | Path, data: dict) -> Path:
    return jsonio.write(path, data, indent=1)
