// Provides the material summary the area-light methods steer by (set per draw by arealights/base.py):
// a Lambertian albedo, and the main specular lobe as a Phong / Blinn-Phong lobe of a given exponent.
uniform vec3 u_lobe_diffuse;   // Lambertian albedo ρ_d (exact for the analytic method)
uniform int u_lobe_kind;       // 0: diffuse only, 1: Phong lobe around the mirror direction, 2: Blinn-Phong lobe
uniform float u_lobe_exponent; // the lobe's (equivalent) exponent e

vec3 mirror_direction(vec3 wo) { return vec3(-wo.x, -wo.y, wo.z); }  // local frame, z = normal
