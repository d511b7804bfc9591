"""docs/techniques/area-lights.md is generated from the method modules' docstrings (one source of truth):
``python -m reflets.arealights.docs > docs/techniques/area-lights.md``; a test keeps it current."""

from __future__ import annotations

import importlib
import inspect

METHODS = ("brute", "adaptive", "biased", "mc", "analytic", "ltc")

HEADER = """# Area lights with arbitrary BRDFs

Direct lighting from nearby planar area lights (quads and convex polygons, one- or two-sided, any number),
over every BRDF of the library, on the GPU — the methods of the area-light document (Meunier 2007:
`brute`, `adaptive`, `biased`, `mc`), the exact diffuse formula (`analytic`) and Linearly Transformed
Cosines (`ltc`, Heitz et al. 2016) with our own fitting tool for every BRDF.

```sh
reflets render scene.toml --method ltc -o out.exr
reflets render scene.toml --method brute --param grid=16
reflets render scene.toml --method mc --param strategy=mis --spp 256
reflets fit-ltc --brdf ggx -o ggx.npz
reflets bench arealights          # benchmarks/results/arealights.{json,md,png}
```

**Unoccluded, then shadowed.** As in the document, each method computes a light's unoccluded integral: a light
contributes wherever its emitting side faces the shaded point, clipped to the point's horizon. Shadows cast by
other objects multiply it by the soft-shadow ratio (docs/techniques/shadows.md), on by default. The accuracy
figures on this page are measured on unoccluded scenes (a plane under the light) against the unoccluded
reference, `reflets.reference(scene, visibility=False)` / `reflets reference --visibility off`; set
`shadows = false` on a light to get the document's setting in any scene.
Point, directional and environment lights in the same scene are shaded as by `forward`.

## Errata of the document, fixed here

| where | the document | here |
|---|---|---|
| (2.12) Phong predictor inverse | exponent 0.4761 and −0.0017 | 1/2.0990 and + 0.0017 (the inverse of (2.11)) |
| (2.13) Blinn predictor | exponent 2.4589 (Δ ≤ 0.05 almost always) | 1/2.4589, by measurement (see `adaptive`) |
| (2.14–2.20) nearest point | divides by the edge length | divides by the squared edge length (any light size) |
| (2.35) two-region estimator | weights B/N, C/N | 2B/N, 2C/N |
| Algorithm 1, rejection sampling | acceptance test reversed | accept when u ≤ p/(M q) |
| (2.23) cone half-angle fit | used beyond e ≈ 300 | exact solution of (2.22) by default, the fit as an option |

## Accuracy and speed

`reflets bench arealights` reproduces the document's experiment (a plane and one unit square light,
800×600, Phong ρ_d = 0, ρ_s = 1, e ∈ {150, 200, 500}) and extends it with GGX α ∈ {0.1, 0.3, 0.6} and
Lambert: every method at several settings, median frame time, light samples per pixel, relative MSE and FLIP
against the unoccluded reference, the largest error against a converged brute 64² grid, and an error-vs-time
plot; then `ltc` (both bases) and brute 8² on the other BRDFs with a shipped table (Beckmann, normalised Phong
and Blinn-Phong, Ward at α = 0.1 and 0.3). Results, with the machine they were measured on:
[benchmarks/results/arealights.md](../../benchmarks/results/arealights.md).

**Measured ordering** (full run, committed; 800×600 on llvmpipe, 2 cores, shared with other work while it
ran, so single timings are noisy — compare within a row of the table, not across runs). On the document's
scene (Phong e = 500): `ltc` 50.9 ms (relMSE 3.6e-6) < `biased` t = 0.99, 4² 123 ms (4.7e-6) < `adaptive`
233 ms (170 samples/px, 4.4e-6) < `brute` 20² 448 ms (400 samples/px, 3.7e-6) < `mc` (MIS) 64 spp 620 ms
(4.8e-5). The document found the same order of its four methods on its 2007 GPU — biased 220 fps, adaptive
33, brute 12, Monte Carlo 3 — with a wider spread: on a SIMD software rasteriser the per-pixel grid sizes of
`adaptive` and the cone bounds of `biased` cost more relative to a fixed loop than on the document's GPU.
There the sampling methods that come within 10 % of `ltc`'s relative MSE (biased 8², adaptive with dither, brute
20² and 32²) take 129–1,043 ms: 2.5–20× its time.

**Beyond the document: `ltc` keeps the highlights' edges** (issue 18). `ltc` used to transform the clamped
cosine (now `base = "cosine"`, beside it in the committed run), whose power-law tail cannot follow a
Phong lobe — the largest error on the document's highlights was 11.35 / 10.72 / 9.89 % of the peak for
e = 150 / 200 / 500, FLIP 0.442 / 0.459 / 0.422 against 0.040 / 0.039 / 0.030 for brute 8². The default base
is now a per-cell mixture with cos³¹ whose tail is cut off outside its support: 0.51 / 0.61 / 0.70 % of the
peak, FLIP 0.064 / 0.054 / 0.029, relative MSE 3.7e-5 / 2.2e-5 / 3.6e-6 (from 5.2e-4 / 3.5e-4 / 6.4e-5) —
more accurate than brute 8² (1.90 / 2.58 / 8.96 %) by every measure but FLIP — the rows of
benchmarks/results/arealights.md (`python tools/bench_arealights_part.py OUT` makes just these rows in minutes,
the whole suite takes over half an hour); details and the other BRDFs in `ltc` below.

**`ltc` cost** (`reflets bench ltc-cost`: interleaved rounds in one run, GGX α = 0.3, one unit light,
800×600, benchmarks/results/ltc-cost.md). On llvmpipe a frame's time is bimodal — two threads when the host
gives the second core, one when it does not — so medians move with the host's load (a session that ran its
other work beside the benchmark measured 12.5 ms) while the 10th percentile (two-thread frames) and the
ratios stay put. Committed run: `ltc` **4.7 ms** (10th percentile; median 7.9 ms) against 3.5 ms (median
5.5 ms) for the same plane lit by one point light: **1.36×** (medians 1.42×). three.js r187's RectAreaLight
draws this scene in about 5.5 ms on this rasteriser, 1.8× its 3.0 ms point-light frame: our point-light
frame is close to its (3.5 vs 3.0 ms two-thread) and our `ltc` frame is faster (4.7 vs 5.5 ms); three.js was not
run beside ours, so the absolute comparison crosses runs. Where the time goes (10th percentiles, one stage
dropped at a time): float32 HDR target and shading frame 1.4 ms, table setup with the two fetches 1.2 ms, the
polygon integral 2.1 ms of which horizon clipping 1.0 ms. `horizon = "sphere"` replaces the edge-by-edge
clipping with what production engines do (the cap with the polygon's vector form factor, clipped in closed
form — exact where nothing crosses the horizon): 3.8 ms, relative MSE 2.2e-3 → 7.5e-3 at GGX α = 0.1 and
5.2e-4 → 8.0e-4 at Phong e = 150 (unchanged at GGX α = 0.3); `exact` stays the default. The speed work of
this issue: light counts and BRDF switches became compile-time (a loop over an absent light type still costs
on llvmpipe), which took `ltc` from 47–50 ms to 12 ms and the point-light frame from 35 ms to 11 ms in the
loaded session's medians.

The tests (tests/arealights/) check: `analytic` against the exact formula (max relative error < 1e-3);
`brute` converging at the midpoint order; `mc` unbiased over 32 seeds and its error falling as 1/√spp;
`biased` within −5 % … 0 % energy at t = 0.99; `adaptive` more accurate than a brute force of the same
cost (and, with `safety_phong = 0.5`, as accurate as 20×20 with fewer samples — with the document's default
safety factors it is *not*, see below); `ltc` within 1 % / 3 % relative MSE of the reference, and the
document's un-normalised Phong highlights (e = 150 / 500) within 2 % of the peak and FLIP 0.1 / 0.06 of a
converged brute force.

**llvmpipe limit.** Mesa's software rasteriser stops a shader loop after 65,535 iterations per pixel (all
lights together) and silently returns a partial sum; `brute` caps `grid` at 128 and `forward`'s
`area_samples` at 64 for that reason. A real GPU has no such limit.

## Masked quad lights

The document shapes lights with a mask texture; here a quad light's `mask` (docs/scene-format.md) does that,
and exact polygons (`type = "polygon"`) remain the better way to an outline without aliasing. The mask's
nearest texel multiplies the radiance, so every renderer integrates the same piecewise-constant emitter.
`forward` multiplies its midpoint samples on the CPU; `brute`, `adaptive` and `biased` fetch the texel at
each grid sample (masks in one float buffer, fetched only when a scene has one, flag `LIGHT_MASKS`) and skip
the samples where it is 0 (`output="samples"` counts the others). `biased`'s exact diffuse term assumes
constant radiance, so on a masked light its diffuse part goes on a `grid`² grid over the whole light (the
whole BRDF when the material has no lobe), and the lobe on the cone's box as usual. `analytic`, `ltc` and
`mc` refuse a masked light with an error; the NumPy reference and the Mitsuba bridge honour masks.

A grid sees a mask's edge with an O(1/n) error — the document's aliasing — unless n is a multiple of the
mask's resolution, when every texel gets the same samples (measured on a half mask, 64×48: `brute` 32²
within 2.3·10⁻⁴ of the exact half light, 8²: 3.6·10⁻³; `adaptive` on Phong e = 50 1.2·10⁻² relative MSE
against `brute` 32², unmasked 8·10⁻⁵, where its odd n put the middle sample column in the dark half;
`biased` 16² 1.1·10⁻⁴, its cone's box straddling the edge). `tests/arealights/test_light_mask.py` checks
the half mask against the half light, that a mask of ones gives the unmasked image bit for bit, and the
methods against `brute`.
"""


def markdown() -> str:
    parts = [HEADER.rstrip("\n")]
    for name in METHODS:
        module = importlib.import_module(f"reflets.arealights.{name}")
        parts += ["", f"## `{name}`", "", inspect.cleandoc(module.__doc__ or "")]
    return "\n".join(parts) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
