// Provides PI, INV_PI, TWO_PI and small frame helpers shared by every reflets shader stage.
const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;
const float TWO_PI = 6.28318530717958647692;

// Orthonormal frame (t, b, n) from a normal and a tangent hint; b = sign * cross(n, t) (glTF convention).
mat3 shading_frame(vec3 n, vec4 tangent) {
    vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
    float len = length(t);
    if (len < 1e-6) {
        // Duff et al. 2017 branchless ONB when the tangent is missing or parallel to n.
        float s = n.z >= 0.0 ? 1.0 : -1.0;
        float a = -1.0 / (s + n.z);
        t = vec3(1.0 + s * n.x * n.x * a, s * n.x * n.y * a, -s * n.x);
    } else {
        t /= len;
    }
    vec3 b = (tangent.w < 0.0 ? -1.0 : 1.0) * cross(n, t);
    return mat3(t, b, n);  // columns: local → world; transpose(frame) * w gives local coordinates
}

// The frame turned by a tangent-space normal map: ``local`` is the mapped normal in ``frame`` (its xy already scaled);
// the tangent re-orthogonalised against it, the bitangent's handedness kept (brdf/base.py's perturbed_frame).
mat3 normal_mapped_frame(mat3 frame, vec3 local) {
    float handedness = dot(cross(frame[2], frame[0]), frame[1]) < 0.0 ? -1.0 : 1.0;
    return shading_frame(normalize(frame * local), vec4(frame[0], handedness));
}

#ifdef IBL_NODES
// The two nodes of a split-sum albedo curve (IBL_NODES values at mu = (k + 1/2) / IBL_NODES) around mu, and the
// weight of the second: every reader of such a curve (lights.glsl, a mapped material's twin: brdf/maps.py) uses it.
void ibl_nodes(float mu, out int k0, out int k1, out float weight) {
    float node = clamp(mu, 0.0, 1.0) * float(IBL_NODES) - 0.5;
    k0 = clamp(int(floor(node)), 0, IBL_NODES - 1);
    k1 = min(k0 + 1, IBL_NODES - 1);
    weight = clamp(node - float(k0), 0.0, 1.0);
}
#endif

// Equirectangular lookup coordinates, Mitsuba 3 envmap convention (row 0 = up, +y is up).
vec2 equirect_uv(vec3 d) {
    float u = atan(d.x, -d.z) / TWO_PI;
    return vec2(u - floor(u), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

// Random numbers: PCG hash (Jarzynski & Olano 2020) seeded per pixel, frame and seed; same inputs, same numbers.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
uint rng_seed(uvec2 pixel, uint frame, uint seed) {
    return pcg_hash(pixel.x + pcg_hash(pixel.y + pcg_hash(frame + pcg_hash(seed))));
}
float rng_next(inout uint state) {
    state = pcg_hash(state);
    return float(state >> 8u) * (1.0 / 16777216.0);  // 24 bits: uniform in [0, 1)
}
