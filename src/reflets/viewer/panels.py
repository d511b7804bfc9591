"""The window's panels (Dear ImGui through imgui-bundle, drawn by moderngl-window's renderer): every widget sends
a controller event, so what a panel does is what a script replays. Edits are sent when a widget is released
(a drag would otherwise prepare the scene again at every pixel of it).

- View: method, area-light method (auto), shadows, exposure, tone curve, what to show (image / reference /
  error), the reference's spp and its start, reset / frame, saving (screenshot, scene, camera);
- Frame: median frame time, accumulated frames and spp, GL renderer, the reference's progress and the
  relative MSE against it;
- Selection (a click in the view selects): a mesh's material parameters and transform (and, for an anisotropic
  material, highlight painting: tool, brush radius, undo / redo, save the field), a light's position (or
  corners), power and shadows. A glTF material's factors are edited like any parameter (its RGBA base colour as
  a colour); each of its textures is shown — a picture of the image as stored, its file, uv set and encoding.
"""

from __future__ import annotations

from pathlib import Path

import moderngl
import numpy as np

#: what the method combo offers (every whole-frame method, and auto)
METHODS = (
    "auto",
    "forward",
    "ltc",
    "brute",
    "adaptive",
    "biased",
    "analytic",
    "mc",
    "translucent",
    "scratches",
    "fermat",
)
AREA_METHODS = ("ltc", "forward", "brute", "adaptive", "biased", "analytic", "mc")
TONEMAPS = ("srgb", "aces")
SHOWS = ("image", "reference", "error")
#: three-component fields edited as colours (HDR: values above 1 allowed)
COLOURS = {
    "albedo",
    "diffuse",
    "specular",
    "radiance",
    "intensity",
    "irradiance",
    "kd",
    "ks",
    "rd",
    "rs",
    "reflectance",
    "emissive",
    "sheen_color",
    "specular_color",
    "attenuation_color",
}
#: four-component fields edited as colours with alpha (glTF's base colour: alpha is coverage, in [0, 1])
COLOURS_ALPHA = {"base_color"}
#: the larger side of a texture's picture in the Selection panel, in pixels
THUMBNAIL = 96


