"""The shading of translucent materials in a forward pass (``shaders/translucent.frag``): the light view the
subsurface terms read, the screen-space maps of the view blend and of refraction, and the program's flags,
uniforms and textures — for one point or directional light (the ``translucent`` pass's; ``auto`` runs one pass
per light). The formulas and the passes are described in ``technique.py``'s docstring."""

from __future__ import annotations

from typing import ClassVar

import moderngl
import numpy as np

from ..errors import ArgumentError
from ..gpu import GLObjects, ProgramSpec, depth, get_program, set_uniforms
from ..gpu.programs import shared_constants
from ..resources import check, largest_fitting
from ..scene.camera import view_eye
from ..scene.geometry import bounding_sphere
from ..scene.model import DirectionalLight, Scene
from ..scene.transform import look_at, perspective
from ..techniques.forward import LIGHT_FLAGS
from ..techniques.prepared import PreparedScene
from ..techniques.shading import MaterialShading
from ..techniques.shadows import directional_view
from . import multiple_fit
from . import rings as rings_module
from .material import Translucent
from .optics import diffuse_normalisation
from .profiles import PROFILES, capture_radii, glsl_uniforms, profile_rd
from .single import march_depths, quadrature_weights

_SHADERS = "reflets/translucency/shaders/"
LIGHT_VIEW_PROGRAM = ProgramSpec(
    "translucency_light_view", vertex="reflets/techniques/shaders/mesh.vert", fragment=_SHADERS + "lightview.frag"
)
BACK_FACE_PROGRAM = ProgramSpec(
    "translucency_back_faces", vertex="reflets/techniques/shaders/mesh.vert", fragment=_SHADERS + "backface.frag"
)
TRANSLUCENT_PROGRAM = ProgramSpec(
    "translucent",
    vertex="reflets/techniques/shaders/mesh.vert",
    fragment=_SHADERS + "translucent.frag",
    flags=frozenset(
        {
            "LIGHT_DIRECTIONAL",
            "PROFILE",
            "SS_NODES",
            "RINGS",
            "ANGLES",
            "TERMS",
            "MS_PRODUCT",
            "VIEW_BLEND",
            "CURVATURE_REJECTION",
            "REFRACTION",
            "RING_SETS",
            "OUTPUT",
        }
    )
    | LIGHT_FLAGS,
    constants=shared_constants(PROFILE={name: code for code, name in enumerate(PROFILES)}),
)
TERM_BITS = {"specular": 1, "single": 2, "multiple": 4, "transmission": 8}
REFRACTION_MODES = {"off": 0, "on": 1, "exit": 2}


#: bytes per texel of a light view and of a screen map: position and normal (float32 RGBA) and a 32-bit depth
#: (measured 36.0 per light-map texel at 2048² and 4096²)
MAP_BYTES_PER_TEXEL = 36


def check_light_map(side: int) -> None:
    """Refuse a ``light_map`` whose light view (side² × MAP_BYTES_PER_TEXEL) exceeds the available memory."""
    check(
        "light_map",
        side * side * MAP_BYTES_PER_TEXEL,
        value=side,
        what=f"{side}² texels × {MAP_BYTES_PER_TEXEL} B: position, normal, depth",
        fits=lambda budget: largest_fitting(lambda n: n * n * MAP_BYTES_PER_TEXEL, 1, side, budget),
    )


