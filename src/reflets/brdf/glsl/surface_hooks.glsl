// The per-fragment hooks of a material with MATERIAL_SURFACE (forward.frag, arealight.frag, reflected.frag,
// scratches.frag) that a library material with maps (reflets/brdf/maps.py) does not define itself: no normal-map
// antialiasing, no coverage, and — unless its twin defines MATERIAL_EMISSION / MATERIAL_OCCLUSION — no emission
// or occlusion. glTF's material (gltf.glsl) defines its own.
void material_antialias(vec3 n) {}
bool material_covered() { return true; }
float material_alpha() { return 1.0; }
#ifndef MATERIAL_EMISSION
vec3 material_emission() { return vec3(0.0); }
#endif
#ifndef MATERIAL_OCCLUSION
float material_occlusion() { return 1.0; }
#endif
