"""Rendering from any thread: each thread draws in its own GL context; a Renderer stays with its thread."""

from __future__ import annotations

import gc
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import reflets
from reflets.errors import ContextThreadError
from reflets.gpu import context as gl_context
from reflets.gpu import get_context

SCENES = ["01_plane_point.toml", "03_shapes.toml", "06_materials.toml", "20_arealight_phong.toml"]
SIZE = (96, 72)


def _scene(name: str):
    from importlib import resources

    return reflets.load_scene(resources.files("reflets") / "data" / "scenes" / name)


def _in_thread(fn, name="worker"):
    result = {}

    def run():
        try:
            result["value"] = fn()
        except Exception as exc:  # handed back to the test thread
            result["error"] = exc

    thread = threading.Thread(target=run, name=name)
    thread.start()
    thread.join()
    return result


def test_render_in_a_worker_thread_after_the_main_thread(ctx):
    scene = _scene(SCENES[0])
    here = reflets.render(scene, size=SIZE)
    there = _in_thread(lambda: reflets.render(scene, size=SIZE))
    assert "error" not in there, there.get("error")
    np.testing.assert_array_equal(there["value"], here)


@pytest.mark.slow
def test_four_concurrent_threads_give_the_sequential_images(ctx):
    scenes = [_scene(name) for name in SCENES]
    sequential = [reflets.render(scene, size=SIZE) for scene in scenes]
    with ThreadPoolExecutor(max_workers=4) as pool:
        concurrent = list(pool.map(lambda scene: reflets.render(scene, size=SIZE), scenes * 2))
    for k, image in enumerate(concurrent):
        np.testing.assert_array_equal(image, sequential[k % len(scenes)], err_msg=SCENES[k % len(scenes)])


def test_a_renderer_used_from_another_thread_names_its_owner(ctx):
    with reflets.Renderer(_scene(SCENES[0]), size=(32, 24)) as renderer:
        renderer.render()
        for call in (renderer.render, lambda: renderer.set_camera(fov_y=30), renderer.release):
            outcome = _in_thread(call, name="pool-7")
            error = outcome.get("error")
            assert isinstance(error, ContextThreadError), outcome
            assert "thread 'MainThread'" in str(error) and "'pool-7'" in str(error)
        assert renderer.render().shape == (24, 32, 3)  # still usable where it belongs


def test_a_renderer_made_in_a_thread_that_ended_says_so(ctx):
    made = _in_thread(lambda: reflets.Renderer(_scene(SCENES[0]), size=(32, 24)))
    gc.collect()
    with pytest.raises(ContextThreadError, match="whose thread has ended"):
        made["value"].render()


def test_a_thread_context_and_its_caches_go_with_the_thread(ctx):
    before = set(gl_context._owners)
    worker_ctx = _in_thread(lambda: (reflets.render(_scene(SCENES[0]), size=(32, 24)), id(get_context()))[1])
    gc.collect()
    assert worker_ctx["value"] != id(ctx)
    assert set(gl_context._owners) == before
    assert worker_ctx["value"] not in gl_context._stores