class TranslucentShading(MaterialShading):
    """Translucent meshes lit by the one light of ``scene`` through its light view (``params``: the
    ``translucent`` method's parameters)."""

    material_type: ClassVar[type] = Translucent
    program: ClassVar[ProgramSpec] = TRANSLUCENT_PROGRAM

    def __init__(self, prepared: PreparedScene, scene: Scene, params):
        self.ctx = prepared.ctx
        self.prepared = prepared
        self.scene = scene
        self.params = params
        self._light = scene.light[0]
        self._gl = GLObjects(prepared.ctx)
        self._own = self._gl.own
        self._screen: dict = {}
        self._tables: list[dict] = []  # the texture tables handed to the pass (screen maps replaced in place)
        meshes = prepared.meshes
        # the light view encloses the translucent meshes (the only ones reading it), not the whole scene: a
        # light may stand anywhere outside them, and the map's texels are spent where they are read
        lit = [m for m, mesh in zip(meshes, scene.mesh, strict=True) if self._is_translucent(mesh)]
        points = np.concatenate([m.positions for m in lit or meshes]) if meshes else np.zeros((1, 3))
        self._light_view_proj, self._shadow_bias = self._light_camera(points)
        ctx = self.ctx
        check_light_map(params.light_map)
        size = (params.light_map, params.light_map)
        self._light_maps = tuple(self._own(ctx.texture(size, 4, dtype="f4")) for _ in range(2))
        for tex in self._light_maps:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            tex.repeat_x = tex.repeat_y = False
        light_depth = self._own(ctx.depth_texture(size))
        self._lv_fbo = self._own(
            ctx.framebuffer(color_attachments=list(self._light_maps), depth_attachment=light_depth)
        )
        self._light_view_drawn = False
        program = get_program(ctx, LIGHT_VIEW_PROGRAM)
        self._lv_vaos = [self._own(prepared.vertex_array(program, i)) for i in range(len(meshes))]
        self._back_vaos = []
        if params.refraction != "off":  # the back faces of translucent meshes only
            back = get_program(ctx, BACK_FACE_PROGRAM)
            self._back_vaos = [
                self._own(prepared.vertex_array(back, i))
                for i, mesh in enumerate(scene.mesh)
                if self._is_translucent(mesh)
            ]

    def _is_translucent(self, mesh) -> bool:
        return isinstance(self.scene.materials[mesh.material], Translucent)

    def _light_camera(self, points: np.ndarray) -> tuple[np.ndarray, float]:
        """View-projection of the light view enclosing the scene, and the shadow-test tolerance (scene units)."""
        center, radius = bounding_sphere(points)
        radius = max(radius, 1e-6)
        texel = 2.0 * radius / self.params.light_map
        if isinstance(self._light, DirectionalLight):  # the shadow maps' orthographic view
            view = directional_view(np.asarray(self._light.direction, dtype=np.float64), center, radius)
            return view["view_proj"], 4.0 * texel
        eye = np.asarray(self._light.position, dtype=np.float64)
        dist = np.linalg.norm(center - eye)
        if dist <= radius * 1.01:
            raise ArgumentError(
                "the translucent technique needs the point light outside the translucent meshes' bounding sphere "
                f"(distance {dist:.3g} ≤ radius {radius:.3g})",
                field="light[0].position",
            )
        fov = np.degrees(2.0 * np.arcsin(radius / dist))
        view = look_at(eye, center, (0.0, 1.0, 0.0) if abs((center - eye)[1]) < 0.99 * dist else (1.0, 0.0, 0.0))
        proj = perspective(fov, 1.0, max(dist - radius, 1e-4), dist + radius)
        return proj @ view, 4.0 * texel * dist / max(dist - radius, 1e-6)

    # ------------------------------------------------------------------ per material
    def flags(self, material: Translucent) -> dict[str, object]:
        p = self.params
        return {
            "LIGHT_DIRECTIONAL": int(isinstance(self._light, DirectionalLight)),
            "PROFILE": PROFILES.index(material.profile),
            "SS_NODES": p.k_max + 1,
            "RINGS": p.rings,
            "ANGLES": p.angles,
            "TERMS": self._terms(material),
            "MS_PRODUCT": int(p.ms_quadrature == "product"),
            "VIEW_BLEND": int(p.view_blend is not None),
            "CURVATURE_REJECTION": int(p.curvature_rejection is not None),
            "REFRACTION": REFRACTION_MODES[p.refraction],
            "RING_SETS": 3 if p.ring_sets == "per_channel" else 1,
        }

    def _terms(self, material: Translucent) -> int:
        bits = sum(TERM_BITS[t] for t in set(self.params.terms))
        return bits if material.single_scattering else bits & ~TERM_BITS["single"]

    def uniforms(self, material: Translucent) -> dict[str, object]:
        p = self.params
        medium = material.medium()
        radii_mm = ring_radii(p, material, medium)
        depths = march_depths(p.k_max, p.c_l)
        light = self._light
        light_vector = (
            -np.asarray(light.direction, np.float64) / np.linalg.norm(light.direction)
            if isinstance(light, DirectionalLight)
            else np.asarray(light.position, np.float64)
        )
        power = light.irradiance if isinstance(light, DirectionalLight) else light.intensity
        return {
            **glsl_uniforms(material.profile, medium),
            "a_sigma_s": tuple(float(v) for v in medium.sigma_s),
            "a_sigma_t": tuple(float(v) for v in medium.sigma_t),
            "a_g": float(material.g),
            "a_mm_per_unit": float(material.mm_per_unit),
            "a_diffuse_norm": (1.0 / (np.pi * diffuse_normalisation(material.eta)),) * 3,
            "a_ss_depth": depths.astype(np.float32).tobytes(),
            "a_ss_weight": quadrature_weights(depths, p.ss_rule).astype(np.float32).tobytes(),
            "a_ss_c_l": float(p.c_l),
            "a_ss_step": float(p.ss_rule == "step"),
            "u_background": tuple(float(v) for v in (self.scene.background_color() or (0.0, 0.0, 0.0))),
            "a_ring_radius": (radii_mm.ravel() / material.mm_per_unit).astype(np.float32).tobytes(),
            **ring_uniforms(p, material, medium, radii_mm),
            "u_light_view_proj": self._light_view_proj.T.astype(np.float32).tobytes(),
            "u_light_vector": tuple(float(v) for v in light_vector),
            "u_light_power": tuple(float(v) for v in power),
            "u_shadow_bias": float(self._shadow_bias),
            "a_blend_lambda": float(p.view_blend or 0.0),
            "a_curvature_max": float(p.curvature_rejection or 0.0),
        }

    def textures(self, material: Translucent) -> dict[str, object]:
        position, normal = self._light_maps
        table = {"u_light_position": position, "u_light_normal": normal}
        size = tuple(self.scene.camera.size)
        if self.params.view_blend is not None:
            cam_position, cam_normal = self._screen_maps("camera", size)
            table.update({"u_camera_position": cam_position, "u_camera_normal": cam_normal})
        if self.params.refraction != "off":
            back_position, back_normal = self._screen_maps("back", size)
            table.update({"u_back_position": back_position, "u_back_normal": back_normal})
        self._tables.append(table)
        return table

    @property
    def screen_bytes_per_sample(self) -> int:
        """Bytes per target sample of the screen maps (``camera`` with view_blend, ``back`` with refraction)."""
        return MAP_BYTES_PER_TEXEL * ((self.params.view_blend is not None) + (self.params.refraction != "off"))

    def _screen_maps(self, name: str, size: tuple[int, int]):
        """Position and normal maps at the render size, seen from the camera: ``camera`` (the view blend's
        first surfaces) or ``back`` (the refraction's back faces); re-created when the size changes, the
        texture tables handed out updated in place."""
        maps = self._screen
        if name in maps and maps[name][0][0].size == size:
            return maps[name][0]
        new = tuple(self._own(self.ctx.texture(size, 4, dtype="f4")) for _ in range(2))
        for tex in new:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            tex.repeat_x = tex.repeat_y = False
        depth_texture = self._own(depth.float_depth_texture(self.ctx, size))  # camera views: reversed-Z
        fbo = self._own(self.ctx.framebuffer(color_attachments=list(new), depth_attachment=depth_texture))
        keys = (f"u_{name}_position", f"u_{name}_normal")
        for table in self._tables:
            if keys[0] in table:
                table.update(dict(zip(keys, new, strict=True)))
        maps[name] = (new, fbo)
        return new

    # ------------------------------------------------------------------ per frame
    def draw_inputs(self, target, vp_bytes: bytes) -> None:
        """The light view (once per prepare: it depends on the light and the meshes, not on the camera, so a
        persistent renderer's camera moves re-use it), then the camera's maps of the view blend and the back
        faces of refraction at the target's size."""
        ctx = self.ctx
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        program = get_program(ctx, LIGHT_VIEW_PROGRAM)
        if not self._light_view_drawn:
            self._lv_fbo.use()
            ctx.viewport = (0, 0, self.params.light_map, self.params.light_map)
            self._lv_fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
            set_uniforms(program, {"u_view_proj": self._light_view_proj.T.astype(np.float32).tobytes()})
            for vao in self._lv_vaos:
                vao.render()
            self._light_view_drawn = True
        with depth.camera_depth(ctx):
            if self.params.view_blend is not None:  # the camera's own maps, same program
                self._screen_maps("camera", target.size)
                fbo = self._screen["camera"][1]
                fbo.use()
                ctx.viewport = (0, 0, *target.size)
                fbo.clear(0.0, 0.0, 0.0, 0.0, depth=depth.CLEAR)
                set_uniforms(program, {"u_view_proj": vp_bytes})
                for vao in self._lv_vaos:
                    vao.render()
            if self._back_vaos:  # the nearest back faces (refraction)
                self._screen_maps("back", target.size)
                fbo = self._screen["back"][1]
                fbo.use()
                ctx.viewport = (0, 0, *target.size)
                fbo.clear(0.0, 0.0, 0.0, 0.0, depth=depth.CLEAR)
                eye = view_eye(self.scene.camera)
                set_uniforms(get_program(ctx, BACK_FACE_PROGRAM), {"u_view_proj": vp_bytes, "u_eye": eye})
                for vao in self._back_vaos:
                    vao.render()
        ctx.disable(ctx.DEPTH_TEST)

    def release(self) -> None:
        self._gl.release()
        self._screen = {}
        self._tables = []


