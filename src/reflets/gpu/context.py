"""The one place that creates the OpenGL context (headless EGL through moderngl/glcontext).

``REFLETS_GL`` picks the driver:

- ``auto`` (default): whatever EGL offers first (the NVIDIA driver when installed, else Mesa);
- ``nvidia``: only NVIDIA's EGL vendor library; an error if it is missing;
- ``llvmpipe``: Mesa's software rasteriser (what CI and machines without a GPU use).

Everything GPU in reflets takes its context from :func:`get_context`, so one process holds one context — the
EGL one made here, or one a window made and handed over (:func:`use_context`, the viewer).
"""

from __future__ import annotations

import os
from functools import cache
from pathlib import Path

from ..errors import GLUnavailableError

GL_REQUIRE = 430  # compute shaders, SSBOs, std430 — used by later techniques
CHOICES = ("auto", "nvidia", "llvmpipe")

_VENDOR_DIRS = (
    "/usr/share/glvnd/egl_vendor.d",
    "/etc/glvnd/egl_vendor.d",
    "/usr/local/nvidia/share/glvnd/egl_vendor.d",
)
_INSTALL_HINT = (
    "install Mesa's EGL and llvmpipe (Debian/Ubuntu: apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1) "
    "or the NVIDIA driver, then run `reflets info`"
)


def _vendor_file(keyword: str) -> str | None:
    for folder in _VENDOR_DIRS:
        d = Path(folder)
        if d.is_dir():
            for f in sorted(d.glob("*.json")):
                if keyword in f.name.lower():
                    return str(f)
    return None


def gl_choice() -> str:
    """The driver requested through REFLETS_GL (validated)."""
    choice = os.environ.get("REFLETS_GL", "auto").strip().lower() or "auto"
    if choice not in CHOICES:
        raise GLUnavailableError(f"unknown value '{choice}'; allowed: {', '.join(CHOICES)}", field="REFLETS_GL")
    return choice


def _prepare_environment(choice: str) -> None:
    """Point glvnd at one vendor before libEGL is first loaded (it reads these variables once)."""
    if choice == "llvmpipe":
        mesa = _vendor_file("mesa")
        if mesa:
            os.environ["__EGL_VENDOR_LIBRARY_FILENAMES"] = mesa
        os.environ["LIBGL_ALWAYS_SOFTWARE"] = "1"
        os.environ["GALLIUM_DRIVER"] = "llvmpipe"
    elif choice == "nvidia":
        nvidia = _vendor_file("nvidia")
        if nvidia is None:
            raise GLUnavailableError(
                "REFLETS_GL=nvidia but no NVIDIA EGL vendor file was found in "
                f"{', '.join(_VENDOR_DIRS)}; install the NVIDIA driver or use REFLETS_GL=llvmpipe"
            )
        os.environ["__EGL_VENDOR_LIBRARY_FILENAMES"] = nvidia


_window_context = None


def use_context(ctx) -> None:
    """Make ``ctx`` — a context something else created and made current, e.g. a viewer's window — the process's
    context: every renderer created afterwards draws in it (programs are cached per context). The headless EGL
    context, if one was made, stays but is no longer handed out. ``None`` goes back to it."""
    global _window_context
    if ctx is not None and ctx.version_code < GL_REQUIRE:
        raise GLUnavailableError(
            f"the context offers OpenGL {ctx.version_code / 100:.1f}; reflets needs {GL_REQUIRE / 100:.1f}"
        )
    _window_context = ctx


def get_context():
    """The process's moderngl context: the one given to :func:`use_context`, else the standalone EGL context
    (created on first use)."""
    return _window_context if _window_context is not None else _egl_context()


@cache
def _egl_context():
    choice = gl_choice()
    _prepare_environment(choice)
    import moderngl

    try:
        ctx = moderngl.create_context(standalone=True, backend="egl", require=GL_REQUIRE)
    except Exception as exc:  # glcontext raises plain Exceptions with the EGL reason
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise GLUnavailableError(
            f"cannot create an OpenGL {GL_REQUIRE // 100}.{GL_REQUIRE % 100 // 10} context through EGL "
            f"(REFLETS_GL={choice}): {reason}; {_INSTALL_HINT}"
        ) from exc
    renderer = ctx.info.get("GL_RENDERER", "")
    if choice == "nvidia" and "nvidia" not in renderer.lower():
        raise GLUnavailableError(f"REFLETS_GL=nvidia but the context runs on '{renderer}'")
    if choice == "llvmpipe" and "llvmpipe" not in renderer.lower():
        raise GLUnavailableError(f"REFLETS_GL=llvmpipe but the context runs on '{renderer}'")
    return ctx


def is_software(ctx=None) -> bool:
    """True on Mesa's software rasterisers, where GPU timer queries are meaningless."""
    ctx = ctx or get_context()
    renderer = ctx.info.get("GL_RENDERER", "").lower()
    return any(k in renderer for k in ("llvmpipe", "softpipe", "swrast", "lavapipe"))


def gl_info() -> dict[str, str]:
    """Vendor, renderer and version strings of the context, for `reflets info` and benchmark reports."""
    ctx = get_context()
    return {
        "vendor": ctx.info.get("GL_VENDOR", "?"),
        "renderer": ctx.info.get("GL_RENDERER", "?"),
        "version": ctx.info.get("GL_VERSION", "?"),
        "glsl": ctx.info.get("GL_SHADING_LANGUAGE_VERSION", "?"),
        "driver_choice": gl_choice(),
    }
