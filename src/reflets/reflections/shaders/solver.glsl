// Provides fermat_reflection(E, V): the reflection point P on the reflector of the vertex V seen from the eye E,
// the stationary point of d(u, v) = |E − f| + |V − f| (Fermat). GLSL twin of reflets/reflections/solver.py
// (solve_robust, solve_document) on the surfaces of reflets/scene/surfaces.py; the tests compare them.
//
// Flags: SURFACE_KIND (SURFACE_SPHERE, _TORUS, _CYLINDER (open), _PLANE, _SAMPLED into a texture), SOLVER (SOLVER_ROBUST: safeguarded Newton with
// the analytic Hessian in a local chart; SOLVER_DOCUMENT: the triangle secant of §3.3), ITERATIONS, COUNT_ITERATIONS
// (1: record after how many iterations the residual fell below FERMAT_TOL — a residual per iteration, so only
// the read-back program pays for it).
// The reflector is a canonical shape (parameters r_params) under the mesh transform x → A x + t (r_linear,
// r_offset): an ellipsoid is a transformed sphere. Derivatives are mapped by A, so d is measured in world space.

uniform mat3 r_linear;   // A
uniform mat3 r_inverse;  // A⁻¹ (normals map by its transpose)
uniform vec3 r_offset;   // t
uniform vec4 r_params;   // sphere (radius); torus (major, minor); cylinder (radius, height); plane (size x, size z)

// FERMAT_TOL, FERMAT_MAX_ANGLE, FERMAT_MAX_STEP, FERMAT_GUESS_ANGLE, FERMAT_ACCEPT, FERMAT_MIN_EDGE, FERMAT_MIN_SIZE,
// SURFACE_* and SOLVER_* are #defines from reflets.reflections.solver (SolverSettings, glsl_constants).

struct FermatResult {
    vec3 position;
    vec3 normal;
    bool converged;    // residual < FERMAT_TOL: a stationary point of d
    bool valid;        // converged, and P faces both E and V
    float residual;    // ||unit(unit(E − P) + unit(V − P)) × n||
    int iterations;    // iterations before the residual fell below FERMAT_TOL (ITERATIONS if never)
};

// ------------------------------------------------------------------------------------------ the surfaces
// Each kind provides, in canonical space: surface_interior (the point O), surface_hit (global (u, v) where the
// segment P → O first meets the surface), chart_setup (the chart around A and B, and their coordinates in it),
// chart_from_uv, chart_clamp, chart_eval (f and its first and second derivatives) and chart_normal.

bool finite(float x) { return !(isnan(x) || isinf(x)); }

// periodic coordinates of global (u, v) taken nearest the middle of A and B (Chart._near_middle)
vec2 near_middle(vec2 x, vec2 a, vec2 b, bvec2 periodic) {
    vec2 m = 0.5 * (a + b);
    return vec2(periodic.x ? x.x - floor(x.x - m.x + 0.5) : x.x, periodic.y ? x.y - floor(x.y - m.y + 0.5) : x.y);
}

#if SURFACE_KIND == SURFACE_SPHERE
// Sphere of radius r_params.x. Robust: the lat-long chart whose equator is the great circle through A and B
// (SphereChart: the reflection lies on it for a sphere — no pole, no seam). Document: the global chart about +y.
mat3 g_frame;
const mat3 GLOBAL_FRAME = mat3(vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0));

