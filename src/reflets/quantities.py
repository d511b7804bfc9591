"""The number types of scene fields: finite, and no larger in magnitude than MAX_MAGNITUDE, so that no later
stage (a product of radiance and area, a float32 buffer, a squared distance) overflows to inf and blames the
wrong thing — a field out of range is refused where it enters, by name."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, Strict

#: the largest magnitude a scene number may have: 10¹² (a million kilometres in metres, a radiance far above
#: the sun's disc in W m⁻² sr⁻¹); its square and products with a few others stay far from float32's 3.4 × 10³⁸
MAX_MAGNITUDE = 1e12

Finite = Annotated[float, Field(allow_inf_nan=False, ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
NonNeg = Annotated[float, Field(ge=0, le=MAX_MAGNITUDE, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, le=MAX_MAGNITUDE, allow_inf_nan=False)]
#: a number of a JSON input file (a board, camera intrinsics, strokes, an event): JSON's own — not a string nor
#: true / false, which pydantic's lax mode would read as numbers —, finite and bounded
JsonNumber = Annotated[Finite, Strict()]
