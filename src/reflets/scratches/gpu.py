"""The scratch BRDF precomputation as a compute shader (``shaders/scratch_trace.comp``), float32.

Same algorithm and ray distribution as :func:`reflets.scratches.tracer2d.trace_table` (different random
numbers: PCG hashes of (ray, column, seed)), so both backends agree within Monte Carlo noise. Runs on a real
GPU (interactive) and on llvmpipe. Fresnel weights are accumulated as fixed-point integers (core GLSL 4.30 has
no float atomics): weight × S with S = min(2²⁴, ⌊(2³² − 1)/(2N)⌋) and stochastic rounding, which is unbiased
and cannot overflow since a column holds at most N rays of weight ≤ 2 (cos ψ / c̄_j × Fresnel ≤ 1).
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import ArgumentError
from ..gpu import ProgramSpec, get_context, get_program, set_uniforms
from ..gpu.programs import shared_constants
from .profiles import Profile
from .tracer2d import FRESNEL_MODELS, MAX_BOUNCES, PROFILE_KINDS, THETAS, FresnelSpec, Tallies

SCRATCH_PROGRAM = ProgramSpec(
    "scratch_trace",
    compute="reflets/scratches/shaders/scratch_trace.comp",
    flags=frozenset({"M_BINS", "LOCAL_SIZE", "PROFILE_KIND", "FRESNEL_MODEL", "MAX_BOUNCES"}),
    constants=shared_constants(FRESNEL=FRESNEL_MODELS, PROFILE=PROFILE_KINDS),
)
LOCAL_SIZE = 64
SLOTS = 7
#: last run's wall time in milliseconds (dispatch + finish + readback), for benchmarks
last_timing_ms: dict[str, float] = {}


def rays_per_invocation(profile: Profile) -> int:
    """Rays one invocation traces: llvmpipe ends an invocation after 65,535 loop iterations in all (nested loops
    included) without an error, and a ray costs up to a few cell steps per cell of the profile; a real GPU also
    prefers many short invocations."""
    return int(max(1, min(64, 4096 // (4 * (profile.cells + 2)))))


def _rgb(values) -> tuple[float, float, float]:
    v = tuple(float(x) for x in values)
    return v * 3 if len(v) == 1 else v


def trace_table_gpu(
    profile: Profile,
    *,
    size: int = 256,
    rays: int = 10000,
    fresnel: FresnelSpec | None = None,
    seed: int = 0,
    slices: int | None = None,
    max_bounces: int = MAX_BOUNCES,
    ctx=None,
) -> Tallies:
    """Trace a table on the GPU; returns the same :class:`Tallies` as the NumPy tracer (no squared sums)."""
    fresnel = fresnel or FresnelSpec()
    M, N = int(size), int(rays)
    if M < 2 or N < 1:
        raise ArgumentError(f"size must be ≥ 2 and rays ≥ 1, got {M}, {N}", field="size")
    if M > 1024:
        raise ArgumentError(f"the GPU tracer supports size ≤ 1024 (shared-memory histogram), got {M}", field="size")
    ctx = ctx or get_context()
    if slices is None:
        slices = -(-N // (LOCAL_SIZE * rays_per_invocation(profile)))
    program = get_program(
        ctx,
        SCRATCH_PROGRAM,
        M_BINS=M,
        LOCAL_SIZE=LOCAL_SIZE,
        PROFILE_KIND=PROFILE_KINDS["quartic" if profile.kind == "quartic" else "polyline"],
        FRESNEL_MODEL=fresnel.model_id,
        MAX_BOUNCES=int(max_bounces),
    )
    scale = float(min(2**24, (2**32 - 1) // (2 * N)))
    knots = np.stack([profile.x, profile.h], axis=1).astype(np.float32)
    knot_buf = ctx.buffer(knots.tobytes())
    tally_buf = ctx.buffer(reserve=(SLOTS * M * M + 2 * M) * 4)
    try:
        tally_buf.clear()
        knot_buf.bind_to_storage_buffer(0)
        tally_buf.bind_to_storage_buffer(1)
        set_uniforms(
            program,
            {
                "u_cells": profile.cells,
                "u_lid": float(profile.lid),
                "u_bottom": float(profile.bottom),
                "u_depth": float(profile.depth),
                "u_rays": N,
                "u_slices": int(slices),
                "u_seed": int(seed) & 0xFFFFFFFF,
                "u_eta": _rgb(fresnel.eta),
                "u_k": _rgb(fresnel.k),
                "u_cos_theta": (float(np.cos(THETAS[0])), float(np.cos(THETAS[1]))),
                "u_scale": scale,
            },
        )
        ctx.finish()
        start = time.perf_counter()
        program.run(group_x=M, group_y=int(slices))
        ctx.finish()
        mid = time.perf_counter()
        raw = np.frombuffer(tally_buf.read(), dtype=np.uint32).astype(np.float64)
        last_timing_ms.update(dispatch=(mid - start) * 1e3, readback=(time.perf_counter() - mid) * 1e3)
    finally:
        knot_buf.release()
        tally_buf.release()
    done = raw[SLOTS * M * M + M :]
    if np.any(done != N):
        if slices < N:  # the driver cut some invocations short: spread the rays thinner and retry
            return trace_table_gpu(
                profile,
                size=M,
                rays=N,
                fresnel=fresnel,
                seed=seed,
                slices=min(N, 4 * slices),
                max_bounces=max_bounces,
                ctx=ctx,
            )
        raise RuntimeError(f"the GPU traced {int(done.min())} of {N} rays in some column")
    slots = raw[: SLOTS * M * M].reshape(SLOTS, M, M)
    counts = slots[0] / scale
    C = fresnel.channels
    if fresnel.model == "none":
        weights = np.broadcast_to(counts, (2, C, M, M)).copy()
    else:
        weights = np.stack([slots[1 : 1 + C], slots[4 : 4 + C]]) / scale  # (T, C, M, M)
    return Tallies(
        size=M,
        rays=N,
        thetas=THETAS,
        counts=counts,
        weights=np.moveaxis(weights, 1, -1),
        counts_sq=None,
        weights_sq=None,
        lost=raw[SLOTS * M * M : SLOTS * M * M + M],
        max_bounces=-1,  # not recorded on the GPU
    )