vec3 sphere_direction(mat3 frame, vec2 x) {
    float phi = TWO_PI * x.x, theta = PI * x.y;
    return frame * vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

vec2 sphere_coordinates(mat3 frame, vec3 d) {  // _frame_inverse
    vec3 loc = transpose(frame) * d;
    float u = atan(loc.y, loc.x) / TWO_PI;
    return vec2(u - floor(u), acos(clamp(loc.z, -1.0, 1.0)) / PI);
}

vec3 surface_interior(vec3 E, vec3 V) { return vec3(0.0); }

vec2 surface_hit(vec3 P, vec3 O) { return sphere_coordinates(GLOBAL_FRAME, normalize(P - O)); }  // O: the centre

void chart_setup(vec2 a_uv, vec2 b_uv, out vec2 a, out vec2 b) {
#if SOLVER == SOLVER_ROBUST
    vec3 da = sphere_direction(GLOBAL_FRAME, a_uv), db = sphere_direction(GLOBAL_FRAME, b_uv);
    vec3 w = db - dot(db, da) * da;
    if (length(w) <= 1e-12) {  // A = ±B: any normal to Â
        vec3 ad = abs(da);
        vec3 axis = ad.x <= ad.y && ad.x <= ad.z ? vec3(1.0, 0.0, 0.0) : (ad.y <= ad.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0));
        w = cross(da, axis);
    }
    vec3 e2 = normalize(w);
    g_frame = mat3(da, e2, cross(da, e2));
    a = vec2(0.0, 0.5);
    b = vec2(atan(dot(db, e2), dot(db, da)) / TWO_PI, 0.5);
#else
    g_frame = GLOBAL_FRAME;
    a = a_uv;
    b = vec2(b_uv.x - floor(b_uv.x - a_uv.x + 0.5), b_uv.y);  // B's longitude next to A's
#endif
}

vec2 chart_from_uv(vec2 uv, vec2 a, vec2 b) {
    return near_middle(sphere_coordinates(g_frame, sphere_direction(GLOBAL_FRAME, uv)), a, b, bvec2(true, false));
}

vec2 chart_clamp(vec2 x) { return vec2(x.x, clamp(x.y, 0.0, 1.0)); }

void chart_eval(vec2 x, out vec3 f, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    x = chart_clamp(x);
    float phi = TWO_PI * x.x, theta = PI * x.y;
    float sp = sin(phi), cp = cos(phi), st = sin(theta), ct = cos(theta);
    mat3 m = r_params.x * g_frame;
    f = m * vec3(st * cp, st * sp, ct);
    fu = m * (TWO_PI * vec3(-st * sp, st * cp, 0.0));
    fv = m * (PI * vec3(ct * cp, ct * sp, -st));
    fuu = m * (TWO_PI * TWO_PI * vec3(-st * cp, -st * sp, 0.0));
    fuv = m * (TWO_PI * PI * vec3(-ct * sp, ct * cp, 0.0));
    fvv = m * (PI * PI * vec3(-st * cp, -st * sp, -ct));
}

vec3 chart_normal(vec2 x, vec3 f, vec3 fu, vec3 fv) { return f; }  // outward, defined at the poles too

#elif SURFACE_KIND == SURFACE_TORUS
// Ring torus about y, major R = r_params.x, minor r = r_params.y: both directions periodic and regular, the
// global chart with B unwrapped next to A. O: the core circle's point at the azimuth of the E, V midpoint.
float torus_implicit(vec3 q) {
    float rho = length(q.xz) - r_params.x;
    return rho * rho + q.y * q.y - r_params.y * r_params.y;
}

vec2 torus_uv(vec3 q) {
    float u = atan(q.x, q.z) / TWO_PI;
    float v = atan(q.y, length(q.xz) - r_params.x) / TWO_PI;
    return vec2(u - floor(u), v - floor(v));
}

vec3 surface_interior(vec3 E, vec3 V) {
    vec3 m = 0.5 * (E + V);
    float phi = atan(m.x, m.z);
    return r_params.x * vec3(sin(phi), 0.0, cos(phi));
}

// First crossing of the segment P → O: 32 march steps, then 48 bisections (ImplicitSurface.segment_hit).
vec2 surface_hit(vec3 P, vec3 O) {
    vec3 D = O - P;
    bool inside0 = torus_implicit(P) < 0.0;
    float lo = 31.0 / 32.0, hi = 1.0;
    bool found = false;
    for (int k = 1; k <= 32; ++k) {
        bool change = (torus_implicit(P + (float(k) / 32.0) * D) < 0.0) != inside0;
        if (change && !found) {
            lo = float(k - 1) / 32.0;
            hi = float(k) / 32.0;
            found = true;
        }
    }
    bool inside_lo = torus_implicit(P + lo * D) < 0.0;
    for (int k = 0; k < 48; ++k) {
        float mid = 0.5 * (lo + hi);
        bool same = (torus_implicit(P + mid * D) < 0.0) == inside_lo;
        lo = same ? mid : lo;
        hi = same ? hi : mid;
    }
    return torus_uv(P + 0.5 * (lo + hi) * D);
}

