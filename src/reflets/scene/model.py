"""The validated scene model: camera, meshes, named materials, lights, background.

Scenes are plain data, like Mitsuba dicts: every object names its ``type`` (or ``shape``) and the
model rejects unknown keys, wrong vector lengths and out-of-range values. Units: metres (or any unit
used consistently), degrees for angles, radiometric quantities in linear RGB.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    Tag,
    field_validator,
    model_validator,
)

from ..quantities import Finite, NonNeg, Positive

Vec3 = tuple[Finite, Finite, Finite]
Color = tuple[NonNeg, NonNeg, NonNeg]
Count = Annotated[int, Field(ge=1, le=4096)]  # tessellation segments

MAX_IMAGE_SIDE = 16384


class Strict(BaseModel):
    """Base for scene objects: unknown keys are errors, assignments are validated."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False)


class Camera(Strict):
    """Pinhole camera. ``fov_y`` is the full vertical field of view in degrees (Mitsuba, OpenGL); with
    ``projection = "orthographic"``, parallel rays along the view direction over a window ``ortho_height`` scene
    units high (a glTF orthographic camera's 2 × ymag), centred on the camera's axis."""

    position: Vec3
    look_at: Vec3
    up: Vec3 = (0.0, 1.0, 0.0)
    fov_y: Annotated[float, Field(gt=0, lt=180, allow_inf_nan=False)] = 45.0
    projection: Literal["perspective", "orthographic"] = "perspective"
    ortho_height: Annotated[float, Field(gt=0, le=1e9, allow_inf_nan=False)] | None = Field(
        None, description="orthographic: the view window's full height in scene units (required there)"
    )
    principal_offset: tuple[Annotated[float, Field(ge=-1, le=1, allow_inf_nan=False)], ...] = Field(
        (0.0, 0.0),
        min_length=2,
        max_length=2,
        description="the principal point's offset from the image centre in fractions of the image's width and "
        "height (x right, y down): a calibrated camera's (cx, cy) off centre (Mitsuba's principal_point_offset)",
    )
    pixel_aspect: Annotated[float, Field(gt=0.1, lt=10, allow_inf_nan=False)] = Field(
        1.0, description="horizontal over vertical focal length (fx / fy of a calibrated camera; fov_y is vertical)"
    )
    size: tuple[Annotated[int, Field(ge=1, le=MAX_IMAGE_SIDE)], Annotated[int, Field(ge=1, le=MAX_IMAGE_SIDE)]] = (
        640,
        480,
    )
    near: Positive | None = Field(
        None,
        description="near clip distance (scene units); default: 1/1000 of the smallest object's size, or less where "
        "an object is nearer (depth is reversed-Z float: its precision does not depend on it)",
    )
    far: Positive | None = Field(
        None, description="far clip distance (scene units); default: none (an infinite far plane)"
    )

    @model_validator(mode="after")
    def _non_degenerate(self) -> Camera:
        if self.projection == "orthographic" and self.ortho_height is None:
            raise ValueError("ortho_height: required by an orthographic camera (the view window's height)")
        if self.near is not None and self.far is not None and not self.near < self.far:
            raise ValueError(f"near ({self.near:g}) must be less than far ({self.far:g})")
        forward = np.subtract(self.look_at, self.position)
        if np.linalg.norm(forward) == 0:
            raise ValueError("position and look_at coincide; the view direction is undefined")
        if np.linalg.norm(np.cross(forward, self.up)) < 1e-9 * np.linalg.norm(forward) * max(
            np.linalg.norm(self.up), 1e-30
        ):
            raise ValueError("up is parallel to the view direction (or zero); choose another up vector")
        return self

    @property
    def orthographic(self) -> bool:
        return self.projection == "orthographic"

    @property
    def width(self) -> int:
        return self.size[0]

    @property
    def height(self) -> int:
        return self.size[1]


class Transform(Strict):
    """Object-to-world transform: scale, then rotate about X, Y, Z (degrees), then translate."""

    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate: Vec3 = (0.0, 0.0, 0.0)
    scale: Positive | tuple[Positive, Positive, Positive] = 1.0

    def matrix(self) -> np.ndarray:
        from .transform import transform_matrix

        return transform_matrix(self.translate, self.rotate, self.scale)


