"""``translucent``: subsurface scattering of translucent materials on the GPU (document 003, errata fixed).

Passes per frame:

1. **light view** — every mesh seen from the scene's one point or directional light, into two float32 maps:
   the world position of the first surface along each light ray and its normal (the document's distance and
   normal maps). Directional light: orthographic over the translucent meshes' bounding sphere; point light:
   perspective. Drawn on the first frame after ``prepare`` only: it depends on the light and the meshes, not on
   the camera, so a persistent renderer's camera moves re-use it.
2. **camera view** — meshes of other materials are shaded by the forward pass; a ``translucent`` mesh gets:
   - the interface's glossy reflection (Beckmann Cook–Torrance, exact dielectric Fresnel), shadowed by
     comparing the shaded point with the surface the light map holds there;
   - **single scattering**: a march along the refracted view ray at k_max + 1 truncated-exponential depths per
     colour channel (c_l mean free paths deep), the light's path to each depth read from the light view and
     Snell-corrected, integrated by the trapezoid rule (``ss_rule = "step"``: the document's biased sum);
   - **multiple scattering**: R_d (``multiple_fit`` by default — multiple scattering only, fitted to volumetric
     Monte Carlo, the light entering each node weighted by its incidence factor — or the document's dipole,
     better dipole or normalised diffusion, which stand for all orders) integrated over ``rings`` ×
     ``angles`` nodes in the plane through the point orthogonal to the light, radii r_max f_β(j/K) (β fitted
     per material; ``ring_sets = "per_channel"``: β and r_max per channel, as the document, three times the
     light-map reads), each node's value R_d(true distance to the surface point the light sees) × transmitted
     flux density, summed with the exact weights of the document's bilinear cell integral (``ms_quadrature =
     "bilinear"``) or, by default, of product integration (R_d integrated exactly per ring, the first ring's
     disc in closed form per direction; rings.py, translucent.frag), then × F_T(ω_o)/(πc).
     On a plane orthogonal to the light, cell area × irradiance normal to the beam is the incident flux (no
     extra n·ω_l, as the note corrects).

   - optionally (``view_blend = λ``) the document's light-/camera-view blend: the same integral over the
     camera's own position/normal maps, weighted by s = 1/(1 + e^{−λ((n·ω_l) − (n·ω_o))}) against the light
     view's.

   - optionally (``curvature_rejection = κ_max``, 1/mm) the document's curvature rejection: along each spoke of
     ring nodes, the first pair of consecutive surface points whose normals turn faster than κ_max per mm ends
     the spoke. Off by default: measured on the bunny it changes the error by less than the reference's noise,
     and on a small sphere it either does nothing or cuts the integral to its first ring
     (docs/techniques/translucency.md).
   - optionally (``refraction = "on"``) image-space two-surface refraction (Wyman 2005): a back-face pass holds
     the nearest back face of the translucent meshes per pixel; the refracted view ray's exit is found there,
     the single-scattering march ends at it, and the background seen through the object along the twice
     refracted ray is added with its unscattered transmittance (term ``transmission``).

Not done here: more than one light for the subsurface terms. Distances: coefficients are per mm, scene
positions × ``mm_per_unit``.
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field, field_validator

from ..errors import ArgumentError
from ..scene.model import DirectionalLight, PointLight, Scene
from ..techniques.base import register_technique
from ..techniques.forward import Forward, ForwardParams
from . import rings as rings_module
from .shading import TranslucentShading


class TranslucencyParams(ForwardParams):
    """Parameters of ``translucent``."""

    light_map: int = Field(1024, ge=64, le=8192, description="light-view map resolution (pixels per side)")
    k_max: int = Field(30, ge=1, le=128, description="single scattering: march intervals (k_max + 1 depths)")
    c_l: float = Field(7.0, gt=0, le=30, description="single scattering: march depth in mean free paths 1/σ_t")
    ss_rule: Literal["trapezoid", "step"] = Field("trapezoid", description="single-scattering quadrature")
    rings: int = Field(12, ge=1, le=64, description="multiple scattering: number of rings")
    angles: int = Field(14, ge=3, le=64, description="multiple scattering: nodes per ring")
    radius_mfp: float | None = Field(
        None,
        gt=0,
        le=1000,
        description="sampling radius in mean free paths 1/σ'_t of the widest channel (the document: 10, 15, 30); "
        "None: the radius holding 99 % of the profile's total reflectance",
    )
    beta: float | None = Field(None, ge=0, le=rings_module.BETA_MAX, description="ring spacing β (None: fitted)")
    ring_sets: Literal["shared", "per_channel"] = Field(
        "shared",
        description="one ring layout for the three channels (β fitted on the luminance-weighted profile, the "
        "widest channel's radius) or one per channel (β and radius fitted to each channel's profile, as the "
        "document; three times the light-map reads)",
    )
    ms_quadrature: Literal["product", "bilinear"] = Field(
        "product",
        description="multiple scattering: bilinear cells (the document) or product integration (R_d integrated "
        "exactly per ring, the light interpolated)",
    )
    view_blend: float | None = Field(
        None,
        gt=0,
        le=100,
        description="λ of the document's light-/camera-view blend of the multiple scattering (None: light view "
        "only); the camera view's own position/normal maps serve where the light grazes the surface",
    )
    curvature_rejection: float | None = Field(
        None,
        gt=0,
        le=1000,
        description="κ_max in 1/mm of the document's curvature rejection: a spoke of ring nodes stops where the "
        "surface turns faster than κ_max per mm between consecutive nodes (None: off, the measured default)",
    )
    refraction: Literal["off", "on", "exit"] = Field(
        "off",
        description="image-space two-surface refraction (Wyman 2005): a back-face pass finds where the refracted "
        "view ray leaves the object; the single-scattering march stops there and the background seen through "
        "the object is added (term 'transmission'); 'exit' writes that exit point instead of radiance (tests)",
    )
    terms: tuple[Literal["specular", "single", "multiple", "transmission"], ...] = Field(
        ("specular", "single", "multiple", "transmission"),
        description="which terms to render (breakdowns, tests); transmission needs refraction",
    )

    @field_validator("terms", mode="before")
    @classmethod
    def _split_terms(cls, value):
        """``--param terms=single,multiple`` from the command line: a comma-separated string."""
        return tuple(t.strip() for t in value.split(",")) if isinstance(value, str) else value


@register_technique
class Translucency(Forward):
    """Translucent materials: single scattering + diffusion profiles through a light view (module docstring)."""

    name: ClassVar[str] = "translucent"
    summary: ClassVar[str] = "translucent materials: single scattering + a diffusion profile (multiple_fit, dipoles…)"
    Params: ClassVar = TranslucencyParams
    auto_order: ClassVar[int] = 0
    one_light_per_pass: ClassVar[bool] = True

    def prepare(self, scene: Scene) -> None:
        if len(scene.light) != 1 or not isinstance(scene.light[0], PointLight | DirectionalLight):
            kinds = ", ".join(light.type for light in scene.light) or "none"
            raise ArgumentError(
                f"the translucent technique needs exactly one point or directional light (got: {kinds})",
                field="light",
            )
        if getattr(scene.light[0], "spot", None) is not None:
            raise ArgumentError("the translucent technique lights by an isotropic point light: drop its spot cone",
                                field="light[0].spot")  # fmt: skip
        super().prepare(scene)

    def material_shadings(self, scene: Scene) -> list:
        return [TranslucentShading(self.prepared, scene, self.params)]
