"""Translucent materials: media and presets, boundary optics, diffusion profiles and single scattering (NumPy,
float64 — the models the GPU technique implements and the tests check), see docs/techniques/translucency.md."""

from .medium import PRESETS, Medium
from .profiles import PROFILES, dipole_rd, dipole_total_reflectance, profile_rd, total_reflectance
from .single import half_space_single_scattering, march_single_scattering

__all__ = [
    "PRESETS",
    "PROFILES",
    "Medium",
    "dipole_rd",
    "dipole_total_reflectance",
    "half_space_single_scattering",
    "march_single_scattering",
    "profile_rd",
    "total_reflectance",
]
