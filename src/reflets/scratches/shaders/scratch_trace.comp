// Provides the scratch BRDF precomputation on the GPU: the 2D profile ray tracer with Fresnel at every bounce
// (twin of reflets/scratches/tracer2d.py, float32). llvmpipe stops a loop after 65,535 iterations in total per
// invocation (nested loops included), silently: the host keeps the rays per invocation small and checks the
// traced-ray count of every column. One workgroup per (φ_in column, slice); each invocation
// traces rays r = slice·LOCAL_SIZE + local, + LOCAL_SIZE·slices, … < u_rays, tallies them in shared memory,
// and the workgroup adds its histogram to the global one with integer atomics.
// Flags: M_BINS (table size), LOCAL_SIZE, PROFILE_KIND (PROFILE_POLYLINE: exact segment hits, PROFILE_QUARTIC: bisection),
// FRESNEL_MODEL (FRESNEL_NONE, _SCHLICK, _DIELECTRIC exact, _LAZANYI, _CONDUCTOR exact; codes from tracer2d.py), MAX_BOUNCES.
// Output layout (uint): slot s ∈ {0 count, 1..3 RGB weights θ0, 4..6 RGB weights θ1} at [s][φ_out][φ_in],
// then the lost-ray count of each column at 7·M², the traced-ray count at 7·M² + M. Every tally is fixed point (× u_scale, stochastic rounding)
// and carries the ray weight cos ψ / c̄_j ≤ 2 (ψ = jittered φ_in, c̄_j = mean of cos over the bin).
#include "reflets/brdf/glsl/fresnel.glsl"

layout(local_size_x = LOCAL_SIZE) in;
layout(std430, binding = 0) readonly buffer Knots { vec2 knots[]; };  // (x_k, h_k), k = 0..u_cells
layout(std430, binding = 1) buffer Tally { uint tally[]; };

uniform int u_cells;
uniform float u_lid;
uniform float u_bottom;
uniform float u_depth;        // quartic depth D
uniform int u_rays;           // rays per column
uniform int u_slices;         // workgroups per column (gl_NumWorkGroups.y)
uniform uint u_seed;
uniform vec3 u_eta;
uniform vec3 u_k;
uniform vec2 u_cos_theta;     // cos θ of the two Fresnel tallies (θ = 0 and π/3)
uniform float u_scale;        // fixed-point scale of the weights

const float HUGE = 1e30;
const int SLOTS = 7;
shared uint s_tally[SLOTS * M_BINS];
shared uint s_lost;
shared uint s_done;

float quartic_h(float x) {
    float s = 2.0 * x - 1.0;
    float q = 1.0 - s * s;
    return -u_depth * q * q;
}

float quartic_dh(float x) {
    float s = 2.0 * x - 1.0;
    return 8.0 * u_depth * s * (1.0 - s * s);
}

vec3 wall_fresnel(float c) {
#if FRESNEL_MODEL == FRESNEL_SCHLICK
    vec3 f0 = (u_eta - 1.0) / (u_eta + 1.0);
    return fresnel_schlick(c, f0 * f0);
#elif FRESNEL_MODEL == FRESNEL_DIELECTRIC
    return fresnel_dielectric(c, u_eta);
#elif FRESNEL_MODEL == FRESNEL_LAZANYI
    float m = 1.0 - clamp(c, 0.0, 1.0);
    float m5 = m * m * m * m * m;
    return ((u_eta - 1.0) * (u_eta - 1.0) + 4.0 * u_eta * m5 + u_k * u_k) / ((u_eta + 1.0) * (u_eta + 1.0) + u_k * u_k);
#elif FRESNEL_MODEL == FRESNEL_CONDUCTOR
    return fresnel_conductor(c, u_eta, u_k);
#else
    return vec3(1.0);
#endif
}

int cell_of(float x) {  // last knot ≤ x (binary search), in [0, u_cells − 1]
    int lo = 0;
    int hi = u_cells;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (knots[mid].x <= x) lo = mid; else hi = mid;
    }
    return lo;
}