void chart_setup(vec2 a_uv, vec2 b_uv, out vec2 a, out vec2 b) {
    a = a_uv;
    b = b_uv - floor(b_uv - a_uv + 0.5);
}

vec2 chart_from_uv(vec2 uv, vec2 a, vec2 b) { return near_middle(uv, a, b, bvec2(true, true)); }

vec2 chart_clamp(vec2 x) { return x; }

void chart_eval(vec2 x, out vec3 f, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    float phi = TWO_PI * x.x, theta = TWO_PI * x.y;
    float sp = sin(phi), cp = cos(phi), st = sin(theta), ct = cos(theta);
    float R = r_params.x, r = r_params.y;
    float w = R + r * ct;
    f = vec3(w * sp, r * st, w * cp);
    fu = TWO_PI * w * vec3(cp, 0.0, -sp);
    fv = TWO_PI * r * vec3(-st * sp, ct, -st * cp);
    float k = TWO_PI * TWO_PI;
    fuu = -k * w * vec3(sp, 0.0, cp);
    fuv = -k * r * st * vec3(cp, 0.0, -sp);
    fvv = -k * r * vec3(ct * sp, st, ct * cp);
}

vec3 chart_normal(vec2 x, vec3 f, vec3 fu, vec3 fv) { return cross(fu, fv); }

#elif SURFACE_KIND == SURFACE_CYLINDER
// Side of a cylinder along y, radius r_params.x, height r_params.y: (r sinφ, h/2 − h v, r cosφ), u periodic.
// O: on the axis at the E, V mean height (clamped to the cylinder).
vec2 cylinder_uv(vec3 q) {
    float u = atan(q.x, q.z) / TWO_PI;
    return vec2(u - floor(u), clamp(0.5 - q.y / r_params.y, 0.0, 1.0));
}

vec3 surface_interior(vec3 E, vec3 V) {
    float h = r_params.y;
    return vec3(0.0, clamp(0.5 * (E.y + V.y), -0.5 * h, 0.5 * h), 0.0);
}

vec2 surface_hit(vec3 P, vec3 O) {
    vec2 p = P.xz, d = O.xz - P.xz;
    float a = dot(d, d), b = dot(p, d), c = dot(p, p) - r_params.x * r_params.x;
    float disc = b * b - a * c;
    float t = (-b - sqrt(max(disc, 0.0))) / max(a, 1e-30);
    t = (disc >= 0.0 && t >= 0.0) ? clamp(t, 0.0, 1.0) : 0.0;
    return cylinder_uv(P + t * (O - P));
}

void chart_setup(vec2 a_uv, vec2 b_uv, out vec2 a, out vec2 b) {
    a = a_uv;
    b = vec2(b_uv.x - floor(b_uv.x - a_uv.x + 0.5), b_uv.y);
}

vec2 chart_from_uv(vec2 uv, vec2 a, vec2 b) { return near_middle(uv, a, b, bvec2(true, false)); }

vec2 chart_clamp(vec2 x) { return vec2(x.x, clamp(x.y, 0.0, 1.0)); }

void chart_eval(vec2 x, out vec3 f, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    x = chart_clamp(x);
    float phi = TWO_PI * x.x;
    float sp = sin(phi), cp = cos(phi), r = r_params.x, h = r_params.y;
    f = vec3(r * sp, 0.5 * h - h * x.y, r * cp);
    fu = TWO_PI * r * vec3(cp, 0.0, -sp);
    fv = vec3(0.0, -h, 0.0);
    fuu = -TWO_PI * TWO_PI * r * vec3(sp, 0.0, cp);
    fuv = vec3(0.0);
    fvv = vec3(0.0);
}

vec3 chart_normal(vec2 x, vec3 f, vec3 fu, vec3 fv) { return -cross(fu, fv); }

#elif SURFACE_KIND == SURFACE_PLANE
// Rectangle in y = 0 of size (r_params.x, r_params.y), normal +y: f = ((u − ½) s_x, 0, −(v − ½) s_z), as
// Plane(point 0, axis_u (s_x, 0, 0), axis_v (0, 0, −s_z)). O: below the plane.
vec3 surface_interior(vec3 E, vec3 V) { return vec3(0.0, -(r_params.x + r_params.y), 0.0); }

