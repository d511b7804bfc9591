"""``scratches``: the layered scratched SV-BRDF of chapter 3 rendered progressively on the forward pass.

Meshes of other materials are shaded by the forward pass; a ``scratched`` mesh gets ``shaders/scratches.frag``
(NumPy twin: :mod:`reflets.scratches.shading`, the formulas are there):

- α of every layer from a mip-mapped texture array (4 layers per RGBA texel), sampled with the pixel footprint
  (trilinear, anisotropic where the driver offers it) — or a constant with the material's ``coverage``;
- the base BRDF weighted by max(0, 1 − ᾱ), lit as by the forward pass (its environment grid included);
- the environment: ``samples`` importance samples per pixel and frame on the reflection half-cones, layers
  chosen ∝ α_k (stratified), φ_in drawn by exact inversion of the table's per-row CDF (a binary search of
  log₂ M texel fetches: the GPU draws exactly the twin's density, not an interpolated inverse CDF);
- point and directional lights "thickened" to f_H(h) = (1 − (h/H)²)² of angular radius H = ``thickness``
  degrees, normalised by 3 / (π H² cos θ_ℓ) so the result converges to the δ-light answer as H → 0, with the
  document's culling (|θ_ℓ + θ_o| ≥ H) and ``light_samples`` stratified samples per live layer.

Frames: ``render(spp=…)`` accumulates spp / samples frames, frame k seeded by (pixel, k, seed); an spp that is
not a multiple of ``samples`` is rounded up to the next one, with a one-line note (a frame is drawn whole).
Compile-time flags keep what a scene lacks out of the program (llvmpipe runs both sides of uniform branches): the
layer count, table size, sample counts, light counts, the environment and constant α.
"""

from __future__ import annotations

import warnings
from typing import ClassVar, Literal

from pydantic import Field

from ..errors import ArgumentError, RefletsWarning
from ..techniques.base import register_technique
from ..techniques.forward import Forward, ForwardParams
from .lobes import LobeSettings, ScratchLobes


class ScratchesParams(ForwardParams):
    """Parameters of ``scratches``."""

    samples: int = Field(
        LobeSettings.samples, ge=0, le=256, description="environment samples per pixel and frame (split ∝ α_k)"
    )
    light_samples: int = Field(
        LobeSettings.light_samples, ge=1, le=64, description="samples per thickened light and live layer per frame"
    )
    thickness: float = Field(
        LobeSettings.thickness, gt=0, le=10, description="H: angular radius of thickened lights, degrees"
    )
    table_backend: Literal["auto", "numpy", "gpu"] = Field(
        LobeSettings.table_backend, description="scratch-table tracer (auto: the GPU compute shader, faster here)"
    )


@register_technique
class Scratches(Forward):
    """Scratched materials: the layered SV-BRDF, environment IS + thickened lights, progressive (docstring)."""

    name: ClassVar[str] = "scratches"
    progressive: ClassVar[bool] = True
    summary: ClassVar[str] = "scratched / brushed materials: layered SV-BRDF, cone importance sampling, progressive"
    Params: ClassVar = ScratchesParams
    auto_order: ClassVar[int] = 1

    def material_shadings(self, scene) -> list:
        p = self.params
        settings = LobeSettings(p.samples, p.light_samples, p.thickness, p.table_backend)
        return [ScratchLobes(self.prepared, scene, settings)]

    @property
    def default_spp(self) -> int:
        return max(self.params.samples, 1)  # one frame

    def frames(self, spp: int) -> tuple[int, int]:
        """(spp / samples frames, no supersampling); spp rounded up to a multiple of ``samples`` with a note."""
        n = max(self.params.samples, 1)
        if spp < 1:
            raise ArgumentError(f"{spp} is out of range; samples per pixel must be at least 1", field="spp")
        frames = -(-spp // n)
        if frames * n != spp:
            warnings.warn(f"spp {spp} rounded up to {frames * n}: the scratched material draws its samples in frames "
                          f"of {n} (samples = {n}); give spp a multiple of {n}, or set samples", RefletsWarning,
                          stacklevel=2)  # fmt: skip
        return frames, 1
