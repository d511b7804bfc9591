// The per-fragment hooks of a material with MATERIAL_SURFACE (forward.frag, arealight.frag, reflected.frag,
// scratches.frag) that a material whose only varying parameters are colours does not need: no normal map to
// antialias, no coverage, emission or occlusion. glTF's material (gltf.glsl) defines its own.
void material_antialias(vec3 n) {}
bool material_covered() { return true; }
vec3 material_emission() { return vec3(0.0); }
float material_alpha() { return 1.0; }
float material_occlusion() { return 1.0; }