vec2 surface_hit(vec3 P, vec3 O) {
    vec3 D = O - P;
    float t = clamp(-P.y / (abs(D.y) > 1e-30 ? D.y : 1e-30), 0.0, 1.0);
    vec3 x = P + t * D;
    return clamp(vec2(x.x / r_params.x + 0.5, 0.5 - x.z / r_params.y), 0.0, 1.0);
}

void chart_setup(vec2 a_uv, vec2 b_uv, out vec2 a, out vec2 b) {
    a = a_uv;
    b = b_uv;
}

vec2 chart_from_uv(vec2 uv, vec2 a, vec2 b) { return uv; }

vec2 chart_clamp(vec2 x) { return clamp(x, 0.0, 1.0); }

void chart_eval(vec2 x, out vec3 f, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    x = chart_clamp(x);
    f = vec3((x.x - 0.5) * r_params.x, 0.0, (0.5 - x.y) * r_params.y);
    fu = vec3(r_params.x, 0.0, 0.0);
    fv = vec3(0.0, 0.0, -r_params.y);
    fuu = fuv = fvv = vec3(0.0);
}

vec3 chart_normal(vec2 x, vec3 f, vec3 fu, vec3 fv) { return vec3(0.0, 1.0, 0.0); }
#elif SURFACE_KIND == SURFACE_SAMPLED
// A reflector sampled into a float texture (surfaces.SampledSurface, bicubic): node grid padded with one ghost
// node before and two after (wrapped, or linearly extrapolated on clamped edges), Catmull–Rom on the 4×4
// stencil, so f is C1 and the Fermat gradient continuous (GridInterpolator). Any analytic reflector can be
// solved this way (sampled = N), and Bézier / height-field patches always are. The global chart, B unwrapped;
// A and B by the generic segment hit (coarse grid search, then Newton on f(u, v) = P + t (O − P)).
uniform sampler2D r_grid;      // (n_u + 3) × (n_v + 3) texels: canonical positions
uniform ivec2 r_nodes;         // n_u, n_v
uniform ivec2 r_periodic;      // 1 where the direction wraps
uniform vec3 r_interior;       // O, canonical
uniform float r_orientation;   // normal = orientation · unit(f_u × f_v)
uniform int r_hit_grid;        // coarse grid of the segment hit

vec4 catmull_rom(float t, int order) {
    if (order == 0) return 0.5 * vec4(-t + 2.0 * t * t - t * t * t, 2.0 - 5.0 * t * t + 3.0 * t * t * t,
                                      t + 4.0 * t * t - 3.0 * t * t * t, -t * t + t * t * t);
    if (order == 1) return 0.5 * vec4(-1.0 + 4.0 * t - 3.0 * t * t, -10.0 * t + 9.0 * t * t,
                                      1.0 + 8.0 * t - 9.0 * t * t, -2.0 * t + 3.0 * t * t);
    return 0.5 * vec4(4.0 - 6.0 * t, -10.0 + 18.0 * t, 8.0 - 18.0 * t, -2.0 + 6.0 * t);
}

// cell index in the padded grid, fraction, d(grid coordinate)/d(parameter)
void grid_cell(float x, int n, bool periodic, out int i, out float t, out float s) {
    if (periodic) {
        float g = x * float(n);
        float f = floor(g);
        i = int(f - float(n) * floor(f / float(n)));
        t = g - f;
        s = float(n);
    } else {
        float g = clamp(x, 0.0, 1.0) * float(n - 1);
        float f = min(floor(g), float(n - 2));
        i = int(f);
        t = g - f;
        s = float(n - 1);
    }
}

