"""The viewer's highlight editing (docs/techniques/highlight-editing.md), a part of :class:`ViewerController`:
paint mode on the selected anisotropic mesh — bend / expand strokes solved before the next frame, the stencil,
the light tool —, undo / redo, the field saved, and the mesh's potential highlight curves (a line integral
convolution of ℓ) blended into the view."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import ArgumentError

#: the highlight-editing tools a drag applies: warps solved for, the stencil, and the light tool (the drag is
#: the highlight's new direction there: the light moves)
PAINT_TOOLS = ("bend", "expand", "stencil", "light")


class Painting:
    """Highlight editing for :class:`~reflets.viewer.controller.ViewerController` (which holds the state these
    methods read: ``scene``, ``renderer``, ``selection``, ``camera``, ``paint_tool``, …)."""

    def _on_paint(self, tool: str | None, radius: float | None = None) -> None:
        """Paint mode on the selected mesh (an anisotropic material used by that mesh alone), or off."""
        if tool is None:
            self.paint_tool = None
            return
        index = self._selected("mesh", None)
        name = self.scene.mesh[index].material
        if "orientation" not in type(self.scene.materials[name]).model_fields:
            raise ArgumentError(
                f"material '{name}' ({self.scene.materials[name].type}) has no orientation to edit: an anisotropic "
                "one (ward, ashikhmin_shirley, microfacet, scratched) has",
                field="event.paint",
            )
        if sum(mesh.material == name for mesh in self.scene.mesh) > 1:
            raise ArgumentError(f"material '{name}' is used by several meshes: one field cannot fit them all")
        if self._paint is None or self._paint.index != index:
            from ..editing.strokes import EditSession

            self._paint = EditSession(self.scene, index)
        self.paint_tool = tool
        self.paint_radius = float(radius) if radius else 0.15 * self._bounds(("mesh", index))[1]

    def _on_stroke(
        self, centre: list[float], stroke: list[float], tool: str | None = None, radius: float | None = None
    ) -> None:
        """One stroke on the painted mesh (what a paint drag sends between frames); the light tool moves the
        first point or directional light instead."""
        if self._paint is None:
            raise ArgumentError("no mesh is being painted: send a paint event first", field="event.stroke")
        tool = tool or self.paint_tool or "bend"
        if tool == "light":
            self._light_tool(np.asarray(centre, float), np.asarray(stroke, float))
            return
        self._paint.stroke(tool, centre, radius or self.paint_radius, stroke)
        self._apply_field()

    def _light_tool(self, centre: np.ndarray, direction: np.ndarray) -> None:
        from ..editing.strokes import EditSession
        from ..editing.tools import light_tool

        session = self._paint
        vertex = int(np.argmin(np.linalg.norm(session.mesh.positions - centre, axis=1)))
        index = next((i for i, lt in enumerate(self.scene.light) if lt.type in ("point", "directional")), None)
        if index is None:
            raise ArgumentError("the light tool moves a point or directional light: the scene has none")
        try:
            incoming, _ = light_tool(session.mesh, session.phi, vertex, direction, self.scene.camera.position)
        except ValueError as exc:
            raise ArgumentError(str(exc), field="event.stroke") from None
        light, p = self.scene.light[index], session.mesh.positions[vertex]
        if light.type == "point":
            fields = {"position": (p + np.linalg.norm(np.asarray(light.position) - p) * incoming).tolist()}
        else:
            fields = {"direction": (-incoming).tolist()}
        self.renderer.set_light(index, **fields)
        self._edited()
        self._paint = EditSession(self.scene, session.index)  # h changed with the light (the strokes restart)

    def _on_undo(self) -> None:
        if self._paint is not None and self._paint.undo():
            self._apply_field()

    def _on_redo(self) -> None:
        if self._paint is not None and self._paint.redo():
            self._apply_field()

    def _paint_drag(self, pointer: dict, x: float, y: float) -> None:
        """A drag from the stroke's start on the surface: its direction in the view plane, the stroke at the start
        (pending: the next frame applies it, so a fast drag costs one solve a frame)."""
        sx, sy = pointer["start"]
        right, up, _ = self.camera.basis()
        direction = (x - sx) * right - (y - sy) * up
        if np.any(direction):  # a drag back to its start is no stroke
            self._pending_stroke = {"centre": list(pointer["surface"]), "stroke": direction.tolist()}

    def _apply_field(self) -> None:
        import tempfile

        if self._fields_dir is None:
            self._fields_dir = Path(tempfile.mkdtemp(prefix="reflets-fields-"))
        path = self._fields_dir / f"field-{len(list(self._fields_dir.iterdir()))}.npz"
        np.savez(path, u=self._paint.field().astype(np.float32))
        name = self.scene.mesh[self._paint.index].material
        self.renderer.set_material(name, orientation=str(path))
        self._edited()

    def _on_show_highlights(self, on: bool) -> None:
        self.show_highlights = bool(on)

    def highlight_curves(self) -> tuple[np.ndarray, np.ndarray]:
        """The selected mesh's potential highlight curves in the view: a line integral convolution of its ℓ
        (editing/lic.py) over the pixels that show the mesh, (H, W) in [0, 1], and that mask — what the view
        blends in when ``show_highlights`` is on (the curves its highlight may follow as the light moves)."""
        from ..editing.highlights import mesh_highlights
        from ..editing.lic import line_integral_convolution
        from ..reference.geometry import MESHES, SceneGeometry
        from ..scene.camera import pixel_rays, project
        from ..scene.geometry import mesh_data

        width, height = self.size
        empty = (np.zeros((height, width)), np.zeros((height, width), bool))
        if self.selection is None or self.selection[0] != "mesh":
            return empty
        index = self.selection[1]
        key = (index, self.scene.camera.model_dump_json(), id(self.scene))
        if getattr(self, "_curves_key", None) == key:
            return self._curves
        try:
            found = mesh_highlights(self.scene, index)
        except ArgumentError:  # no point or directional light: no highlight curves
            self._curves, self._curves_key = empty, key
            return empty
        if self._geometry is None:
            self._geometry = SceneGeometry(self.scene)
        geometry = self._geometry
        origin, dirs = pixel_rays(self.scene.camera, self.size)
        origins = np.broadcast_to(origin, dirs.shape).reshape(-1, 3)  # an orthographic camera's: one per pixel
        hits = geometry.intersect(origins, dirs.reshape(-1, 3))
        on = (hits.kind == MESHES) & (geometry.face_mesh[np.maximum(hits.prim, 0)] == index)
        offset = sum(mesh_data(self.scene, j).n_vertices for j in range(index))  # its vertices in the geometry's
        corners = geometry.faces[hits.prim[on]] - offset  # in the mesh's own vertex order (mesh_data's)
        ell = found["ell"][corners]  # (N, 3 corners, 3)
        ell[:, 1:] *= np.where(np.einsum("nj,ncj->nc", ell[:, 0], ell[:, 1:]) < 0, -1.0, 1.0)[..., None]
        u, v = hits.u[on], hits.v[on]
        along = (1 - u - v)[:, None] * ell[:, 0] + u[:, None] * ell[:, 1] + v[:, None] * ell[:, 2]
        points = origins[on] + hits.t[on][:, None] * dirs.reshape(-1, 3)[on]
        scale = 1e-3 * self._bounds(("mesh", index))[1]
        screen = project(self.scene.camera, points + scale * along, self.size) - project(
            self.scene.camera, points, self.size
        )
        directions = np.zeros((height * width, 2))
        directions[on] = np.nan_to_num(screen)
        mask = on.reshape(height, width)
        self._curves = (line_integral_convolution(directions.reshape(height, width, 2), mask), mask)
        self._curves_key = key
        return self._curves

    def save_field(self, path: str | Path, overwrite: bool = False) -> Path:
        """The painted mesh's orientation field (.npz, u), for a material's ``orientation``."""
        import io

        from ..outputs import atomic_write, check_output

        if self._paint is None:
            raise ArgumentError("no mesh is being painted", field="save_field")
        path = check_output(path, (".npz",), inputs=self.scene.input_files(), overwrite=overwrite)
        with io.BytesIO() as buffer:
            np.savez(buffer, u=self._paint.field().astype(np.float32))
            atomic_write(path, buffer.getvalue())
        return path
