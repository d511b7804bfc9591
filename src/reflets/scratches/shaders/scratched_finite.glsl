// Provides brdf_eval(wo, wi) = s_base_weight · base_brdf_eval(wo, wi): the finite part of a scratched material,
// the base weighted by its mean uncovered share (the scratch lobes are singular on the Kajiya–Kay cone), and the
// finite part's split sum where the base gives its own per fragment (a textured base: base_material_ibl, its clear
// coat's base_material_coat_ibl) — the scratches pass reads the base's, weighting it per pixel itself.
uniform float s_base_weight;

vec3 brdf_eval(vec3 wo, vec3 wi) { return s_base_weight * base_brdf_eval(wo, wi); }

#ifdef MATERIAL_IBL
void material_ibl(float mu, out vec3 diffuse_albedo, out vec3 specular_albedo, out float alpha) {
    base_material_ibl(mu, diffuse_albedo, specular_albedo, alpha);
    diffuse_albedo *= s_base_weight;
    specular_albedo *= s_base_weight;
}
#endif
#ifdef MATERIAL_COAT
void material_coat_ibl(mat3 frame, vec3 v, out float weight, out vec3 normal, out float alpha, out float albedo) {
    base_material_coat_ibl(frame, v, weight, normal, alpha, albedo);
    albedo *= s_base_weight;  // (1 − w) L_base + w a L_coat, every term × the share
}
#endif
