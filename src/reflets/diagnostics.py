"""Warnings about scenes that render without error but not as the user meant: no silent black.

A light facing away from every mesh, a whole-frame method that ignores part of the scene (``analytic`` on a
glossy material, ``ltc`` on a mirror reflector…), or a material its lights cannot show
(``Material.lighting_warnings``: a scratch profile without a mirror peak under point lights) renders an image
that is darker than the scene says and exits 0. Each such case is one line on stderr (``RefletsWarning``; the
CLI prints it as ``reflets: warning: …``).
"""

from __future__ import annotations

import warnings

import numpy as np

from .errors import RefletsWarning
from .scene.model import PolygonLight, QuadLight, Scene

__all__ = ["RefletsWarning", "scene_warnings", "warn_scene"]


#: what a whole-frame method other than a material's own technique draws of it (``Material.techniques``)
WITHOUT = {
    "translucent": "by its far-field BRDF only (no subsurface transport)",
    "scratches": "by its base BRDF only (no scratch lobes)",
    "fermat": "without its mirror reflections (only the non-specular part)",
}
#: methods whose output is not radiance: nothing to warn about
AOV_METHODS = ("position", "normal", "uv")


#: area-light methods whose integrals read a material's constant parameters (tables, lobe summaries), not the
#: per-fragment ones its textures give — ``ltc`` save for materials it reads per fragment (``fragment_ltc``):
#: ``auto`` takes ``forward``'s midpoint rule for the others
CONSTANT_MATERIAL_METHODS = ("ltc", "analytic", "biased")


def lit_by_constants(method: str, material) -> bool:
    """Whether ``method`` lights ``material`` under quad / polygon lights by its constant factors and an isotropic
    lobe, its textures or anisotropy ignored there."""
    if method not in CONSTANT_MATERIAL_METHODS or material.tabulated:
        return False
    if method == "ltc" and material.fragment_ltc:  # textures read per fragment; the lobe isotropic
        return getattr(material, "anisotropic", False)
    return True


def scene_warnings(scene: Scene, method: str) -> list[str]:
    """One line per part of ``scene`` that ``method`` leaves unlit or ignores."""
    from .scene.geometry import mesh_data

    if method in AOV_METHODS:
        return []
    messages = []
    points = [mesh_data(scene, i).positions for i in range(len(scene.mesh))]
    allpoints = np.concatenate(points) if points else np.zeros((0, 3))
    for i, light in enumerate(scene.light):
        if isinstance(light, QuadLight | PolygonLight) and not light.two_sided and len(allpoints):
            poly = light.polygon()
            normal = np.sum(np.cross(poly, np.roll(poly, -1, axis=0)), axis=0)
            if np.all((allpoints - poly[0]) @ normal <= 0.0):
                messages.append(
                    f"light[{i}] ({light.type}) faces away from every mesh and lights nothing "
                    "(reverse its corner order or set two_sided = true)"
                )
    for name, material in scene.materials.items():
        used = [i for i, mesh in enumerate(scene.mesh) if mesh.material == name]
        if not used:
            continue
        own = sorted({m for i in used for m in material.techniques(scene.mesh[i]).values()})
        if own and method not in ("auto", *own):
            kind = "reflector" if "fermat" in own else material.type
            what = "; ".join(WITHOUT.get(m, f"without its {m} pass") for m in own)
            alternatives = " or ".join(("auto", *own))
            messages.append(
                f"materials.{name}: method '{method}' renders this {kind} material {what}; use {alternatives}"
            )
        else:  # drawn by its own technique: what that cannot light
            lights = {light.type for light in scene.light}
            messages += [f"materials.{name}: {text}" for text in material.lighting_warnings(lights)]
        if lit_by_constants(method, material) and _has_area_light(scene):
            if method == "ltc" and material.fragment_ltc:  # it reads textures per fragment, not an anisotropic lobe
                messages.append(
                    f"materials.{name}: method 'ltc' lights this anisotropic material by an isotropic lobe of the same "
                    f"area under quad / polygon lights (its anisotropy is ignored there; auto or forward use it)"
                )
            else:
                kind, what = ("textured", "textures are") if material.textured else ("anisotropic", "anisotropy is")
                messages.append(
                    f"materials.{name}: method '{method}' lights this {kind} material by its constant factors and an "
                    f"isotropic lobe under quad / polygon lights (its {what} ignored there; auto or forward use "
                    f"{'them' if material.textured else 'it'})"
                )
        if method == "analytic" and _has_glossy_part(material) and _has_area_light(scene):
            messages.append(
                f"materials.{name}: method 'analytic' integrates only Lambertian parts under quad / polygon lights; "
                f"this {material.type} material's glossy part gets no area light (use ltc or auto)"
            )
    return messages


def warn_scene(scene: Scene, method: str) -> None:
    for message in scene_warnings(scene, method):
        warnings.warn(message, RefletsWarning, stacklevel=3)


def _has_area_light(scene: Scene) -> bool:
    return any(isinstance(light, QuadLight | PolygonLight) for light in scene.light)


def _has_glossy_part(material) -> bool:
    return material.type != "lambert"