class MeshBase(Strict):
    name: str | None = None
    material: str
    transform: Transform = Transform()
    #: a smooth curved mirror whose reflections the ``fermat`` method renders (material type "mirror")
    reflector: bool = False


class FileMesh(MeshBase):
    """A mesh read from OBJ / PLY / glTF / GLB / STL / OFF (path relative to the scene file).

    A glTF or OBJ file without ``material`` stands for its whole scene with its own materials: the loader expands it
    into one mesh per primitive instance (``part``; an OBJ's: per material), the file's node transforms baked in,
    ``transform`` on top. With a ``material``, every triangle of the file is one mesh of that material."""

    file: Path
    material: str | None = Field(
        None, description="the material of every triangle (required unless the file is a glTF or OBJ file: its own)"
    )
    part: Annotated[int, Field(ge=0)] | None = Field(
        None, description="a glTF file's primitive instance or an OBJ file's faces of one material (set by the loader)"
    )


class PlaneMesh(MeshBase):
    """Rectangle in the y = 0 plane, centred at the origin, normal +y."""

    shape: Literal["plane"]
    size: tuple[Positive, Positive] = (1.0, 1.0)
    segments: tuple[Count, Count] = (1, 1)


class SphereMesh(MeshBase):
    """Sphere centred at the origin, (u, v) = (azimuth, polar angle) parameterisation."""

    shape: Literal["sphere"]
    radius: Positive = 1.0
    segments: tuple[Count, Count] = (256, 128)


class CubeMesh(MeshBase):
    shape: Literal["cube"]
    size: Positive | tuple[Positive, Positive, Positive] = 1.0


class CylinderMesh(MeshBase):
    """Capped cylinder along y, centred at the origin."""

    shape: Literal["cylinder"]
    radius: Positive = 0.5
    height: Positive = 1.0
    segments: Count = 128
    caps: bool = True

    @model_validator(mode="after")
    def _open_reflector(self) -> CylinderMesh:
        if self.reflector and self.caps:
            raise ValueError("a reflector cylinder is its smooth side only: set caps = false")
        return self


class TorusMesh(MeshBase):
    """Torus around the y axis."""

    shape: Literal["torus"]
    major: Positive = 1.0
    minor: Positive = 0.25
    segments: tuple[Count, Count] = (128, 64)

    @model_validator(mode="after")
    def _minor_below_major(self) -> TorusMesh:
        if self.minor >= self.major:
            raise ValueError(f"minor ({self.minor}) must be smaller than major ({self.major})")
        return self


ControlRow = Annotated[list[Vec3], Field(min_length=4, max_length=4)]


class BezierMesh(MeshBase):
    """Bicubic Bézier patch: ``control_points[i][j]`` weighs B_i(u) B_j(v) (outer list along u, inner along v);
    the front side is f_u × f_v. Usable as a reflector (the solver runs on the exact patch)."""

    shape: Literal["bezier"]
    control_points: Annotated[list[ControlRow], Field(min_length=4, max_length=4)]
    segments: tuple[Count, Count] = (32, 32)

    @field_validator("control_points")
    @classmethod
    def _not_degenerate(cls, value: list[list[tuple[float, float, float]]]) -> list[list[tuple[float, float, float]]]:
        from .shapes import bezier_degeneracy

        problem = bezier_degeneracy(np.asarray(value, dtype=np.float64))
        if problem:
            raise ValueError(problem)
        return value


class HeightFieldMesh(MeshBase):
    """y = height_scale · h(x, z) over the size[0] × size[1] rectangle centred at the origin (Catmull–Rom
    bicubic between samples); ``heights`` inline or ``file`` (.npy, relative to the scene file); row 0 at
    z = −d/2, column 0 at x = −w/2. Usable as a reflector."""

    shape: Literal["heightfield"]
    heights: list[list[Finite]] | None = None
    file: Path | None = None
    size: tuple[Positive, Positive] = (1.0, 1.0)
    height_scale: Finite = 1.0
    segments: tuple[Count, Count] | None = None

    @field_validator("heights")
    @classmethod
    def _grid(cls, value: list[list[float]] | None) -> list[list[float]] | None:
        from .shapes import heights_problem

        if value is not None:
            lengths = {len(row) for row in value}
            if len(lengths) > 1:
                raise ValueError(f"rows have different lengths {sorted(lengths)}; heights must be a rectangular grid")
            problem = heights_problem(np.asarray(value, dtype=np.float64))
            if problem:
                raise ValueError(problem)
        return value

    @model_validator(mode="after")
    def _one_source(self) -> HeightFieldMesh:
        if (self.heights is None) == (self.file is None):
            raise ValueError("a heightfield needs exactly one of heights (inline 2D array) or file (a .npy file)")
        return self


