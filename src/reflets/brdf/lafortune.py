"""The generalised cosine-lobe model of Lafortune et al. 1997 (the area-light document's eq 1.8)."""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ..quantities import Finite
from ..textures import TextureRef
from .base import (
    RGB,
    Reflectance,
    finish_sample,
    luminance,
    pdf_cosine,
    register_material,
    sample_cosine,
    sample_power_cosine,
    upper,
)
from .maps import LobeMap, Mapped

#: the most lobes a material may have (the GLSL twin's uniform arrays have this size)
MAX_LOBES = 8

_Z = np.array([0.0, 0.0, 1.0])


def cosine_power(x: np.ndarray, exponent: float) -> np.ndarray:
    """max(0, x)^n, zero where x ≤ 0 for every n (also n = 0)."""
    return np.where(x > 0.0, np.maximum(x, 0.0) ** exponent, 0.0)


class Lobe(BaseModel):
    """One generalised cosine lobe: scale · max(0, c_x wo_x wi_x + c_y wo_y wi_y + c_z wo_z wi_z)^exponent."""

    model_config = ConfigDict(extra="forbid")

    c: tuple[Finite, Finite, Finite] = (-1.0, -1.0, 1.0)
    exponent: float = Field(default=20.0, ge=0, le=1e6, allow_inf_nan=False)
    scale: RGB = (1.0, 1.0, 1.0)


