"""The GLSL sources (#version 330 core). Strands are drawn as GL_LINES segments that a
geometry shader widens into camera-facing ribbons of a fixed width in pixels; their
fragments are shaded by Kajiya–Kay (diffuse sin(T, L), specular sin(T, H)^p) and darkened
by the opacity shadow map (shadows.py). Bodies are triangle meshes, Lambert-shaded, in the
same shadow. Each pass has a depth-only twin that draws into the light's depth map."""

VERSION = "#version 330 core\n"

HAIR_VERTEX = """
in vec3 in_pos;
in vec3 in_tan;
in float in_t;     // 0 at the root, 1 at the tip
in float in_tint;  // one random number a strand, in [-1, 1]
out vec3 v_pos;
out vec3 v_tan;
out float v_t;
out float v_tint;
void main() {
    v_pos = in_pos;
    v_tan = in_tan;
    v_t = in_t;
    v_tint = in_tint;
}
"""

# One segment in, one quad out: each end moved by half the width, across the segment's
# direction on the screen, so the ribbon always faces the camera.
HAIR_GEOMETRY = """
layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;
uniform mat4 mvp;
uniform vec2 viewport;   // pixels
uniform float width_px;
in vec3 v_pos[];
in vec3 v_tan[];
in float v_t[];
in float v_tint[];
out vec3 g_pos;
out vec3 g_tan;
out float g_t;
out float g_tint;
void emit(int i, vec2 offset) {
    vec4 c = mvp * vec4(v_pos[i], 1.0);
    gl_Position = vec4(c.xy + offset * c.w, c.z, c.w);
    g_pos = v_pos[i];
    g_tan = v_tan[i];
    g_t = v_t[i];
    g_tint = v_tint[i];
    EmitVertex();
}
void main() {
    vec4 a = mvp * vec4(v_pos[0], 1.0);
    vec4 b = mvp * vec4(v_pos[1], 1.0);
    vec2 d = (b.xy / b.w - a.xy / a.w) * viewport;
    vec2 n = length(d) > 1e-6 ? normalize(vec2(-d.y, d.x)) : vec2(1.0, 0.0);
    vec2 offset = n * width_px / viewport;  // half the width in NDC is width_px / viewport
    emit(0, offset);
    emit(0, -offset);
    emit(1, offset);
    emit(1, -offset);
    EndPrimitive();
}
"""

# transmittance toward the light: exp(−σ·(depth past the first occluder)) over (2·PCF + 1)²
# texels of the depth map; PCF 0 (one tap, filtered bilinearly) costs 0.18 s less a frame on
# llvmpipe than PCF 1 (docs/decisions/render.md)
SHADOW_LOOKUP = """
#ifndef PCF
#define PCF 0
#endif
uniform sampler2D shadow_map;
uniform mat4 light_mvp;
uniform float light_depth_cm;  // far − near of the light's orthographic box
uniform float sigma;           // 1/cm: how fast hair darkens what lies behind it
uniform float shadow_bias_cm;
uniform bool use_shadows;
float transmittance(vec3 world) {
    if (!use_shadows) return 1.0;
    vec4 l = light_mvp * vec4(world, 1.0);
    vec3 p = l.xyz / l.w * 0.5 + 0.5;
    if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0) return 1.0;
    vec2 texel = 1.0 / vec2(textureSize(shadow_map, 0));
    float sum = 0.0;
    for (int i = -PCF; i <= PCF; ++i) {
        for (int j = -PCF; j <= PCF; ++j) {
            float first = texture(shadow_map, p.xy + vec2(i, j) * texel).r;
            float past = max((p.z - first) * light_depth_cm - shadow_bias_cm, 0.0);
            sum += exp(-sigma * past);
        }
    }
    return sum / float((2 * PCF + 1) * (2 * PCF + 1));
}
"""

HAIR_FRAGMENT = (
    SHADOW_LOOKUP
    + """
uniform vec3 light_dir;  // toward the light, unit
uniform vec3 eye;
uniform vec3 root_color;
uniform vec3 tip_color;
uniform vec3 specular_color;
uniform float tint_amount;
uniform float ambient;
uniform float kd;
uniform float ks;
uniform float shininess;
uniform float gamma;
in vec3 g_pos;
in vec3 g_tan;
in float g_t;
in float g_tint;
out vec4 f_color;
void main() {
    vec3 T = normalize(g_tan);
    vec3 V = normalize(eye - g_pos);
    vec3 H = normalize(light_dir + V);
    float tl = dot(T, light_dir);
    float th = dot(T, H);
    float diffuse = sqrt(max(1.0 - tl * tl, 0.0));                    // Kajiya–Kay: sin(T, L)
    float specular = pow(sqrt(max(1.0 - th * th, 0.0)), shininess);   // sin(T, H)^p
    vec3 albedo = mix(root_color, tip_color, g_t) * (1.0 + tint_amount * g_tint);
    float lit = transmittance(g_pos);
    vec3 c = albedo * (ambient + kd * diffuse * lit) + ks * specular * lit * specular_color;
    f_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / gamma)), 1.0);
}
"""
)

BODY_VERTEX = """
uniform mat4 mvp;
uniform mat4 model;  // object → world: the body's transform of this frame
in vec3 in_pos;
in vec3 in_normal;
out vec3 b_world;
out vec3 b_normal;
out vec3 b_object_normal;
void main() {
    vec4 w = model * vec4(in_pos, 1.0);
    b_world = w.xyz;
    b_normal = mat3(model) * in_normal;  // rotations and translations only
    b_object_normal = in_normal;
    gl_Position = mvp * w;
}
"""

# eyes: two dark dots on the +z side of the object, so a turning sphere shows that it turns
BODY_FRAGMENT = (
    SHADOW_LOOKUP
    + """
uniform vec3 light_dir;
uniform vec3 eye;
uniform vec3 body_color;
uniform bool face_marks;
uniform float ambient;
uniform float gamma;
in vec3 b_world;
in vec3 b_normal;
in vec3 b_object_normal;
out vec4 f_color;
void main() {
    vec3 N = normalize(b_normal);
    vec3 V = normalize(eye - b_world);
    if (dot(N, V) < 0.0) N = -N;
    vec3 albedo = body_color;
    if (face_marks) {
        vec3 o = normalize(b_object_normal);
        float eyes = max(dot(o, normalize(vec3(0.33, 0.22, 0.92))), dot(o, normalize(vec3(-0.33, 0.22, 0.92))));
        albedo = eyes > 0.997 ? vec3(0.08, 0.06, 0.05) : albedo;
    }
    float lit = transmittance(b_world);
    float diffuse = max(dot(N, light_dir), 0.0);
    vec3 H = normalize(light_dir + V);
    float specular = 0.15 * pow(max(dot(N, H), 0.0), 40.0);
    vec3 c = albedo * (ambient + (1.0 - ambient) * diffuse * lit) + vec3(specular * lit);
    f_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / gamma)), 1.0);
}
"""
)

DEPTH_FRAGMENT = """
void main() {}
"""


def source(*parts):
    """One shader's source: the version line, then the parts."""
    return VERSION + "".join(parts)
