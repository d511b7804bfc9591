"""Per-vertex reflections on curved smooth reflectors by Fermat's principle (NumPy core, issue 6).

``surfaces`` holds the parametric reflectors (analytic or sampled like GPU textures) with first and second
derivatives; ``solver`` the document's triangle-secant search, a robust Newton search in local charts, the
planar closed form and the statistics behind the benchmark.
"""

from reflets.reflections.solver import (
    ReflectionResult,
    convergence_statistics,
    gradient,
    hessian,
    initial_guess,
    path_length,
    planar_reflection,
    random_valid_pairs,
    reflection_residual,
    solve_document,
    solve_robust,
    sphere_reflection,
    third_point,
)
from reflets.scene.surfaces import (
    BezierPatch,
    Chart,
    Cylinder,
    Ellipsoid,
    GridInterpolator,
    HeightField,
    IdentityChart,
    ImplicitSurface,
    Plane,
    SampledSurface,
    Sphere,
    SphereChart,
    Surface,
    Torus,
)

__all__ = [
    "BezierPatch",
    "Chart",
    "Cylinder",
    "Ellipsoid",
    "GridInterpolator",
    "HeightField",
    "IdentityChart",
    "ImplicitSurface",
    "Plane",
    "ReflectionResult",
    "SampledSurface",
    "Sphere",
    "SphereChart",
    "Surface",
    "Torus",
    "convergence_statistics",
    "gradient",
    "hessian",
    "initial_guess",
    "path_length",
    "planar_reflection",
    "random_valid_pairs",
    "reflection_residual",
    "solve_document",
    "solve_robust",
    "sphere_reflection",
    "third_point",
]