SHAPE_MODELS: dict[str, type[MeshBase]] = {
    "plane": PlaneMesh,
    "sphere": SphereMesh,
    "cube": CubeMesh,
    "cylinder": CylinderMesh,
    "torus": TorusMesh,
    "bezier": BezierMesh,
    "heightfield": HeightFieldMesh,
}


def _mesh_tag(value: Any) -> str | None:
    if isinstance(value, dict):
        return "file" if "file" in value and "shape" not in value else value.get("shape")
    return "file" if isinstance(value, FileMesh) else getattr(value, "shape", None)


_SHAPES_ALLOWED = ", ".join(['file = "…"'] + [f'shape = "{s}"' for s in SHAPE_MODELS])
Mesh = Annotated[
    Union[  # noqa: UP007 (Tag needs the typing form)
        Annotated[FileMesh, Tag("file")],
        *(Annotated[m, Tag(name)] for name, m in SHAPE_MODELS.items()),
    ],
    Discriminator(
        _mesh_tag,
        custom_error_type="mesh_kind",
        custom_error_message=f"unknown or missing shape; allowed: {_SHAPES_ALLOWED}",
    ),
]


def _non_zero(v: tuple[float, float, float]) -> tuple[float, float, float]:
    if not np.any(v):
        raise ValueError("direction must not be the zero vector")
    return v


#: a direction (any length but zero)
Direction = Annotated[Vec3, AfterValidator(_non_zero)]


class SpotCone(Strict):
    """A point light's cone (glTF's spot light): full intensity within ``inner_deg`` of ``direction``, none beyond
    ``outer_deg``, between them KHR_lights_punctual's smooth falloff t² with t = (cos θ − cos θ_o) / (cos θ_i −
    cos θ_o) (the specification's recommended form, as Khronos' sample viewer and three.js draw it)."""

    direction: Direction
    inner_deg: Annotated[float, Field(ge=0, lt=90, allow_inf_nan=False)] = 0.0
    outer_deg: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)] = 45.0

    @model_validator(mode="after")
    def _ordered(self) -> SpotCone:
        if self.inner_deg >= self.outer_deg:
            raise ValueError(f"inner_deg ({self.inner_deg:g}) must be less than outer_deg ({self.outer_deg:g})")
        return self

    def scale_offset(self) -> tuple[float, float]:
        """(s, o) with t = clamp(cos θ · s + o, 0, 1): KHR_lights_punctual's angular attenuation before squaring."""
        cos_inner, cos_outer = np.cos(np.radians(self.inner_deg)), np.cos(np.radians(self.outer_deg))
        scale = 1.0 / max(1e-3, cos_inner - cos_outer)
        return float(scale), float(-cos_outer * scale)

    @property
    def axis(self) -> np.ndarray:
        """The unit direction of the cone."""
        return np.asarray(self.direction, np.float64) / np.linalg.norm(self.direction)

    def falloff(self, from_light: np.ndarray) -> np.ndarray:
        """The attenuation (N,) along unit directions (N, 3) from the light."""
        scale, offset = self.scale_offset()
        return np.clip(from_light @ self.axis * scale + offset, 0.0, 1.0) ** 2


class PointLight(Strict):
    """Point light; ``intensity`` is radiant intensity (W/sr) per RGB channel, isotropic or, with ``spot``, within
    a cone."""

    type: Literal["point"]
    position: Vec3
    intensity: Color
    shadows: bool = Field(True, description="casts shadows (GPU: a cube shadow map; the reference: shadow rays)")
    spot: SpotCone | None = Field(None, description="a cone (glTF spot light): direction, inner_deg, outer_deg")

    def falloff(self, from_light: np.ndarray) -> np.ndarray:
        """The intensity's angular factor (N,) along unit directions (N, 3) from the light (1 without a cone)."""
        return np.ones(len(from_light)) if self.spot is None else self.spot.falloff(from_light)