// Traces one ray; returns the exit bin, or −1 if the ray is lost. w0 / w1: Fresnel path weights.
int trace(float phi_in, float x0, out vec3 w0, out vec3 w1) {
    float px = x0;
    float py = u_lid;
    float dx = -sin(phi_in);
    float dy = -cos(phi_in);
    int cell = cell_of(px);
    w0 = vec3(1.0);
    w1 = vec3(1.0);
    int max_steps = 3 * u_cells + 8;
    for (int bounce = 0; bounce <= MAX_BOUNCES; ++bounce) {
        float t_exit = dy > 0.0 ? (u_lid - py) / dy : HUGE;
        float t_floor = dy < 0.0 ? (u_bottom - py) / dy : HUGE;
        float t_lo = 0.0;
        float t_hit = 0.0;
#if PROFILE_KIND == PROFILE_QUARTIC
        float g_lo = max(py - quartic_h(px), 0.0);
#endif
        int status = 0;  // 0 lost, 1 hit, 2 left through the lid
        for (int step = 0; step < max_steps; ++step) {
            vec2 a = knots[cell];
            vec2 b = knots[cell + 1];
            float t_out = dx > 0.0 ? (b.x - px) / dx : (dx < 0.0 ? (a.x - px) / dx : HUGE);
#if PROFILE_KIND == PROFILE_POLYLINE
            float slope = (b.y - a.y) / (b.x - a.x);
            float g0 = py - a.y - (px - a.x) * slope;
            float den = dy - dx * slope;
            if (den < 0.0) {
                float ts = -g0 / den;
                if (ts <= min(t_out, t_exit) && ts >= t_lo - 1e-5) {
                    t_hit = max(ts, 0.0);
                    status = 1;
                    break;
                }
            }
#else
            float th = min(min(t_out, t_exit), t_floor);
            float g_hi = py + th * dy - quartic_h(px + th * dx);
            bool crossed = g_hi <= 0.0;
            // a graze entering and leaving the curve inside the cell: possible only if g comes within
            // max g''·Δt²/8 ≤ 4D (dx Δt)² of 0 (|h''| ≤ 32 D) and g' < 0 at the start, > 0 at the end; the
            // minimum of g is then estimated by three regula-falsi steps on g' (no loop nor bisection here:
            // llvmpipe runs both sides of a branch, so the loops stay out of the cell walk)
            float reach = dx * (th - t_lo);
            float gp_lo = dy - dx * quartic_dh(px + t_lo * dx);
            float gp_hi = dy - dx * quartic_dh(px + th * dx);
            if (!crossed && min(g_lo, g_hi) < 8.0 * u_depth * reach * reach && gp_lo < 0.0 && gp_hi > 0.0) {
                float a = t_lo;
                float b = th;
                float ga = gp_lo;
                float gb = gp_hi;
                float tm = a;
                for (int k = 0; k < 3; ++k) {
                    tm = a + (b - a) * (-ga) / (gb - ga);
                    float gm = dy - dx * quartic_dh(px + tm * dx);
                    if (gm < 0.0) { a = tm; ga = gm; } else { b = tm; gb = gm; }
                }
                if (py + tm * dy - quartic_h(px + tm * dx) <= 0.0) {
                    crossed = true;
                    th = tm;
                }
            }
            if (crossed) {
                t_hit = th;  // bracket [t_lo, th], refined after the walk
                status = 1;
                break;
            }
            g_lo = g_hi;
#endif
            if (t_exit <= t_out) {
                status = 2;
                break;
            }
            t_lo = t_out;
            cell += dx > 0.0 ? 1 : -1;
            if (cell >= u_cells) {
                cell = 0;
                px -= 1.0;
            } else if (cell < 0) {
                cell = u_cells - 1;
                px += 1.0;
            }
        }
        if (status == 0) return -1;
#if PROFILE_KIND == PROFILE_QUARTIC
        if (status == 1) {  // bisection on the exact curve; the new origin is the end still above it
            float lo = t_lo;
            float hi = t_hit;
            for (int k = 0; k < 24; ++k) {
                float mid = 0.5 * (lo + hi);
                if (py + mid * dy - quartic_h(px + mid * dx) <= 0.0) hi = mid; else lo = mid;
            }
            t_hit = lo;
        }
#endif
        if (status == 2) {
            float phi_out = atan(dx, dy);
            return clamp(int(floor((phi_out + 0.5 * PI) * float(M_BINS) / PI)), 0, M_BINS - 1);
        }
        px += t_hit * dx;
        py += t_hit * dy;
#if PROFILE_KIND == PROFILE_POLYLINE
        float s = (knots[cell + 1].y - knots[cell].y) / (knots[cell + 1].x - knots[cell].x);
#else
        float s = quartic_dh(px);
#endif
        vec2 m = vec2(-s, 1.0) / sqrt(1.0 + s * s);
        float dm = dx * m.x + dy * m.y;
#if FRESNEL_MODEL != 0
        w0 *= wall_fresnel(abs(dm) * u_cos_theta.x);
        w1 *= wall_fresnel(abs(dm) * u_cos_theta.y);
#endif
        dx -= 2.0 * dm * m.x;
        dy -= 2.0 * dm * m.y;
        float len = inversesqrt(dx * dx + dy * dy);  // keep |d| = 1 in float32
        dx *= len;
        dy *= len;
    }
    return -1;
}

