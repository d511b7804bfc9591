"""Homogeneous scattering media: coefficients per millimetre, the twelve measured materials of Jensen et al. 2001.

A medium is given by σ_a and σ'_s (reduced scattering, what Jensen et al. measured) or by σ_s and the
Henyey–Greenstein mean cosine g (σ'_s = σ_s (1 − g)); η = n_inside / n_outside. Every derived quantity the
profiles need lives here, per RGB channel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Jensen, Marschner, Levoy & Hanrahan 2001, Fig 5: σ'_s and σ_a in mm⁻¹ (R, G, B) and η
PRESETS: dict[str, dict[str, tuple]] = {
    "apple": {"sigma_s_prime": (2.29, 2.39, 1.97), "sigma_a": (0.0030, 0.0034, 0.046), "eta": 1.3},
    "chicken1": {"sigma_s_prime": (0.15, 0.21, 0.38), "sigma_a": (0.015, 0.077, 0.19), "eta": 1.3},
    "chicken2": {"sigma_s_prime": (0.19, 0.25, 0.32), "sigma_a": (0.018, 0.088, 0.20), "eta": 1.3},
    "cream": {"sigma_s_prime": (7.38, 5.47, 3.15), "sigma_a": (0.0002, 0.0028, 0.0163), "eta": 1.3},
    "ketchup": {"sigma_s_prime": (0.18, 0.07, 0.03), "sigma_a": (0.061, 0.97, 1.45), "eta": 1.3},
    "marble": {"sigma_s_prime": (2.19, 2.62, 3.00), "sigma_a": (0.0021, 0.0041, 0.0071), "eta": 1.5},
    "potato": {"sigma_s_prime": (0.68, 0.70, 0.55), "sigma_a": (0.0024, 0.0090, 0.12), "eta": 1.3},
    "skimmilk": {"sigma_s_prime": (0.70, 1.22, 1.90), "sigma_a": (0.0014, 0.0025, 0.0142), "eta": 1.3},
    "skin1": {"sigma_s_prime": (0.74, 0.88, 1.01), "sigma_a": (0.032, 0.17, 0.48), "eta": 1.3},
    "skin2": {"sigma_s_prime": (1.09, 1.59, 1.79), "sigma_a": (0.013, 0.070, 0.145), "eta": 1.3},
    "spectralon": {"sigma_s_prime": (11.6, 20.4, 14.9), "sigma_a": (0.0, 0.0, 0.0), "eta": 1.3},
    "wholemilk": {"sigma_s_prime": (2.55, 3.21, 3.77), "sigma_a": (0.0011, 0.0024, 0.014), "eta": 1.3},
}


@dataclass(frozen=True)
class Medium:
    """σ_a, σ_s (mm⁻¹, per channel), HG g and relative index η; derived quantities as properties."""

    sigma_a: np.ndarray
    sigma_s: np.ndarray
    g: float = 0.0
    eta: float = 1.3

    def __post_init__(self):
        object.__setattr__(self, "sigma_a", np.asarray(self.sigma_a, dtype=np.float64))
        object.__setattr__(self, "sigma_s", np.asarray(self.sigma_s, dtype=np.float64))

    @classmethod
    def preset(cls, name: str, g: float = 0.0) -> Medium:
        """A measured material; with g ≠ 0, σ_s = σ'_s / (1 − g) keeps the measured reduced coefficient."""
        p = PRESETS[name]
        return cls(np.array(p["sigma_a"]), np.array(p["sigma_s_prime"]) / (1.0 - g), g, p["eta"])

    @classmethod
    def from_reduced(cls, sigma_a, sigma_s_prime, eta: float = 1.3, g: float = 0.0) -> Medium:
        return cls(np.asarray(sigma_a, np.float64), np.asarray(sigma_s_prime, np.float64) / (1.0 - g), g, eta)

    def channel(self, c: int) -> Medium:
        """The medium of one colour channel (scalar coefficients)."""
        return Medium(self.sigma_a[..., c], self.sigma_s[..., c], self.g, self.eta)

    @property
    def sigma_t(self) -> np.ndarray:
        return self.sigma_a + self.sigma_s

    @property
    def albedo(self) -> np.ndarray:
        return np.divide(self.sigma_s, self.sigma_t, out=np.zeros_like(self.sigma_t), where=self.sigma_t > 0)

    @property
    def sigma_s_prime(self) -> np.ndarray:
        return self.sigma_s * (1.0 - self.g)

    @property
    def sigma_t_prime(self) -> np.ndarray:
        return self.sigma_a + self.sigma_s_prime

    @property
    def albedo_prime(self) -> np.ndarray:
        return self.sigma_s_prime / self.sigma_t_prime

    @property
    def mean_free_path(self) -> np.ndarray:
        """1/σ'_t in mm: the length unit of the profiles (sampling radii are given in these)."""
        return 1.0 / self.sigma_t_prime