vec3 chart_eval_order(vec2 x, int order, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    int iu, iv;
    float tu, tv, su, sv;
    grid_cell(x.x, r_nodes.x, r_periodic.x == 1, iu, tu, su);
    grid_cell(x.y, r_nodes.y, r_periodic.y == 1, iv, tv, sv);
    vec4 wu0 = catmull_rom(tu, 0), wu1 = catmull_rom(tu, 1), wu2 = catmull_rom(tu, 2);
    vec4 wv0 = catmull_rom(tv, 0), wv1 = catmull_rom(tv, 1), wv2 = catmull_rom(tv, 2);
    vec3 f = vec3(0.0);
    fu = fv = fuu = fuv = fvv = vec3(0.0);
    for (int j = 0; j < 4; ++j) {
        vec3 r0 = vec3(0.0), r1 = vec3(0.0), r2 = vec3(0.0);
        for (int i = 0; i < 4; ++i) {
            vec3 node = texelFetch(r_grid, ivec2(iu + i, iv + j), 0).xyz;
            r0 += wu0[i] * node;
            r1 += wu1[i] * node;
            r2 += wu2[i] * node;
        }
        f += wv0[j] * r0;
        fu += wv0[j] * r1;
        fv += wv1[j] * r0;
        fuu += wv0[j] * r2;
        fuv += wv1[j] * r1;
        fvv += wv2[j] * r0;
    }
    fu *= su;
    fv *= sv;
    fuu *= su * su;
    fuv *= su * sv;
    fvv *= sv * sv;
    return f;
}

vec2 chart_clamp(vec2 x) {
    return vec2(r_periodic.x == 1 ? x.x : clamp(x.x, 0.0, 1.0), r_periodic.y == 1 ? x.y : clamp(x.y, 0.0, 1.0));
}

void chart_eval(vec2 x, out vec3 f, out vec3 fu, out vec3 fv, out vec3 fuu, out vec3 fuv, out vec3 fvv) {
    f = chart_eval_order(chart_clamp(x), 2, fu, fv, fuu, fuv, fvv);
}

vec3 sampled_position(vec2 x) {
    vec3 fu, fv, fuu, fuv, fvv;
    return chart_eval_order(chart_clamp(x), 0, fu, fv, fuu, fuv, fvv);
}

vec3 surface_interior(vec3 E, vec3 V) { return r_interior; }

// Surface.segment_hit: the node of a coarse grid nearest to the segment, then 16 Newton steps (each at most half
// a coarse cell in (u, v)) on f(u, v) = P + t D (Cramer's rule on [f_u, f_v, −D]).
vec2 surface_hit(vec3 P, vec3 O) {
    vec3 D = O - P;
    float dd = max(dot(D, D), 1e-30);
    float g = float(r_hit_grid);
    vec2 best = vec2(0.0);
    float best_s = 0.0, best_d = 1e30;
    for (int j = 0; j <= r_hit_grid; ++j) {
        for (int i = 0; i <= r_hit_grid; ++i) {
            vec2 x = vec2(float(i), float(j)) / g;
            vec3 X = sampled_position(x);
            float s = clamp(dot(X - P, D) / dd, 0.0, 1.0);
            vec3 r = P + s * D - X;
            float d2 = dot(r, r);
            if (d2 < best_d) {
                best_d = d2;
                best = x;
                best_s = s;
            }
        }
    }
    vec2 x = best;
    float s = best_s;
    for (int k = 0; k < 16; ++k) {
        vec3 f, fu, fv, fuu, fuv, fvv;
        chart_eval(x, f, fu, fv, fuu, fuv, fvv);
        vec3 F = f - P - s * D;
        vec3 c2 = -D;
        float det = dot(fu, cross(fv, c2));
        float scale = length(fu) * length(fv) * length(c2);
        bool ok = abs(det) > 1e-14 * scale && finite(det);
        vec3 rhs = -F;
        vec3 step = ok ? vec3(dot(rhs, cross(fv, c2)), dot(fu, cross(rhs, c2)), dot(fu, cross(fv, rhs))) / det : vec3(0.0);
        float len = length(step.xy);
        step *= min(1.0, 0.5 / g / max(len, 1e-30));
        x = chart_clamp(x + step.xy);
        s = clamp(s + step.z, 0.0, 1.0);
    }
    return vec2(r_periodic.x == 1 ? x.x - floor(x.x) : x.x, r_periodic.y == 1 ? x.y - floor(x.y) : x.y);
}