def thumbnail(codes: np.ndarray, side: int = THUMBNAIL) -> np.ndarray:
    """A texture's picture for the panel: its stored codes (H, W, 4 uint8, row 0 at the top) subsampled to at most
    ``side`` pixels a side, made opaque (a cut-out's holes would hide the colours)."""
    h, w = codes.shape[:2]
    step = max(1, -(-max(h, w) // side))
    picture = np.array(codes[::step, ::step], np.uint8)
    picture[..., 3] = 255
    return np.ascontiguousarray(picture)


class Panels:
    """The panels of one window (one ImGui context)."""

    def __init__(self, wnd):
        from imgui_bundle import imgui
        from moderngl_window.integrations.imgui_bundle import ModernglWindowRenderer

        self.imgui = imgui
        imgui.create_context()
        imgui.get_io().set_ini_filename("")  # no imgui.ini left in the user's folder (a file "" cannot open)
        self.renderer = ModernglWindowRenderer(wnd)
        self.visible = True
        self.spp = 64
        self._pending: dict[str, object] = {}  # widget id → value being dragged
        self._thumbnails: dict[str, moderngl.Texture] = {}  # texture content key → its picture, registered
        self._events: list[dict] = []
        self.saves: list[str] = []  # "screenshot" / "scene" / "camera" asked for this frame

    @property
    def wants_mouse(self) -> bool:
        return self.visible and self.imgui.get_io().want_capture_mouse

    @property
    def wants_keyboard(self) -> bool:
        return self.visible and self.imgui.get_io().want_capture_keyboard

    def draw(self, controller) -> list[dict]:
        """Draw the panels over the current framebuffer; the events their widgets sent this frame."""
        imgui = self.imgui
        self._events, self.saves = [], []
        imgui.new_frame()
        if self.visible:
            self._markers(controller)
            self._view(controller)
            self._frame(controller)
            self._selection(controller)
        imgui.render()
        self.renderer.render(imgui.get_draw_data())
        # the GL defaults back (the ImGui renderer leaves blending on): reflets' passes enable what they use
        ctx = self.renderer.ctx
        ctx.enable_only(moderngl.NOTHING)
        ctx.blend_func = moderngl.ONE, moderngl.ZERO
        ctx.blend_equation = moderngl.FUNC_ADD
        return self._events

    def release(self) -> None:
        for texture in self._thumbnails.values():
            texture.release()
        self._thumbnails = {}
        self.renderer.shutdown()
        self.imgui.destroy_context()

    # ------------------------------------------------------------------ panels
    def _view(self, c) -> None:
        imgui = self.imgui
        imgui.set_next_window_pos(imgui.ImVec2(8, 8), imgui.Cond_.first_use_ever)
        imgui.set_next_window_size(imgui.ImVec2(300, 0), imgui.Cond_.first_use_ever)
        imgui.begin("View")
        self._choice("method", c.method, METHODS, lambda m: {"type": "method", "name": m})
        if c.method == "auto":
            area = c.params.get("area_method", "ltc")
            params = c.params
            self._choice(
                "area lights",
                area,
                AREA_METHODS,
                lambda m: {"type": "method", "name": "auto", "params": {**params, "area_method": m}},
            )
        on = all(light.shadows for light in c.scene.light) if c.scene.light else True
        changed, value = imgui.checkbox("shadows", on)
        if changed:
            self._events.append({"type": "shadows", "on": value})
        changed, stops = imgui.slider_float("exposure", c.exposure, -8.0, 8.0, "%.1f stops")
        if changed:
            self._events.append({"type": "exposure", "stops": stops})
        self._choice("tone curve", c.tonemap_mode, TONEMAPS, lambda m: {"type": "tonemap", "mode": m})
        self._choice("show", c.show, SHOWS, lambda m: {"type": "show", "mode": m})
        _, self.spp = imgui.input_int("ref. spp", self.spp, 16, 64)
        self.spp = int(np.clip(self.spp, 4, 4096))
        if imgui.button("compute reference"):
            self._events.append({"type": "reference", "spp": self.spp})
        if imgui.button("reset camera"):
            self._events.append({"type": "reset"})
        imgui.same_line()
        if imgui.button("frame"):
            self._events.append({"type": "frame"})
        imgui.text("save")
        for what in ("screenshot", "scene", "camera"):
            imgui.same_line()
            if imgui.button(what):
                self.saves.append(what)
        imgui.end()

    def _frame(self, c) -> None:
        imgui = self.imgui
        status = c.status()
        imgui.set_next_window_pos(imgui.ImVec2(8, 330), imgui.Cond_.first_use_ever)
        imgui.begin("Frame")
        imgui.text(f"{status['frame_ms']:.1f} ms to draw (median)  {status['frames']} frame(s), {status['spp']} spp")
        gpu = f"  GPU {status['gpu_ms']:.2f} ms" if status["gpu_ms"] is not None else "  (no GPU timer here)"
        imgui.text(f"CPU {status['cpu_ms']:.1f} ms{gpu}")
        imgui.text(status["renderer"])
        if "reference_progress" in status:
            fraction = status["reference_progress"]
            imgui.progress_bar(fraction, imgui.ImVec2(-1, 0), f"reference {100 * fraction:.0f} %")
        if "relmse" in status:
            imgui.text(f"relative MSE {status['relmse']:.3e}")
        if "reference_error" in status:
            imgui.text(status["reference_error"])
        imgui.end()

    def _selection(self, c) -> None:
        imgui = self.imgui
        # kept at the view's right edge, fitted to what is selected (later selections grow it), within the view's
        # height (then it scrolls)
        imgui.set_next_window_pos(imgui.ImVec2(c.size[0] - 8, 8), imgui.Cond_.always, imgui.ImVec2(1.0, 0.0))
        imgui.set_next_window_size_constraints(imgui.ImVec2(280, 0), imgui.ImVec2(c.size[0], c.size[1] - 16))
        imgui.begin("Selection", None, imgui.WindowFlags_.always_auto_resize)
        imgui.push_item_width(150)  # what the window's width is fitted to
        imgui.text(c.selection_label())
        for index in range(len(c.scene.light)):  # lights without a surface to click
            if index:
                imgui.same_line()
            if imgui.small_button(f"light[{index}]"):
                self._events.append({"type": "select", "light": index})
        if c.selection is not None:
            kind, index = c.selection
            if kind == "mesh":
                name = c.scene.mesh[index].material
                imgui.separator()
                imgui.text(f"material '{name}'")
                material = c.scene.materials[name]
                fields = material.model_dump(exclude_none=True)
                for field, value in fields.pop("maps", {}).items():  # mapped colours (their factors edited below)
                    self._texture(field, value, material.texture_data(field))
                for field, value in fields.items():
                    if isinstance(value, dict) and "texture" in value:  # a texture slot (glTF)
                        self._texture(field, value, material.texture_data(field))
                        continue
                    self._field(f"m.{name}.{field}", field, value,
                                lambda f, v, n=name: {"type": "material", "name": n, "fields": {f: v}})  # fmt: skip
                if "orientation" in type(c.scene.materials[name]).model_fields:
                    self._paint_widgets(c)
                imgui.separator()
                imgui.text("transform")
                for field, value in c.scene.mesh[index].transform.model_dump().items():
                    self._field(f"t.{index}.{field}", field, value,
                                lambda f, v, i=index: {"type": "transform", "index": i, "fields": {f: v}})  # fmt: skip
            else:
                for field, value in c.scene.light[index].model_dump(exclude_none=True).items():
                    self._field(f"l.{index}.{field}", field, value,
                                lambda f, v, i=index: {"type": "light", "index": i, "fields": {f: v}})  # fmt: skip
        imgui.pop_item_width()
        imgui.end()

    def _paint_widgets(self, c) -> None:
        """Highlight editing on the selected mesh: the paint tool (a left drag on the mesh strokes it), the
        brush radius, undo / redo, saving the field."""
        imgui = self.imgui
        imgui.separator()
        tools = ("off", "bend", "expand", "stencil", "light")
        current = c.paint_tool or "off"
        changed, k = imgui.combo("paint", tools.index(current), list(tools))
        if changed:
            self._events.append(
                {"type": "paint", "tool": None if k == 0 else tools[k], "radius": c.paint_radius or None}
            )
        changed, on = imgui.checkbox("highlight curves", c.show_highlights)
        if changed:
            self._events.append({"type": "show_highlights", "on": on})
        if c.paint_tool is not None:
            changed, radius = imgui.drag_float("brush radius", c.paint_radius, 0.005, 0.001, 100.0, "%.3f")
            if changed:
                self._events.append({"type": "paint", "tool": c.paint_tool, "radius": radius})
            if imgui.button("undo"):
                self._events.append({"type": "undo"})
            imgui.same_line()
            if imgui.button("redo"):
                self._events.append({"type": "redo"})
            imgui.same_line()
            if imgui.button("save field"):
                self.saves.append("field")

    def _markers(self, c) -> None:
        """The lights' gizmos: a disc at each point light, a ring at each area light's centre (yellow when
        selected); a click selects, a shift-drag moves."""
        imgui = self.imgui
        draw = imgui.get_background_draw_list()
        for index, (x, y) in c.light_pixels().items():
            selected = c.selection == ("light", index)
            colour = imgui.get_color_u32(imgui.ImVec4(1.0, 0.85, 0.1, 1.0) if selected else imgui.ImVec4(1, 1, 1, 0.9))
            centre = imgui.ImVec2(x, y)
            if c.scene.light[index].type == "point":
                draw.add_circle_filled(centre, 5.0, colour)
            else:
                draw.add_circle(centre, 7.0, colour, 0, 2.0)
            draw.add_text(imgui.ImVec2(x + 8, y - 8), colour, f"light[{index}]")

    # ------------------------------------------------------------------ widgets
    def _texture(self, field: str, ref: dict, data) -> None:
        """A texture slot: its picture (made once per image content), file, uv set and encoding."""
        imgui = self.imgui
        where = Path(ref["texture"]).name + (f" image {ref['image']}" if ref.get("image") is not None else "")
        encoding = "sRGB" if data.srgb else "linear"
        imgui.text(f"{field}: {where}")
        imgui.text(f"  uv set {ref.get('uv', 0)}, {encoding}, {data.size[0]} x {data.size[1]}")
        picture = self._thumbnails.get(data.key)
        if picture is None:
            codes = thumbnail(data.codes)
            picture = self.renderer.ctx.texture((codes.shape[1], codes.shape[0]), 4, codes.tobytes())
            self.renderer.register_texture(picture)
            self._thumbnails[data.key] = picture
        imgui.image(picture.glo, imgui.ImVec2(*picture.size))

    def _choice(self, label: str, current: str, options: tuple[str, ...], event) -> None:
        items = list(options) if current in options else [current, *options]
        changed, k = self.imgui.combo(label, items.index(current), items)
        if changed and items[k] != current:
            self._events.append(event(items[k]))

    def _field(self, key: str, field: str, value, event) -> None:
        """One editable parameter: a number, a 3-vector (a colour for power and albedo fields), an RGBA colour
        (glTF's base colour), a flag, a list of 3-vectors (a quad's corners); anything else is shown as text."""
        imgui = self.imgui
        shown = self._pending.get(key, value)
        label = f"{field}##{key}"
        if isinstance(value, bool):
            changed, new = imgui.checkbox(label, shown)
            if changed:
                self._events.append(event(field, new))
            return
        if isinstance(value, int):
            _, new = imgui.drag_int(label, int(shown), 1.0)
        elif isinstance(value, float):
            _, new = imgui.drag_float(label, float(shown), max(abs(value), 0.01) * 0.005, 0.0, 0.0, "%.4g")
        elif field in COLOURS_ALPHA and isinstance(value, list | tuple) and len(value) == 4:
            _, new = imgui.color_edit4(label, list(shown), imgui.ColorEditFlags_.float)
        elif _is_vec3(value):
            if field in COLOURS:
                _, new = imgui.color_edit3(label, list(shown), imgui.ColorEditFlags_.hdr | imgui.ColorEditFlags_.float)
            else:
                _, new = imgui.drag_float3(label, list(shown), 0.01)
        elif isinstance(value, list | tuple) and value and all(_is_vec3(v) for v in value):
            new = [list(v) for v in shown]
            for k in range(len(new)):
                _, new[k] = imgui.drag_float3(f"{field}[{k}]##{key}", new[k], 0.01)
                self._commit(key, field, new, value, event)
            return
        else:
            imgui.text(f"{field}: {value}")
            return
        self._commit(key, field, new, value, event)

    def _commit(self, key: str, field: str, new, value, event) -> None:
        """Keep a dragged value on screen; send it when the widget is released."""
        if self.imgui.is_item_active():
            self._pending[key] = new
        if self.imgui.is_item_deactivated_after_edit():
            self._pending.pop(key, None)
            self._events.append(event(field, _plain(new)))
        elif not self.imgui.is_item_active() and key in self._pending and not _differs(new, value):
            self._pending.pop(key, None)


def _is_vec3(value) -> bool:
    return isinstance(value, list | tuple) and len(value) == 3 and all(isinstance(v, int | float) for v in value)


def _plain(value):
    """Widget values as scene values (lists of floats; integers stay integers)."""
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value if isinstance(value, int) else float(value)


def _differs(a, b) -> bool:
    return not np.allclose(np.asarray(_plain(a), float), np.asarray(_plain(b), float))
