// Provides brdf_eval(wo, wi) of a scratched material over a glTF base (twin of reflets/scratches/material.py):
// the finite part s_base_weight · ρ_b, and base_brdf_eval, the base itself (the scratches technique shades the
// scratch lobes and weights the base per pixel); the base's textures through gltf.glsl's material_surface.
#define brdf_eval base_brdf_eval
#include "reflets/brdf/glsl/gltf.glsl"
#undef brdf_eval
#include "reflets/scratches/shaders/scratched_finite.glsl"
