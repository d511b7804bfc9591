"""Scratched and brushed materials (chapter 3): profiles and the scratch BRDF precomputation.

- :mod:`.profiles` — V-groove, symmetric quartic, tabulated height fields (periodic, lid = highest point);
- :mod:`.tracer2d` — the 2D profile ray tracer with Fresnel at every bounce (NumPy reference);
- :mod:`.tracer3d` — brute-force 3D tracing of the extruded profile (ground truth of the BRDF);
- :mod:`.table` — ρ_m, ρ_s(0), ρ_s(π/3), γ, pdf / CDF / inverse CDF, symmetrisation, .npz, plots;
- :mod:`.gpu` — the same tracer as a compute shader.
"""

from .profiles import Profile, flat, from_samples, parse_profile, quartic, read_profile, vgroove
from .table import ScratchTable, build_table, fit_gamma, load_table, plot_table, table_from_tallies
from .tracer2d import FresnelSpec, Tallies, make_fresnel, trace_rays, trace_table

__all__ = [
    "Profile",
    "flat",
    "from_samples",
    "parse_profile",
    "quartic",
    "read_profile",
    "vgroove",
    "ScratchTable",
    "build_table",
    "fit_gamma",
    "load_table",
    "plot_table",
    "table_from_tallies",
    "FresnelSpec",
    "Tallies",
    "make_fresnel",
    "trace_rays",
    "trace_table",
]
