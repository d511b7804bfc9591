"""Evaluate a material's GLSL twin on the GPU for arrays of directions (the NumPy/GLSL parity check)."""

from __future__ import annotations

import numpy as np

from ..gpu import ProgramSpec, get_context, get_program, set_uniforms
from .base import Material

EVAL_PROGRAM = ProgramSpec("brdf_eval", compute="reflets/brdf/glsl/eval.comp")


def eval_glsl(material: Material, wo: np.ndarray, wi: np.ndarray, ctx=None) -> np.ndarray:
    """f_r(wo, wi) computed by ``material.glsl`` in float32, shape (..., 3) like ``material.eval``."""
    ctx = ctx or get_context()
    wo, wi = np.broadcast_arrays(np.asarray(wo, dtype=np.float32), np.asarray(wi, dtype=np.float32))
    shape = wo.shape[:-1]
    count = int(np.prod(shape, dtype=np.int64))
    pad = np.zeros((count, 1), np.float32)
    program = get_program(ctx, EVAL_PROGRAM, slots={"BRDF": material.brdf_source}, **material.flags())
    buffers = [ctx.buffer(np.hstack([w.reshape(count, 3), pad]).tobytes()) for w in (wo, wi)]
    buffers.append(ctx.buffer(reserve=max(count, 1) * 16))
    try:
        for binding, buf in enumerate(buffers):
            buf.bind_to_storage_buffer(binding)
        samplers = {}
        for unit, (uniform, texture) in enumerate(material.textures(ctx).items()):
            texture.use(unit)
            samplers[uniform] = unit
        set_uniforms(program, {**material.uniforms(), **samplers, "u_count": count})
        program.run(group_x=(count + 63) // 64)
        out = np.frombuffer(buffers[2].read(), dtype=np.float32).reshape(-1, 4)[:count, :3]
    finally:
        for buf in buffers:
            buf.release()
    return out.reshape(*shape, 3).copy()