@register_material
class Lafortune(Mapped):
    """Diffuse term plus a sum of generalised cosine lobes in the local frame (Lafortune, Foo, Torrance &
    Greenberg 1997, "Non-linear approximation of reflectance functions").

    f = ρ_d/π + Σ_i scale_i · max(0, C_x,i wo_x wi_x + C_y,i wo_y wi_y + C_z,i wo_z wi_z)^(n_i)

    The lobe is zero where the dot product is ≤ 0, also for n_i = 0. C_x = C_y = −1, C_z = 1 is Phong's lobe
    around the mirror direction (un-normalised: (r·wi)^n); C_x ≠ C_y makes it anisotropic (x = tangent);
    C_x = C_y > 0 reflects back towards the viewer (retro-reflection); |C| ≠ 1 scales the lobe by |C|^n
    and, with C_z ≠ −C_x, moves it towards or away from the normal (off-specular peaks).

    Parameters
    ----------
    kd : [r, g, b] in [0, 1], default [0, 0, 0]
        Diffuse reflectance ρ_d.
    lobes : list of 1 to 8 tables, default one Phong lobe {c = [−1, −1, 1], exponent = 20, scale = [1, 1, 1]}
        c : [C_x, C_y, C_z], finite reals, default [−1, −1, 1];
        exponent : n ≥ 0 (at most 1e6), default 20;
        scale : [r, g, b] ≥ 0, default [1, 1, 1] (the lobe's ρ_s; fitted values are often > 1).

    Maps: ``kd``, and in a lobe its ``scale`` or its ``exponent`` (``scale = { texture = "spec.png", factor = [1, 1, 1]
    }``; kept as ``maps.lobe<i>_scale``): factor × the texel (an exponent: × its R, linear data). Every mapped scale
    reads one texture, and every mapped exponent one texture (the prefiltered environment mixes the curves with the
    mapped scales at 0 and at their factors at the texel, and interpolates curves at texel values of the exponents);
    ``c`` stays constant.

    Always reciprocal (the lobe is symmetric in wo and wi). Energy conservation depends on the fitted
    coefficients (a lobe's albedo grows like scale·|C|^n) and is not checked, so it is never declared.

    Sampling: one-sample mixture of cosine-weighted directions (diffuse) and, per lobe, directions with
    density (n + 1)/(2π) cos^n α around the lobe axis normalize(C_x wo_x, C_y wo_y, C_z wo_z) — exactly the
    lobe's shape; the normal when that vector vanishes. The strategy weights depend on wo: lum(ρ_d) for the
    diffuse term, lum(scale)·|C ⊙ wo|^n·2π/(n + 2)·max(a_z, 0.05) for a lobe with axis a (its albedo
    ignoring the horizon). Lobe directions may fall below the surface (f = 0 there); no sample fails.
    """

    type: Literal["lafortune"] = "lafortune"
    kd: Reflectance = (0.0, 0.0, 0.0)
    lobes: list[Lobe] = Field(default_factory=lambda: [Lobe()], min_length=1, max_length=MAX_LOBES)
    lambertian_field: ClassVar[str] = "kd"
    affine_group: ClassVar[bool] = True  # every mapped lobe scale reads one texture
    lobe_maps: ClassVar[dict[str, LobeMap]] = {f"lobe{i}_exponent": LobeMap(low=0.0, widest="min")
                                                for i in range(MAX_LOBES)}  # fmt: skip

    @classmethod
    def _lift_maps(cls, data: dict, maps: dict) -> tuple[dict, dict]:
        """A lobe's ``scale = { texture = … }`` / ``exponent = …``: its texture to ``maps.lobe<i>_<field>``, its
        factor (default 1) to the lobe."""
        lobes = data.get("lobes")
        if not isinstance(lobes, list):
            return data, maps
        lifted = []
        for i, lobe in enumerate(lobes):
            if isinstance(lobe, dict):
                lobe = dict(lobe)
                if isinstance(lobe.get("c"), dict):
                    raise ValueError(f"lobes[{i}].c cannot be a texture (a lobe's scale or exponent can)")
                for field, default in (("scale", (1.0, 1.0, 1.0)), ("exponent", 1.0)):
                    value = lobe.get(field)
                    if isinstance(value, TextureRef):
                        value = value.model_dump()
                    if isinstance(value, dict) and "texture" in value:
                        value = dict(value)
                        lobe[field] = value.pop("factor", default)
                        maps[f"lobe{i}_{field}"] = value
            lifted.append(lobe)
        return {**data, "lobes": lifted}, maps

    @classmethod
    def mappable(cls, data: dict | None = None) -> tuple[str, ...]:
        return ("kd",)

    @classmethod
    def affine_colours(cls, data: dict | None = None) -> tuple[str, ...]:
        """The lobes' scales: the BRDF is linear in each, so affine in one when the others stay (the split sum
        mixes the curves with every mapped scale at 0 and at its factor)."""
        lobes = (data or {}).get("lobes")
        return tuple(f"lobe{i}_scale" for i in range(len(lobes) if isinstance(lobes, list) else 1))

    @model_validator(mode="after")
    def _check_maps(self) -> Lafortune:
        for key in self.maps or {}:
            at = self._lobe_field(key)
            if at is not None and at[0] >= len(self.lobes):
                raise ValueError(f"maps.{key}: there are {len(self.lobes)} lobes (lobe0 … lobe{len(self.lobes) - 1})")
        scales = [self.maps[key] for key in self.mapped_scales]
        if any(ref != scales[0] for ref in scales):
            raise ValueError("the lobes' mapped scales read different textures: they must read the same one (the "
                             "prefiltered environment mixes its curves at one texel)")
        return self

    @property
    def mapped_scales(self) -> list[str]:
        """The lobes' scales read from maps."""
        return [key for key in self.maps or {} if key.endswith("_scale")]

    @property
    def mapped_affine(self) -> list[str]:
        """One of the mapped scales (they read one texture): what the split sum mixes by."""
        return self.mapped_scales[:1]

    def affine_zeros(self) -> list[Lafortune] | None:
        """The material with every mapped lobe scale at 0 (``Mapped.affine_zeros``: one texture, one mix)."""
        fields = self.mapped_scales
        return [self.with_values(dict.fromkeys(fields, (0.0, 0.0, 0.0)))] if fields else None

    @staticmethod
    def _lobe_field(key: str) -> tuple[int, str] | None:
        if not key.startswith("lobe"):
            return None
        index, _, field = key[4:].partition("_")
        return int(index), field

    def factor(self, field: str):
        at = self._lobe_field(field)
        return getattr(self.lobes[at[0]], at[1]) if at else getattr(self, field)

    def with_values(self, values: dict, points: bool = False) -> Lafortune:
        own = {key: value for key, value in values.items() if self._lobe_field(key) is None}
        lobes = [dict(lobe) for lobe in self.lobes]
        for key, value in values.items():
            at = self._lobe_field(key)
            if at is not None:
                lobes[at[0]][at[1]] = value
        made = [Lobe.model_construct(**lobe) if points else Lobe(**lobe) for lobe in lobes]
        return super().with_values({**own, "lobes": made}, points)

    @classmethod
    def uniform_of(cls, field: str) -> str:
        at = cls._lobe_field(field)
        return f"m_lobe_{at[1]}[{at[0]}]" if at else f"m_{field}"

    def lobe_summary(self):
        return tuple(float(c) for c in self.kd), 1, float(max(lobe.exponent for lobe in self.lobes))

    glsl = "reflets/brdf/glsl/lafortune.glsl"

    def eval(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo = np.asarray(wo, dtype=np.float64)
        wi = np.asarray(wi, dtype=np.float64)
        prod = wo * wi
        f = np.broadcast_to(np.asarray(self.kd) / np.pi, prod.shape).copy()
        for lobe in self.lobes:
            value = cosine_power(prod @ np.asarray(lobe.c, dtype=np.float64), lobe.exponent)
            f += value[..., None] * np.asarray(lobe.scale)
        return np.where(upper(wo, wi), f, 0.0)

    @property
    def energy_conserving(self) -> bool:
        return False  # depends on the fit: scale·|C|^n can make a lobe reflect more than it receives

    def _strategies(self, wo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lobe axes (..., K, 3) and normalised strategy probabilities (..., K + 1), diffuse first."""
        c = np.array([lobe.c for lobe in self.lobes], dtype=np.float64)  # (K, 3)
        n = np.array([lobe.exponent for lobe in self.lobes], dtype=np.float64)
        lum = np.array([luminance(lobe.scale) for lobe in self.lobes])
        v = wo[..., None, :] * c
        length = np.linalg.norm(v, axis=-1)
        ok = length > 1e-12
        axes = np.where(ok[..., None], v / np.where(ok, length, 1.0)[..., None], _Z)
        with np.errstate(divide="ignore"):
            log_w = (
                np.log(lum)
                + n * np.log(np.where(ok, length, 1.0))
                + np.log(2.0 * np.pi / (n + 2.0))
                + np.log(np.maximum(axes[..., 2], 0.05))
            )
            log_w = np.where(ok, log_w, -np.inf)  # an empty lobe (C ⊙ wo = 0) is zero everywhere
            log_w = np.concatenate(
                [np.broadcast_to(np.log(luminance(self.kd)), log_w.shape[:-1])[..., None], log_w], -1
            )
        top = np.max(log_w, axis=-1, keepdims=True)
        w = np.exp(log_w - np.where(np.isfinite(top), top, 0.0))  # ratios only: no overflow of |C|^n
        total = np.sum(w, axis=-1, keepdims=True)
        w[..., 0] = np.where(total[..., 0] > 0, w[..., 0], 1.0)  # nothing to sample: fall back to diffuse
        return axes, w / np.maximum(np.sum(w, axis=-1, keepdims=True), 1e-300)

    def sample(self, wo: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pick diffuse or a lobe with the wo-dependent probabilities (u1, re-stretched), then draw wi."""
        u1 = np.asarray(u1, dtype=np.float64)
        u2 = np.broadcast_to(np.asarray(u2, dtype=np.float64), u1.shape)
        wo = np.broadcast_to(np.asarray(wo, dtype=np.float64), u1.shape + (3,))
        axes, prob = self._strategies(wo)
        cdf = np.cumsum(prob, axis=-1)
        k = np.minimum(np.sum(cdf <= u1[..., None], axis=-1), prob.shape[-1] - 1)
        lo = np.where(k > 0, np.take_along_axis(cdf, np.maximum(k - 1, 0)[..., None], -1)[..., 0], 0.0)
        width = np.take_along_axis(prob, k[..., None], -1)[..., 0]
        u1s = np.clip((u1 - lo) / np.maximum(width, 1e-300), 0.0, np.nextafter(1.0, 0.0))
        wi = np.zeros(u1.shape + (3,))
        chosen = k == 0
        wi[chosen] = sample_cosine(u1s[chosen], u2[chosen])
        for index, lobe in enumerate(self.lobes):
            chosen = k == index + 1
            if np.any(chosen):
                wi[chosen] = sample_power_cosine(axes[chosen][:, index], lobe.exponent, u1s[chosen], u2[chosen])
        return finish_sample(self, wo, wi)

    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray:
        wo, wi = np.broadcast_arrays(np.asarray(wo, dtype=np.float64), np.asarray(wi, dtype=np.float64))
        axes, prob = self._strategies(wo)
        p = prob[..., 0] * pdf_cosine(wi)
        for index, lobe in enumerate(self.lobes):
            cos_a = np.sum(axes[..., index, :] * wi, axis=-1)
            p = p + prob[..., index + 1] * (lobe.exponent + 1.0) / (2.0 * np.pi) * cosine_power(cos_a, lobe.exponent)
        return p

    def brdf_uniforms(self) -> dict[str, object]:
        pad = MAX_LOBES - len(self.lobes)
        return {
            "m_kd": tuple(self.kd),
            "m_lobe_count": len(self.lobes),
            "m_lobe_c": [tuple(lobe.c) for lobe in self.lobes] + [(0.0, 0.0, 0.0)] * pad,
            "m_lobe_exponent": [float(lobe.exponent) for lobe in self.lobes] + [0.0] * pad,
            "m_lobe_scale": [tuple(lobe.scale) for lobe in self.lobes] + [(0.0, 0.0, 0.0)] * pad,
        }