def ring_radii(params, material: Translucent, medium) -> np.ndarray:
    """Ring radii ρ_0 = 0 … ρ_K in mm, one row per ring set: r_max from ``radius_mfp`` (× the mean free
    path) or the capture radius, β fitted (∫|g''|) on the set's profile — the luminance-weighted one for a
    shared set (the widest channel's radius), each channel's own per channel."""
    p = params
    mfp = np.asarray(medium.mean_free_path, np.float64)  # mm
    r_max = p.radius_mfp * mfp if p.radius_mfp is not None else capture_radii(material.profile, medium)
    weights = np.eye(3)
    if p.ring_sets == "shared":
        weights, r_max = np.array([[0.2126, 0.7152, 0.0722]]), np.array([np.max(r_max)])
    radii = []
    for w, radius in zip(weights, r_max, strict=True):
        beta = p.beta
        if beta is None and material.profile == "multiple_fit":
            beta = multiple_fit.RING_BETA
        if beta is None:

            def rd(r_mm, w=w):
                return profile_rd(material.profile, np.asarray(r_mm)[..., None], medium) @ w

            beta = rings_module.fit_beta(rd, float(radius))
        radii.append(rings_module.ring_radii(float(radius), p.rings, beta))
    return np.array(radii)


def ring_uniforms(params, material: Translucent, medium, radii_mm: np.ndarray) -> dict[str, object]:
    """Per ring set (rows of ``radii_mm``), the node weights of the chosen quadrature (and 1/R_d at the ring
    radii for the product rule), stacked set after set."""
    p = params

    def rd(r):
        return profile_rd(material.profile, np.asarray(r)[..., None], medium)

    weights, inv_rd = [], []
    for radii in radii_mm:
        if p.ms_quadrature == "bilinear":
            weights.append(np.repeat(rings_module.ring_weights(radii, p.angles)[:, None], 3, axis=1))
            inv_rd.append(np.ones_like(weights[-1]))
        else:
            weights.append(rings_module.product_weights(radii, p.angles, rd, first_cell=False))
            # a channel whose profile has vanished at a ring (a wide radius for a strongly absorbed
            # channel) contributes nothing there: 0, not 1/0 (inf × 0 is NaN on the GPU)
            value = rd(np.maximum(radii, 1e-9))
            inv_rd.append(np.divide(1.0, value, out=np.zeros_like(value), where=value > 1e-30))
    return {
        "a_ring_weight": np.concatenate(weights).astype(np.float32).tobytes(),
        "a_ring_inv_rd": np.concatenate(inv_rd).astype(np.float32).tobytes(),
    }
