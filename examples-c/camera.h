/* Column-major camera matrices for Nimbus (right-handed, wgpu clip space: depth in [0, 1]).
 * Header-only, C99. */
#ifndef NIMBUS_CAMERA_H
#define NIMBUS_CAMERA_H

#include <math.h>

typedef struct { float x, y, z; } vec3;

static inline vec3 v3(float x, float y, float z) { vec3 v; v.x = x; v.y = y; v.z = z; return v; }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline float v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b) { return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static inline vec3 v3_norm(vec3 a) { float l = sqrtf(v3_dot(a, a)); return l > 0.0f ? v3_scale(a, 1.0f / l) : a; }

/* World-to-view, camera at `eye` looking at `target` (as glam's look_at_rh). */
static inline void mat_look_at(float m[16], vec3 eye, vec3 target, vec3 up) {
    vec3 f = v3_norm(v3_sub(target, eye));
    vec3 s = v3_norm(v3_cross(f, up));
    vec3 u = v3_cross(s, f);
    m[0] = s.x; m[1] = u.x; m[2] = -f.x; m[3] = 0.0f;
    m[4] = s.y; m[5] = u.y; m[6] = -f.y; m[7] = 0.0f;
    m[8] = s.z; m[9] = u.z; m[10] = -f.z; m[11] = 0.0f;
    m[12] = -v3_dot(s, eye); m[13] = -v3_dot(u, eye); m[14] = v3_dot(f, eye); m[15] = 1.0f;
}

/* Perspective with depth 0 at `near` and 1 at `far` (as glam's perspective_rh). */
static inline void mat_perspective(float m[16], float fov_y, float aspect, float near, float far) {
    float h = 1.0f / tanf(0.5f * fov_y), r = far / (near - far);
    int i;
    for (i = 0; i < 16; i++) m[i] = 0.0f;
    m[0] = h / aspect; m[5] = h; m[10] = r; m[11] = -1.0f; m[14] = r * near;
}

/* Transforms a point by a column-major matrix; returns clip-space (x, y, z) / w in *ndc and w. */
static inline float mat_project(const float m[16], vec3 p, vec3 *ndc) {
    float x = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    float y = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    float z = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    float w = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    *ndc = v3(x / w, y / w, z / w);
    return w;
}

static inline void mat_mul(float out[16], const float a[16], const float b[16]) {
    int c, r, k;
    for (c = 0; c < 4; c++)
        for (r = 0; r < 4; r++) {
            float s = 0.0f;
            for (k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
            out[c * 4 + r] = s;
        }
}

/* Direction toward the sun from elevation and azimuth in degrees (as nimbus::demo). */
static inline vec3 sun_from_angles(float elevation_deg, float azimuth_deg) {
    float e = elevation_deg * 0.01745329252f, a = azimuth_deg * 0.01745329252f;
    return v3(cosf(e) * sinf(a), sinf(e), -cosf(e) * cosf(a));
}

#endif