void main() {
    int column = int(gl_WorkGroupID.x);
    int slice = int(gl_WorkGroupID.y);
    uint local = gl_LocalInvocationIndex;
    for (uint i = local; i < uint(SLOTS * M_BINS); i += uint(LOCAL_SIZE)) s_tally[i] = 0u;
    if (local == 0u) {
        s_lost = 0u;
        s_done = 0u;
    }
    barrier();
    int stride = LOCAL_SIZE * u_slices;
    float half_bin = 0.5 * PI / float(M_BINS);
    float c_bar = cos(-0.5 * PI + (float(column) + 0.5) * PI / float(M_BINS)) * sin(half_bin) / half_bin;
    for (int r = slice * LOCAL_SIZE + int(local); r < u_rays; r += stride) {
        uint state = rng_seed(uvec2(uint(r), uint(column)), 0u, u_seed);
        // φ_in stratified inside the bin; ray weight c(ψ) = cos ψ / c̄_j (exactly reciprocal tallies, see tracer2d)
        float phi_in = -0.5 * PI + (float(column) + (float(r) + rng_next(state)) / float(u_rays)) * PI / float(M_BINS);
        float x0 = rng_next(state);
        vec3 w0;
        vec3 w1;
        int bin = trace(phi_in, x0, w0, w1);
        atomicAdd(s_done, 1u);
        if (bin < 0) {
            atomicAdd(s_lost, 1u);
            continue;
        }
        float cw = cos(phi_in) / c_bar * u_scale;
        atomicAdd(s_tally[bin], uint(cw + rng_next(state)));
#if FRESNEL_MODEL != 0
        for (int c = 0; c < 3; ++c) {
            atomicAdd(s_tally[(1 + c) * M_BINS + bin], uint(w0[c] * cw + rng_next(state)));
            atomicAdd(s_tally[(4 + c) * M_BINS + bin], uint(w1[c] * cw + rng_next(state)));
        }
#endif
    }
    barrier();
    for (uint i = local; i < uint(SLOTS * M_BINS); i += uint(LOCAL_SIZE)) {
        uint v = s_tally[i];
        if (v != 0u) {
            uint slot = i / uint(M_BINS);
            uint b = i % uint(M_BINS);
            atomicAdd(tally[(slot * uint(M_BINS) + b) * uint(M_BINS) + uint(column)], v);
        }
    }
    if (local == 0u) {
        if (s_lost != 0u) atomicAdd(tally[uint(SLOTS * M_BINS * M_BINS) + uint(column)], s_lost);
        atomicAdd(tally[uint(SLOTS * M_BINS * M_BINS + M_BINS) + uint(column)], s_done);
    }
}
