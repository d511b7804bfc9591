"""The one place that creates the OpenGL context (headless EGL through moderngl/glcontext).

``REFLETS_GL`` picks the driver:

- ``auto`` (default): whatever EGL offers first (the NVIDIA driver when installed, else Mesa);
- ``nvidia``: only NVIDIA's EGL vendor library; an error if it is missing;
- ``llvmpipe``: Mesa's software rasteriser (what CI and machines without a GPU use).

Everything GPU in reflets takes its context from :func:`get_context`. A GL context is current on one thread at a
time, so each thread that renders gets its own headless EGL context, made on its first call and released when
the thread ends; a window's context (:func:`use_context`, the viewer) serves only the thread that handed it
over. Four threads rendering at once therefore draw in four contexts, with nothing shared but NumPy data and the
content caches (which lock); objects tied to one context (compiled programs, textures kept across renders) live
in that context's :func:`context_store`, dropped with it.
"""

from __future__ import annotations

import contextlib
import os
import threading
import weakref
from pathlib import Path

from ..errors import ContextThreadError, GLUnavailableError

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


_window = None  # (context, thread) a window handed over
_local = threading.local()  # this thread's EGL context, in a holder whose finaliser releases it
_lock = threading.RLock()
_stores: dict[int, dict[str, object]] = {}  # id(context) → named caches of that context's GL objects
_owners: dict[int, threading.Thread] = {}  # id(EGL context) → the thread it is current on
_software_turn = threading.RLock()  # what renders on a software rasteriser take turns on (``turn``)
_environment_ready = False


def use_context(ctx) -> None:
    """Make ``ctx`` — a context something else created and made current on this thread, e.g. a viewer's window —
    this thread's context: every renderer it creates afterwards draws in it (programs are cached per context).
    Other threads keep their own EGL contexts. ``None`` goes back to the EGL context."""
    global _window
    if ctx is not None and ctx.version_code < GL_REQUIRE:
        raise GLUnavailableError(
            f"the context offers OpenGL {ctx.version_code / 100:.1f}; reflets needs {GL_REQUIRE / 100:.1f}"
        )
    if _window is not None and ctx is None:
        forget_context(_window[0])
    _window = None if ctx is None else (ctx, threading.current_thread())


def get_context():
    """This thread's moderngl context: the one it gave to :func:`use_context`, else its own EGL context (made on
    first use, released when the thread ends)."""
    window = _window
    if window is not None and window[1] is threading.current_thread():
        return window[0]
    holder = getattr(_local, "holder", None)
    if holder is None:
        holder = _Holder(_egl_context())
        _local.holder = holder
    return holder.ctx


def turn(ctx):
    """What a render in ``ctx`` holds while it draws: on a software rasteriser (llvmpipe already spreads one
    render over every core), a process-wide lock, so that threads take turns — `reflets bench threads` on 2 cores
    (benchmarks/results/threads.md): 4 threads taking turns 1.06× the throughput of one thread, rendering at once
    0.82×; on a GPU, nothing (each thread's context runs at once; not measured here: no GPU)."""
    return _software_turn if is_software(ctx) else contextlib.nullcontext()


def context_store(ctx, name: str, factory=dict):
    """A container (``factory()``) for caching GL objects of ``ctx`` (e.g. ``"programs"``): each context has its
    own, so an object is never used, or released, in a context that does not own it; dropped with the context."""
    with _lock:
        stores = _stores.setdefault(id(ctx), {})
        if name not in stores:
            stores[name] = factory()
        return stores[name]


def forget_context(ctx) -> None:
    """Drop the caches of a context that is about to go (its GL objects go with it)."""
    with _lock:
        _stores.pop(id(ctx), None)


def owner_thread(ctx) -> threading.Thread | None:
    """The thread ``ctx`` is current on (None once that thread has ended)."""
    window = _window
    if window is not None and window[0] is ctx:
        return window[1]
    with _lock:
        return _owners.get(id(ctx))


def check_thread(ctx, what: str) -> None:
    """Raise a :class:`ContextThreadError` unless ``ctx`` can be driven from the calling thread."""
    owner = owner_thread(ctx)
    if owner is threading.current_thread():
        return
    here = threading.current_thread().name
    if owner is None:
        raise ContextThreadError(
            f"{what} drew in a GL context whose thread has ended; make a new one in thread '{here}'", field="thread"
        )
    raise ContextThreadError(
        f"{what} belongs to thread '{owner.name}' (its GL context is current there) and cannot be used from thread "
        f"'{here}'; make one per thread, or call reflets.render(), which takes the calling thread's context",
        field="thread",
    )


class _Holder:
    """Owns one thread's EGL context; the thread's local storage holds it, so it goes when the thread ends."""

    def __init__(self, ctx):
        self.ctx = ctx
        with _lock:
            _owners[id(ctx)] = threading.current_thread()
        weakref.finalize(self, _release, ctx)


def _release(ctx) -> None:
    with _lock:
        _owners.pop(id(ctx), None)
        forget_context(ctx)
    with contextlib.suppress(Exception):  # the context went with its thread already
        ctx.release()


def _egl_context():
    global _environment_ready
    choice = gl_choice()
    with _lock:
        if not _environment_ready:
            _prepare_environment(choice)
            _environment_ready = True
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
