"""``analytic``: the exact irradiance of each polygon light (Lambert 1760; Arvo 1994) with horizon clipping,
times the material's Lambertian albedo / π.

Exact (to float32) for Lambertian surfaces, the reference every diffuse method is measured against; for
other materials it returns only their Lambertian term (ρ_d/π of Phong, Blinn-Phong, Ward, Lafortune,
microfacet ``diffuse``) — use ``ltc`` or a sampling method for specular lobes.
"""

from __future__ import annotations

from typing import ClassVar

from ..techniques.base import register_technique
from .base import SHADERS, AreaLightTechnique


@register_technique
class Analytic(AreaLightTechnique):
    """Exact diffuse polygon irradiance with horizon clipping (specular lobes not included)."""

    name: ClassVar[str] = "analytic"
    summary: ClassVar[str] = "area lights: exact Lambert polygon irradiance (diffuse terms only)"
    area_glsl: ClassVar[str] = SHADERS + "analytic.glsl"