class DirectionalLight(Strict):
    """Distant light; ``direction`` is the direction the light travels along, ``irradiance`` on a
    surface facing it (W/m²)."""

    type: Literal["directional"]
    direction: Direction
    irradiance: Color
    shadows: bool = Field(True, description="casts shadows (GPU: a shadow map over the scene; the reference: rays)")


class QuadLight(Strict):
    """Parallelogram light from corners c1 (bottom-left), c2 (bottom-right), c4 (top-left), constant
    radiance; emits on the side of normalize((c2 − c1) × (c4 − c1)) unless two-sided.

    ``mask`` (optional image, path relative to the scene file) shapes the light as in the area-light
    document: its value in [0, 1] multiplies the radiance, u along c1 → c2, v along c1 → c4, the image's
    bottom-left texel at c1 (texture convention), each texel a cell of constant emission (nearest texel, so
    every renderer integrates the same emitter; ``scene/lightmask.py``)."""

    type: Literal["quad"]
    corners: tuple[Vec3, Vec3, Vec3]
    radiance: Color
    two_sided: bool = False
    mask: Path | None = None
    shadows: bool = Field(True, description="casts soft shadows (GPU: shadow maps from points over the emitter)")

    @model_validator(mode="after")
    def _non_degenerate(self) -> QuadLight:
        c1, c2, c4 = (np.asarray(c) for c in self.corners)
        if np.linalg.norm(np.cross(c2 - c1, c4 - c1)) <= 1e-12:
            raise ValueError("corners are collinear; the quad has zero area")
        return self

    def polygon(self) -> np.ndarray:
        """Vertices in order c1, c2, c3, c4 (counter-clockwise around the emitting normal)."""
        c1, c2, c4 = (np.asarray(c, dtype=np.float64) for c in self.corners)
        return np.stack([c1, c2, c2 + c4 - c1, c4])


class PolygonLight(Strict):
    """Planar convex polygon light; emits on the side of the normal given by the vertex order
    (counter-clockwise seen from the lit side) unless two-sided."""

    type: Literal["polygon"]
    vertices: list[Vec3] = Field(min_length=3, max_length=16)
    radiance: Color
    two_sided: bool = False
    shadows: bool = Field(True, description="casts soft shadows (GPU: shadow maps from points over the emitter)")

    @model_validator(mode="after")
    def _planar_convex(self) -> PolygonLight:
        p = np.asarray(self.vertices, dtype=np.float64)
        edges = np.roll(p, -1, axis=0) - p
        normal = np.sum(np.cross(p, np.roll(p, -1, axis=0)), axis=0)  # Newell's method
        size = np.max(np.linalg.norm(edges, axis=1))
        if np.linalg.norm(normal) <= 1e-12 * size * size:
            raise ValueError("vertices have zero area")
        n = normal / np.linalg.norm(normal)
        if np.max(np.abs((p - p[0]) @ n)) > 1e-4 * size:
            raise ValueError("vertices are not coplanar")
        turns = np.cross(edges, np.roll(edges, -1, axis=0)) @ n
        if np.any(turns < -1e-9 * size * size):
            raise ValueError("polygon is not convex (or its vertices are not in order)")
        return self

    def polygon(self) -> np.ndarray:
        return np.asarray(self.vertices, dtype=np.float64)


class EnvironmentLight(Strict):
    """Equirectangular environment map (EXR, HDR, NPY, PNG), same orientation as Mitsuba 3's ``envmap``:
    direction d maps to u = atan2(d.x, −d.z) / 2π (mod 1), v = acos(d.y) / π (row 0 = up)."""

    type: Literal["environment"]
    file: Path
    scale: NonNeg = 1.0
    rotate_y: Finite = 0.0
    shadows: bool = Field(True, description="occluded by the scene (GPU: shadow maps from 32 directions)")
    emitters: Literal["keep", "extract"] = Field(
        "extract", description='"extract": the GPU renders the map\'s compact emitters (a sun) as directional lights '
        "and prefilters the rest (scene.map_emitters); the references always see the whole map")
    #: set on the GPU's copy whose emitters are already lights of its scene (``map_emitters.with_map_emitters``):
    #: only then is the map lit as its residual — a scene prepared without the split keeps the whole map
    _split: bool = PrivateAttr(False)


