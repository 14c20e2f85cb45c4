/* A small scene "rendered" on the CPU so depth occlusion of the clouds is visible: a sky
 * gradient, a checkered ground plane and a few towers, some tall enough to reach into the
 * cloud layer. Produces linear RGBA color and clip-space depth (standard convention). The
 * sunlight on the ground and towers goes through the clouds' shadow map when one is given.
 * Header-only, C99. */
#ifndef NIMBUS_SCENE_H
#define NIMBUS_SCENE_H

#include <math.h>
#include "camera.h"
#include "nimbus.h"

/* What the clouds give the scene's lighting: a read-back copy of Nimbus's cloud shadow map
 * (nimbus_context_read_cloud_shadows) and its layout (nimbus_context_cloud_shadows), and the
 * light at the camera (nimbus_context_read_ambient_light). */
typedef struct {
    const float *texels; /* 4 floats per texel: front depth, mean extinction, optical depth, T */
    NimbusCloudShadowInfo info;
    const NimbusAmbientLight *ambient; /* NULL: the scene's own clear-sky ambient alone */
} SceneShadows;

/* The fraction of sunlight reaching world point p through the clouds: the map's texels
 * filtered bilinearly (repeat addressing: the map is toroidal), then the Beer shadow map's
 * optical depth min(mean extinction * max(depth - front, 0), total). 1 outside the square. */
