// Provides brdf_eval(wo, wi) = s_base_weight · base_brdf_eval(wo, wi): the finite part of a scratched material,
// the base weighted by its mean uncovered share (the scratch lobes are singular on the Kajiya–Kay cone).
uniform float s_base_weight;

vec3 brdf_eval(vec3 wo, vec3 wi) { return s_base_weight * base_brdf_eval(wo, wi); }
