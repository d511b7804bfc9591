// Provides area_light_contribution() for the "brute" method (eq 2.8 of the area-light document): a fixed
// a_grid × a_grid midpoint grid per parallelogram light, the fan rule with a_grid² sub-triangles per fan
// triangle for other convex polygons. V1 (x on the emitting side) skips the whole light.
#include "reflets/arealights/shaders/grid.glsl"

uniform int a_grid;

vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
    AreaLight L = area_light(i);
    if (!area_light_faces(L, x)) return vec3(0.0);
    if (L.parallelogram) return grid_parallelogram(L, x, frame, wo, vec2(0.0), vec2(1.0), a_grid, a_grid, vec3(0.0));
    return grid_fan(i, L, x, frame, wo, a_grid, vec3(0.0));
}
