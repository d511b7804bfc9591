// Provides area_light_contribution() for the "analytic" method: the exact irradiance of the polygon (Lambert's
// formula with horizon clipping) times the material's Lambertian albedo / π. Specular lobes are not included.
vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
    AreaLight L = area_light(i);
    return u_lobe_diffuse * INV_PI * L.radiance * polygon_irradiance(i, x, frame);
}