static inline float scene_sun_visibility(const SceneShadows *s, vec3 p) {
    const float *m;
    float u, v, z, fx, fy, wx, wy, tau, margin, texel[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    int n, x0, y0, k, c;
    if (!s || !s->texels) return 1.0f;
    m = s->info.world_to_map;
    n = (int)s->info.resolution;
    u = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    v = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    z = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    /* Half a texel in from the edge: the bilinear footprint must not reach across the
     * toroidal seam into the square's other side. */
    margin = 0.5f / (float)n;
    if (u - s->info.window_origin[0] < margin || u - s->info.window_origin[0] >= 1.0f - margin ||
        v - s->info.window_origin[1] < margin || v - s->info.window_origin[1] >= 1.0f - margin)
        return 1.0f;
    fx = u * (float)n - 0.5f;
    fy = v * (float)n - 0.5f;
    x0 = (int)floorf(fx);
    y0 = (int)floorf(fy);
    wx = fx - (float)x0;
    wy = fy - (float)y0;
    for (k = 0; k < 4; k++) {
        int x = ((x0 + (k & 1)) % n + n) % n, y = ((y0 + (k >> 1)) % n + n) % n;
        float w = ((k & 1) ? wx : 1.0f - wx) * ((k >> 1) ? wy : 1.0f - wy);
        for (c = 0; c < 4; c++) texel[c] += w * s->texels[((size_t)y * (size_t)n + (size_t)x) * 4 + (size_t)c];
    }
    tau = texel[1] * (z - texel[0] > 0.0f ? z - texel[0] : 0.0f);
    return expf(-(tau < texel[2] ? tau : texel[2]));
}

typedef struct { vec3 lo, hi, albedo; } SceneBox;

static const SceneBox SCENE_BOXES[] = {
    {{-900.0f, 0.0f, -5200.0f}, {-400.0f, 1900.0f, -4700.0f}, {0.45f, 0.42f, 0.40f}},
    {{300.0f, 0.0f, -7400.0f}, {1100.0f, 2600.0f, -6600.0f}, {0.35f, 0.38f, 0.42f}},
    {{-3200.0f, 0.0f, -9000.0f}, {-2200.0f, 1200.0f, -8000.0f}, {0.40f, 0.36f, 0.30f}},
    {{2400.0f, 0.0f, -3600.0f}, {2800.0f, 700.0f, -3200.0f}, {0.50f, 0.45f, 0.38f}},
    {{-1800.0f, 0.0f, -2200.0f}, {-1600.0f, 420.0f, -2000.0f}, {0.55f, 0.50f, 0.45f}},
};

static inline vec3 scene_sky(vec3 d, vec3 sun, vec3 sun_color, float day) {
    float t, g;
    vec3 zenith = v3(0.18f, 0.33f, 0.75f), horizon = v3(0.65f, 0.75f, 0.9f), c;
    t = 1.0f - (d.y > 0.0f ? d.y : 0.0f);
    t = t * t * t * t;
    c = v3_add(v3_scale(zenith, 1.0f - t), v3_scale(horizon, t));
    g = v3_dot(d, sun);
    g = g > 0.0f ? powf(g, 32.0f) * 1.5f : 0.0f;
    return v3_scale(v3_add(v3_scale(c, day), v3_scale(sun_color, g)), 0.9f);
}

/* Ray vs axis-aligned box (slab test): the entry distance and normal, if hit in front. */
static inline int scene_box_hit(vec3 o, vec3 d, const SceneBox *b, float *t_out, vec3 *n_out) {
    float t0 = 0.0f, t1 = 1e30f;
    int axis, near_axis = -1;
    float sign = 0.0f;
    for (axis = 0; axis < 3; axis++) {
        float oa = axis == 0 ? o.x : axis == 1 ? o.y : o.z;
        float da = axis == 0 ? d.x : axis == 1 ? d.y : d.z;
        float lo = axis == 0 ? b->lo.x : axis == 1 ? b->lo.y : b->lo.z;
        float hi = axis == 0 ? b->hi.x : axis == 1 ? b->hi.y : b->hi.z;
        if (fabsf(da) < 1e-9f) {
            if (oa < lo || oa > hi) return 0;
        } else {
            float a = (lo - oa) / da, c = (hi - oa) / da, s = -1.0f;
            if (a > c) { float tmp = a; a = c; c = tmp; s = 1.0f; }
            if (a > t0) { t0 = a; near_axis = axis; sign = s; }
            if (c < t1) t1 = c;
            if (t0 > t1) return 0;
        }
    }
    if (near_axis < 0) return 0; /* inside the box */
    *t_out = t0;
    *n_out = v3(near_axis == 0 ? sign : 0.0f, near_axis == 1 ? sign : 0.0f, near_axis == 2 ? sign : 0.0f);
    return 1;
}

/* Fills `color` (w*h*4 floats, linear) and `depth` (w*h floats, 1 = sky) for a camera at
 * `eye` looking along `fwd` (unit) with vertical field of view `fov_y`; `view_proj` maps hits
 * to clip space for their depth. */
static inline void scene_render(float *color, float *depth, int w, int h, vec3 eye, vec3 fwd,
                                float fov_y, const float view_proj[16], vec3 sun, vec3 sun_color,
                                float sun_illuminance, const SceneShadows *shadows) {
    vec3 right = v3_norm(v3_cross(fwd, v3(0.0f, 1.0f, 0.0f)));
    vec3 up = v3_cross(right, fwd);
    float tan_half = tanf(0.5f * fov_y), aspect = (float)w / (float)h;
    float day = sun.y * 4.0f, light = sun_illuminance / 10.0f;
    vec3 ambient;
    int x, y;
    size_t i;
    day = day < 0.15f ? 0.15f : day > 1.0f ? 1.0f : day;
    /* Sky ambient 0.25 * day under a clear sky. Under clouds only the sky visibility V of it
     * gets through, and the clouds add their own light E (Nimbus's units: the sun gives an
     * irradiance of `illuminance`, which this scene draws as 0.06 * illuminance):
     * ambient = V * sky + 0.06 * E (docs/frame-outputs.md, "Ambient light at the camera"). */
    ambient = v3(0.25f * day, 0.25f * day, 0.25f * day);
    if (shadows && shadows->ambient) {
        const NimbusAmbientLight *a = shadows->ambient;
        ambient = v3_add(v3_scale(ambient, a->above_sky_visibility),
                         v3_scale(v3(a->above_cloud_irradiance[0], a->above_cloud_irradiance[1],
                                     a->above_cloud_irradiance[2]), 0.06f));
    }
    for (y = 0; y < h; y++) {
        for (x = 0; x < w; x++) {
            float nx = ((float)x + 0.5f) / (float)w * 2.0f - 1.0f;
            float ny = 1.0f - ((float)y + 0.5f) / (float)h * 2.0f;
            vec3 d = v3_norm(v3_add(fwd, v3_add(v3_scale(right, nx * tan_half * aspect), v3_scale(up, ny * tan_half))));
            float best = 1e30f;
            vec3 n = v3(0.0f, 1.0f, 0.0f), albedo = v3(0.0f, 0.0f, 0.0f), c;
            size_t b;
            i = (size_t)y * (size_t)w + (size_t)x;
            if (d.y < -1e-6f && eye.y > 0.0f) {
                float t = -eye.y / d.y;
                vec3 p = v3_add(eye, v3_scale(d, t));
                int checker = ((int)floorf(p.x / 400.0f) + (int)floorf(p.z / 400.0f)) & 1;
                best = t;
                albedo = checker ? v3(0.16f, 0.22f, 0.10f) : v3(0.20f, 0.26f, 0.12f);
            }
            for (b = 0; b < sizeof SCENE_BOXES / sizeof SCENE_BOXES[0]; b++) {
                float t;
                vec3 nb;
                if (scene_box_hit(eye, d, &SCENE_BOXES[b], &t, &nb) && t < best) {
                    best = t;
                    n = nb;
                    albedo = SCENE_BOXES[b].albedo;
                }
            }
            if (best < 1e29f) {
                vec3 hit = v3_add(eye, v3_scale(d, best)), ndc;
                float lambert = v3_dot(n, sun), fog = 1.0f - expf(-best / 40000.0f);
                lambert = lambert > 0.0f ? lambert * scene_sun_visibility(shadows, hit) : 0.0f;
                c = v3_mul(albedo, v3_add(ambient, v3_scale(v3(1.0f, 1.0f, 1.0f), 0.6f * lambert * light)));
                c = v3_add(v3_scale(c, 1.0f - fog), v3_scale(scene_sky(v3(d.x, 0.05f, d.z), sun, sun_color, day), fog));
                mat_project(view_proj, hit, &ndc);
                depth[i] = ndc.z < 0.0f ? 0.0f : ndc.z > 1.0f ? 1.0f : ndc.z;
            } else {
                c = scene_sky(d, sun, sun_color, day);
                depth[i] = 1.0f;
            }
            color[i * 4 + 0] = c.x; color[i * 4 + 1] = c.y; color[i * 4 + 2] = c.z; color[i * 4 + 3] = 1.0f;
        }
    }
}

#endif
