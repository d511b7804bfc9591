"""The material interface and registry shared by scene files, the GPU renderer and the references.

A material is data (a pydantic model with keyword parameters and documented defaults) plus two
evaluations of the same BRDF: NumPy float64 (``eval``, the reference) and a GLSL file defining
``vec3 brdf_eval(vec3 wo, vec3 wi)``. Both work in the local shading frame (normal = +z, tangent = +x)
with pbrt's argument order ``(wo, wi)``; they return f_r without the cosine, and 0 below the horizon.
"""

from __future__ import annotations

from typing import Annotated, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

MATERIALS: dict[str, type[Material]] = {}


class Material(BaseModel):
    """Base of every material model; subclasses set ``type`` (a Literal) and ``glsl``."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    #: package path of the GLSL twin, e.g. "reflets/brdf/glsl/lambert.glsl"
    glsl: ClassVar[str]

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        """BRDF value f_r(wo, wi), shape (..., 3), float64; zero when wo or wi is below the surface."""
        raise NotImplementedError

    def uniforms(self) -> dict[str, object]:
        """Values of the GLSL uniforms declared in ``glsl`` (names as in the shader)."""
        raise NotImplementedError

    def flags(self) -> dict[str, object]:
        """Compile-time shader flags (``#define``s) this material needs; none by default."""
        return {}


def register_material(cls: type[Material]) -> type[Material]:
    """Class decorator: make a material selectable by its ``type`` name. Duplicate names are errors."""
    name = cls.model_fields["type"].default
    if not isinstance(name, str):
        raise TypeError(f"{cls.__name__}.type needs a default equal to its name")
    if name in MATERIALS:
        raise ValueError(f"material type '{name}' is registered twice ({MATERIALS[name].__name__}, {cls.__name__})")
    MATERIALS[name] = cls
    return cls


def cos_theta(w: np.ndarray) -> np.ndarray:
    return w[..., 2]


def upper(wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """Mask of direction pairs both strictly above the surface, shape (..., 1) for broadcasting."""
    return ((wo[..., 2] > 0) & (wi[..., 2] > 0))[..., None]


Unit = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
NonNeg = Annotated[float, Field(ge=0, allow_inf_nan=False)]
#: an RGB reflectance in [0, 1] per channel
Reflectance = tuple[Unit, Unit, Unit]
#: an RGB scale factor ≥ 0 per channel
RGB = tuple[NonNeg, NonNeg, NonNeg]