void chart_setup(vec2 a_uv, vec2 b_uv, out vec2 a, out vec2 b) {
    a = a_uv;
    b = vec2(r_periodic.x == 1 ? b_uv.x - floor(b_uv.x - a_uv.x + 0.5) : b_uv.x,
             r_periodic.y == 1 ? b_uv.y - floor(b_uv.y - a_uv.y + 0.5) : b_uv.y);
}

vec2 chart_from_uv(vec2 uv, vec2 a, vec2 b) { return near_middle(uv, a, b, bvec2(r_periodic.x == 1, r_periodic.y == 1)); }

vec3 chart_normal(vec2 x, vec3 f, vec3 fu, vec3 fv) { return r_orientation * cross(fu, fv); }
#endif

// ------------------------------------------------------------------------------------------ world space
struct ChartPoint {  // f and its derivatives at a chart point, in world space
    vec3 f, fu, fv, fuu, fuv, fvv;
};

ChartPoint world_eval(vec2 x) {
    ChartPoint p;
    chart_eval(x, p.f, p.fu, p.fv, p.fuu, p.fuv, p.fvv);
    p.f = r_linear * p.f + r_offset;
    p.fu = r_linear * p.fu;
    p.fv = r_linear * p.fv;
    p.fuu = r_linear * p.fuu;
    p.fuv = r_linear * p.fuv;
    p.fvv = r_linear * p.fvv;
    return p;
}

// Gradient of d = |E − f| + |V − f| in the chart and its analytic Hessian (solver._derivatives):
// g = −(f_u, f_v)·(â + b̂), H_ij = −f_ij·(â + b̂) + f_iᵀ[(I − ââᵀ)/|a| + (I − b̂b̂ᵀ)/|b|] f_j.
void path_derivatives(ChartPoint p, vec3 E, vec3 V, out vec2 g, out mat2 H) {
    vec3 av = E - p.f, bv = V - p.f;
    float la = length(av), lb = length(bv);
    vec3 ah = av / la, bh = bv / lb;
    vec3 h = ah + bh;
    g = -vec2(dot(p.fu, h), dot(p.fv, h));
    float uu = dot(p.fu, p.fu), uv = dot(p.fu, p.fv), vv = dot(p.fv, p.fv);
    float ua = dot(p.fu, ah), va = dot(p.fv, ah), ub = dot(p.fu, bh), vb = dot(p.fv, bh);
    float h00 = -dot(p.fuu, h) + (uu - ua * ua) / la + (uu - ub * ub) / lb;
    float h01 = -dot(p.fuv, h) + (uv - ua * va) / la + (uv - ub * vb) / lb;
    float h11 = -dot(p.fvv, h) + (vv - va * va) / la + (vv - vb * vb) / lb;
    H = mat2(h00, h01, h01, h11);
}

FermatResult fermat_result(vec2 x, vec3 E, vec3 V, int iterations) {
    vec3 f, fu, fv, fuu, fuv, fvv;
    chart_eval(x, f, fu, fv, fuu, fuv, fvv);
    vec3 n_canonical = chart_normal(x, f, fu, fv);
    FermatResult r;
    r.position = r_linear * f + r_offset;
    r.normal = normalize(transpose(r_inverse) * n_canonical);
    vec3 h = normalize(normalize(E - r.position) + normalize(V - r.position));
    r.residual = length(cross(h, r.normal));
    r.residual = finite(r.residual) ? r.residual : 1e30;
    r.converged = r.residual < FERMAT_TOL;
    r.valid = r.converged && dot(r.normal, E - r.position) > 0.0 && dot(r.normal, V - r.position) > 0.0;
    r.iterations = iterations;
    return r;
}

// A, B, O of the document's initialisation and the chart around them; a, b are A's and B's chart coordinates.
void fermat_start(vec3 E, vec3 V, out vec2 a, out vec2 b, out vec3 O_canonical) {
    vec3 Ec = r_inverse * (E - r_offset), Vc = r_inverse * (V - r_offset);
    O_canonical = surface_interior(Ec, Vc);
    chart_setup(surface_hit(Vc, O_canonical), surface_hit(Ec, O_canonical), a, b);
}

