// The document's object shading, fragment stage: the specular term k_s times the captured cube map along the
// reflected direction, at the mip level of the lobe's exponent (McGuire et al. 2013:
// λ = log2(N √3) − ½ log2(Ns + 1)); alpha 1 marks the object's coverage.
in vec3 v_position;
in vec3 v_normal;
in vec3 v_diffuse;

uniform samplerCube u_environment;
uniform vec3 u_eye;
uniform vec3 u_ks;
uniform float u_level;

out vec4 frag_color;

void main() {
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_position);
    if (dot(n, v) < 0.0) n = -n;  // two-sided, as seen
    vec3 r = reflect(-v, n);
    vec3 specular = u_ks * textureLod(u_environment, r, u_level).rgb;
    frag_color = vec4(v_diffuse + specular, 1.0);
}