LIGHT_MODELS = {
    "point": PointLight,
    "directional": DirectionalLight,
    "quad": QuadLight,
    "polygon": PolygonLight,
    "environment": EnvironmentLight,
}
Light = Annotated[
    Union[PointLight, DirectionalLight, QuadLight, PolygonLight, EnvironmentLight],  # noqa: UP007
    Field(discriminator="type"),
]


class Scene(Strict):
    """A whole scene. ``base_dir`` resolves relative file paths (the scene file's folder)."""

    title: str | None = None
    description: str | None = None
    camera: Camera
    # every registered material, by its ``type``: the union is completed by reflets.materials (above the
    # technique packages that define some materials), which importing reflets runs first
    materials: dict[str, MaterialSpec] = Field(default_factory=dict)  # noqa: F821
    mesh: list[Mesh] = Field(default_factory=list)
    light: list[Light] = Field(default_factory=list)
    background: Color | Literal["environment"] | None = None
    method: str | None = None
    base_dir: Path | None = Field(default=None, exclude=True)

    @model_validator(mode="after")
    def _references(self) -> Scene:
        for i, m in enumerate(self.mesh):
            if m.material is None:
                continue  # a glTF / OBJ file standing for its own meshes and materials (expanded by the loader)
            if m.material not in self.materials:
                known = ", ".join(sorted(self.materials)) or "none defined"
                raise ValueError(f"mesh[{i}].material: unknown material '{m.material}'; defined materials: {known}")
            if m.reflector and self.materials[m.material].type != "mirror":
                raise ValueError(
                    f'mesh[{i}].reflector: a reflector needs a material of type "mirror", '
                    f"'{m.material}' is \"{self.materials[m.material].type}\""
                )
        envs = [light for light in self.light if isinstance(light, EnvironmentLight)]
        if len(envs) > 1:
            raise ValueError("light: at most one environment light is allowed")
        if self.background == "environment" and not envs:
            raise ValueError('background = "environment" needs a light of type "environment"')
        return self

    @property
    def environment(self) -> EnvironmentLight | None:
        return next((light for light in self.light if isinstance(light, EnvironmentLight)), None)

    def background_color(self) -> tuple[float, float, float] | None:
        """RGB of a constant background, or None when the environment map is shown."""
        if self.background is None:
            return None if self.environment is not None else (0.0, 0.0, 0.0)
        return None if self.background == "environment" else tuple(self.background)

    def input_files(self) -> set[Path]:
        """Every file the scene reads — mesh and height-field files, textures, light masks, environment maps,
        measured BRDFs, orientation fields: each a ``Path`` field; scratch profiles (``file:PATH``); a .gltf file's
        buffers and images —, resolved.
        An output must not replace one."""
        found: set[Path] = set()

        def walk(value) -> None:
            if isinstance(value, Path):
                found.add(self.resolve(value).resolve())
            elif isinstance(value, str) and value.startswith("file:"):  # a scratch profile read from a file
                found.add(self.resolve(Path(value[5:])).resolve())
            elif isinstance(value, dict):
                for item in value.values():
                    walk(item)
            elif isinstance(value, list | tuple):
                for item in value:
                    walk(item)

        walk(self.model_dump(exclude_none=True))
        for path in [p for p in found if p.suffix.lower() == ".gltf"]:  # and the .bin / images it names by uri
            from ..errors import SceneError
            from ..gltf_file import read_gltf

            try:
                found.update(target.resolve() for target in read_gltf(path).external_files())
            except SceneError:
                pass  # reading the scene says what is wrong with it
        return found

    def resolve(self, path: Path) -> Path:
        """A path from the scene, made absolute against the scene file's folder."""
        path = Path(path).expanduser()
        return path if path.is_absolute() or self.base_dir is None else self.base_dir / path