#if SOLVER == SOLVER_ROBUST
// Angle the normal turns along a chart step (normal curvature × 3D length), to first order (solver._turn).
float normal_turn(vec2 s, ChartPoint p) {
    float len = length(p.fu * s.x + p.fv * s.y);
    float bend = abs(dot(normalize(cross(p.fu, p.fv)), p.fuu * s.x * s.x + 2.0 * p.fuv * s.x * s.y + p.fvv * s.y * s.y));
    return bend / max(len, 1e-30);
}

// −H⁻¹ g, or −g/||H||_F where H is singular or not finite (solver._newton_step).
vec2 newton_step(vec2 g, mat2 H) {
    float det = H[0][0] * H[1][1] - H[0][1] * H[1][0];
    float fro2 = dot(H[0], H[0]) + dot(H[1], H[1]);
    bool ok = finite(det) && abs(det) > 1e-10 * fro2;
    vec2 newton = vec2(H[1][1] * g.x - H[1][0] * g.y, H[0][0] * g.y - H[0][1] * g.x);
    vec2 step = ok ? -newton / det : -g / max(sqrt(fro2), 1e-30);
    return (finite(step.x) && finite(step.y)) ? step : vec2(0.0);
}

// Start (initial_guess, "tangent_plane"): X where the ray from O along the bisector of OA and OB meets the
// surface, then the closed-form mirror point of the tangent plane at X, pulled back to first order and limited
// to a normal turn of FERMAT_GUESS_ANGLE.
vec2 fermat_guess(vec3 E, vec3 V, vec2 a, vec2 b, vec3 O_canonical) {
    vec3 O = r_linear * O_canonical + r_offset;
    vec3 oa = world_eval(a).f - O, ob = world_eval(b).f - O;
    vec3 w = normalize(oa) + normalize(ob);
    w = length(w) > 1e-6 ? w : oa;
    vec3 far_point = O + 2.0 * max(length(oa), length(ob)) * normalize(w);
    vec2 X = chart_from_uv(surface_hit(r_inverse * (far_point - r_offset), O_canonical), a, b);
    ChartPoint p = world_eval(X);
    vec3 n = normalize(cross(p.fu, p.fv));
    vec3 Vm = V - 2.0 * dot(V - p.f, n) * n;  // planar_reflection
    float den = dot(Vm - E, n);
    vec3 d = E + (dot(p.f - E, n) / (abs(den) > 1e-30 ? den : 1e-30)) * (Vm - E) - p.f;
    float g00 = dot(p.fu, p.fu), g01 = dot(p.fu, p.fv), g11 = dot(p.fv, p.fv);
    float det = g00 * g11 - g01 * g01;
    vec2 delta = vec2(g11 * dot(p.fu, d) - g01 * dot(p.fv, d), g00 * dot(p.fv, d) - g01 * dot(p.fu, d)) / det;
    bool usable = finite(delta.x) && finite(delta.y) && det > 1e-12 * g00 * g11;
    delta = usable ? delta : vec2(0.0);
    delta *= min(1.0, FERMAT_GUESS_ANGLE / max(normal_turn(delta, p), 1e-30));
    return chart_clamp(X + delta);
}

// Newton on ∇d = 0 with the analytic Hessian, in the local chart, inside a trust region (solver.solve_robust):
// steps limited by the normal's turn and a chart length; a step that multiplies |∇d|² by more than
// FERMAT_ACCEPT is rejected and the region shrinks to a quarter of it, an accepted one doubles it.
FermatResult fermat_reflection(vec3 E, vec3 V) {
    vec2 a, b;
    vec3 O_canonical;
    fermat_start(E, V, a, b, O_canonical);
    vec2 x = fermat_guess(E, V, a, b, O_canonical);
    ChartPoint p = world_eval(x);
    vec2 g;
    mat2 H;
    path_derivatives(p, E, V, g, H);
    float merit = dot(g, g);
    merit = finite(merit) ? merit : 1e38;
    float angle = FERMAT_MAX_ANGLE, radius = FERMAT_MAX_STEP;
    int used = ITERATIONS;
    for (int k = 1; k <= ITERATIONS; ++k) {
        vec2 step = newton_step(g, H);
        float turn = normal_turn(step, p);
        float len = length(step);
        float scale = min(1.0, min(angle / max(turn, 1e-30), radius / max(len, 1e-30)));
        step *= scale;
        turn *= scale;
        len *= scale;
        vec2 xc = chart_clamp(x + step);
        ChartPoint pc = world_eval(xc);
        vec2 gc;
        mat2 Hc;
        path_derivatives(pc, E, V, gc, Hc);
        float mc = dot(gc, gc);
        mc = finite(mc) ? mc : 1e38;
        bool accept = mc < FERMAT_ACCEPT * merit || merit >= 1e38;
        if (accept) {
            x = xc;
            p = pc;
            g = gc;
            H = Hc;
            merit = mc;
        }
        angle = accept ? min(2.0 * angle, 2.0 * FERMAT_MAX_ANGLE) : 0.25 * max(turn, 1e-12);
        radius = accept ? min(2.0 * radius, 2.0 * FERMAT_MAX_STEP) : 0.25 * max(len, 1e-12);
#if COUNT_ITERATIONS
        if (used == ITERATIONS && fermat_result(x, E, V, 0).residual < FERMAT_TOL) used = k;
#endif
    }
    return fermat_result(x, E, V, used);
}

#else
// The document's triangle secant (solver.solve_document, global chart, B unwrapped next to A): triangle A, B, C
// in (u, v) with the gradients there; [G_B − G_A, G_C − G_A](α, β)ᵀ = −G_A, P = (1 − α − β)A + αB + βC replaces
// the vertex farthest from P; a pair stops on a singular system or a triangle smaller than FERMAT_MIN_SIZE.
vec2 chart_gradient(vec2 x, vec3 E, vec3 V) {
    ChartPoint p = world_eval(x);
    vec3 h = normalize(E - p.f) + normalize(V - p.f);
    return -vec2(dot(p.fu, h), dot(p.fv, h));
}

float cross2(vec2 p, vec2 q) { return p.x * q.y - p.y * q.x; }

FermatResult fermat_reflection(vec3 E, vec3 V) {
    vec2 X[3];
    vec3 O_canonical;
    fermat_start(E, V, X[0], X[1], O_canonical);
    // third_point: equilateral on AB (B first moved FERMAT_MIN_EDGE from A when they nearly coincide)
    vec2 e = X[1] - X[0];
    float elen = length(e);
    vec2 dir = elen > 0.0 ? e / elen : vec2(1.0, 0.0);
    if (elen < FERMAT_MIN_EDGE) X[1] = X[0] + FERMAT_MIN_EDGE * dir;
    e = X[1] - X[0];
    X[2] = chart_clamp(0.5 * (X[0] + X[1]) + 0.5 * sqrt(3.0) * vec2(-e.y, e.x));
    vec2 G[3];
    for (int k = 0; k < 3; ++k) G[k] = chart_gradient(X[k], E, V);
    int best = 0;
    for (int k = 1; k < 3; ++k) if (length(G[k]) < length(G[best])) best = k;
    vec2 x = X[best];
    bool running = true;
    int used = 0;
    for (int it = 0; it < ITERATIONS; ++it) {
        vec2 d1 = G[1] - G[0], d2 = G[2] - G[0];
        float det = cross2(d1, d2);
        bool ok = finite(det) && abs(det) > 1e-12 * length(d1) * length(d2);
        det = ok ? det : 1.0;
        float alpha = cross2(-G[0], d2) / det, beta = cross2(d1, -G[0]) / det;
        vec2 P = chart_clamp(X[0] + alpha * (X[1] - X[0]) + beta * (X[2] - X[0]));
        bool step = running && ok && finite(P.x) && finite(P.y);
        if (step) {
            vec2 GP = chart_gradient(P, E, V);
            int far = 0;
            for (int k = 1; k < 3; ++k) if (length(X[k] - P) > length(X[far] - P)) far = k;
            X[far] = P;
            G[far] = GP;
            x = P;
            used += 1;
        }
        float size = max(max(length(X[0] - X[1]), length(X[1] - X[2])), length(X[2] - X[0]));
        running = step && size > FERMAT_MIN_SIZE;
    }
    return fermat_result(x, E, V, used);
}
#endif
