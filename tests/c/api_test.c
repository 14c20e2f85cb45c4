/* C API tests: every kind of bad input gets its documented code and a message in the
 * documented place, successes leave the messages empty, and the context stays usable.
 * Built with -std=c99 -Wall -Wextra -Werror -pedantic, under AddressSanitizer + UBSan and
 * under valgrind. Needs a library built with the `test-hooks` feature (NIMBUS_TEST_HOOKS).
 * Ends with "N passed, N failed" and the number of distinct bad-input cases. */
#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nimbus.h"
#include "camera.h"

#ifdef NIMBUS_TEST_HOOKS
/* Test hooks: exported only by a library built with the `test-hooks` feature; not in nimbus.h. */
NimbusResult nimbus_test_hook_panic(NimbusContext *ctx);
NimbusResult nimbus_test_hook_lose_device(NimbusContext *ctx);
#endif

/* Struct layouts are part of the ABI: pin sizes and every field's offset (64-bit targets),
 * the same numbers src/ffi/types.rs pins from the Rust side. */
#define PIN(name, cond) typedef char pin_##name[(cond) ? 1 : -1]
#define PIN_SIZE(type, size) PIN(size_##type, sizeof(type) == (size))
#define PIN_OFFSET(type, field, off) PIN(off_##type##_##field, offsetof(type, field) == (off))
PIN_SIZE(NimbusChainedStruct, 16);
PIN_SIZE(NimbusWindowHandle, 32);
PIN_SIZE(NimbusContextDesc, 32);
PIN_SIZE(NimbusSettingsExt, 48);
PIN_SIZE(NimbusQualityExt, 24);
PIN_SIZE(NimbusFrame, 176);
PIN_SIZE(NimbusTextureDesc, 24);
PIN_SIZE(NimbusTargets, 32);
PIN_SIZE(NimbusWeatherState, 96);
PIN_OFFSET(NimbusWeatherState, next, 0);
PIN_OFFSET(NimbusWeatherState, from_name, 8);
PIN_OFFSET(NimbusWeatherState, to_name, 40);
PIN_OFFSET(NimbusWeatherState, start, 72);
PIN_OFFSET(NimbusWeatherState, duration, 80);
PIN_OFFSET(NimbusWeatherState, progress, 88);
PIN_OFFSET(NimbusWeatherState, phase, 92);
PIN_OFFSET(NimbusChainedStruct, s_type, 0);
PIN_OFFSET(NimbusChainedStruct, next, 8);
PIN_OFFSET(NimbusWindowHandle, platform, 0);
PIN_OFFSET(NimbusWindowHandle, display, 8);
PIN_OFFSET(NimbusWindowHandle, window, 16);
PIN_OFFSET(NimbusWindowHandle, surface, 24);
PIN_OFFSET(NimbusContextDesc, next, 0);
PIN_OFFSET(NimbusContextDesc, abi_version, 8);
PIN_OFFSET(NimbusContextDesc, width, 12);
PIN_OFFSET(NimbusContextDesc, height, 16);
PIN_OFFSET(NimbusContextDesc, window, 24);
PIN_OFFSET(NimbusSettingsExt, chain, 0);
PIN_OFFSET(NimbusSettingsExt, initial_preset, 16);
PIN_OFFSET(NimbusSettingsExt, noise_seed, 20);
PIN_OFFSET(NimbusSettingsExt, march_max_steps, 24);
PIN_OFFSET(NimbusSettingsExt, march_min_steps, 28);
PIN_OFFSET(NimbusSettingsExt, jitter, 32);
PIN_OFFSET(NimbusSettingsExt, max_distance, 36);
PIN_OFFSET(NimbusSettingsExt, planet_radius, 40);
PIN_OFFSET(NimbusQualityExt, chain, 0);
PIN_OFFSET(NimbusQualityExt, quality, 16);
PIN_OFFSET(NimbusFrame, next, 0);
PIN_OFFSET(NimbusFrame, view, 8);
PIN_OFFSET(NimbusFrame, projection, 72);
PIN_OFFSET(NimbusFrame, depth_flags, 136);
PIN_OFFSET(NimbusFrame, sun_direction, 140);
PIN_OFFSET(NimbusFrame, sun_color, 152);
PIN_OFFSET(NimbusFrame, sun_illuminance, 164);
PIN_OFFSET(NimbusFrame, time, 168);
PIN_OFFSET(NimbusTextureDesc, next, 0);
PIN_OFFSET(NimbusTextureDesc, width, 8);
PIN_OFFSET(NimbusTextureDesc, height, 12);
PIN_OFFSET(NimbusTextureDesc, format, 16);
PIN_OFFSET(NimbusTargets, next, 0);
PIN_OFFSET(NimbusTargets, scene_color, 8);
PIN_OFFSET(NimbusTargets, scene_depth, 16);
PIN_OFFSET(NimbusTargets, output, 24);
PIN_SIZE(NimbusCloudShadowsExt, 40);
PIN_OFFSET(NimbusCloudShadowsExt, flags, 32);
PIN_OFFSET(NimbusCloudShadowsExt, reserved, 36);
PIN_OFFSET(NimbusCloudShadowsExt, extent, 16);
PIN_OFFSET(NimbusCloudShadowsExt, resolution, 20);
PIN_OFFSET(NimbusCloudShadowsExt, steps, 24);
PIN_OFFSET(NimbusCloudShadowsExt, update_slices, 28);
PIN_SIZE(NimbusFrameOutputs, 24);
PIN_OFFSET(NimbusFrameOutputs, version, 8);
PIN_OFFSET(NimbusFrameOutputs, grid_width, 12);
PIN_OFFSET(NimbusFrameOutputs, grid_height, 16);
PIN_OFFSET(NimbusFrameOutputs, has_cloud_shadows, 20);
PIN_SIZE(NimbusCloudShadowInfo, 104);
PIN_OFFSET(NimbusCloudShadowInfo, world_to_map, 8);
PIN_OFFSET(NimbusCloudShadowInfo, sun, 72);
PIN_OFFSET(NimbusCloudShadowInfo, resolution, 84);
PIN_OFFSET(NimbusCloudShadowInfo, window_origin, 88);
PIN_OFFSET(NimbusCloudShadowInfo, extent, 96);
PIN_OFFSET(NimbusCloudShadowInfo, reserved, 100);

/* Result codes are enum constants: arithmetic on them compiles. */
PIN(codes_are_constants, 0 - NIMBUS_ERROR_NULL_POINTER == 1);

static int passed = 0, failed = 0, bad_cases = 0;
static NimbusContext *ctx = NULL;

static int empty(const char *s) { return s == NULL || s[0] == '\0'; }

/* Checks a call's result and its messages: on failure the thread's message (last_error(NULL))
 * and, when `on` is given, the context's message are set (and contain `needle` if given); on
 * success both are empty. */
static void check(int32_t got, int32_t want, NimbusContext *on, const char *needle,
                  const char *what, int line) {
    const char *thread_msg = nimbus_context_last_error(NULL);
    const char *ctx_msg = on ? nimbus_context_last_error(on) : NULL;
    if (got != want) {
        printf("FAIL line %d: %s returned %s (%d), expected %s: %s\n", line, what,
               nimbus_result_name(got), got, nimbus_result_name(want), thread_msg);
        failed++;
        return;
    }
    if (want < 0) {
        bad_cases++;
        if (empty(thread_msg) || (on && empty(ctx_msg))) {
            printf("FAIL line %d: %s gave no message (thread: '%s', context: '%s')\n", line, what,
                   thread_msg, ctx_msg ? ctx_msg : "-");
            failed++;
            return;
        }
        if (on && strcmp(thread_msg, ctx_msg) != 0) {
            printf("FAIL line %d: %s: thread and context messages differ\n", line, what);
            failed++;
            return;
        }
        if (needle && !strstr(thread_msg, needle)) {
            printf("FAIL line %d: %s: message '%s' lacks '%s'\n", line, what, thread_msg, needle);
            failed++;
            return;
        }
        printf("ok   %-60s -> %-30s %s\n", what, nimbus_result_name(got), thread_msg);
    } else if (!empty(thread_msg) || (on && !empty(ctx_msg))) {
        printf("FAIL line %d: %s succeeded but a message remains: '%s'\n", line, what, thread_msg);
        failed++;
        return;
    }
    passed++;
}
/* EXPECT: a call whose errors land on the thread only (no context, or a NULL one). */
#define EXPECT(call, code) check((call), (code), NULL, NULL, #call, __LINE__)
/* EXPECT_ON: a call on context `c`; its errors land on the thread and on `c`. */
#define EXPECT_ON(c, call, code) check((call), (code), (c), NULL, #call, __LINE__)
#define EXPECT_MSG(c, call, code, needle) check((call), (code), (c), (needle), #call, __LINE__)
#define TRUE(cond) do { if (cond) passed++; else { printf("FAIL line %d: %s\n", __LINE__, #cond); failed++; } } while (0)

#define W 64
#define H 36

static NimbusTexture *scene, *output, *depth, *small_tex, *rgba32, *depth_rgba8;

static void frame_defaults(NimbusFrame *f) {
    vec3 sun = sun_from_angles(40.0f, 30.0f);
    memset(f, 0, sizeof *f);
    mat_look_at(f->view, v3(0.0f, 2.0f, 0.0f), v3(0.0f, 1000.0f, -1200.0f), v3(0.0f, 1.0f, 0.0f));
    mat_perspective(f->projection, 1.2f, (float)W / (float)H, 1.0f, 100000.0f);
    f->sun_direction[0] = sun.x; f->sun_direction[1] = sun.y; f->sun_direction[2] = sun.z;
    f->sun_illuminance = 10.0f;
}

static int32_t render_on(NimbusContext *c, NimbusTexture *color, NimbusTexture *out, double time) {
    NimbusFrame f;
    NimbusTargets t = {0};
    frame_defaults(&f);
    f.time = time;
    t.scene_color = color;
    t.output = out;
    return nimbus_context_render(c, &f, &t);
}

static int32_t render_ok(void) { return render_on(ctx, scene, output, 0.0); }

static NimbusTexture *make_texture_on(NimbusContext *c, uint32_t w, uint32_t h, uint32_t format) {
    NimbusTextureDesc d = {0};
    NimbusTexture *t = NULL;
    d.width = w; d.height = h; d.format = format;
    if (nimbus_texture_create(c, &d, &t) != NIMBUS_OK) {
        printf("could not create a %ux%u texture: %s\n", w, h, nimbus_context_last_error(c));
        exit(1);
    }
    return t;
}

static NimbusTexture *make_texture(uint32_t w, uint32_t h, uint32_t format) {
    return make_texture_on(ctx, w, h, format);
}

/* ---- log callback: counts messages, sees panics, and calls back into Nimbus ---------------- */
static int log_count = 0, log_panics = 0, log_reentered = 0;

static void log_cb(int32_t level, const char *message, void *user) {
    log_count++;
    if (level == 1 && strstr(message, "panic")) log_panics++;
    if (!log_reentered) {
        /* Re-entering from the callback used to deadlock on the library's log lock. */
        log_reentered = 1;
        (void)nimbus_set_log_callback(log_cb, user, 4);
        (void)nimbus_result_name(NIMBUS_OK);
    }
}

static void test_results_and_versions(void) {
    TRUE(strcmp(nimbus_result_name(NIMBUS_ERROR_NULL_POINTER), "NIMBUS_ERROR_NULL_POINTER") == 0);
    TRUE(strcmp(nimbus_result_name(NIMBUS_ERROR_DEVICE_LOST), "NIMBUS_ERROR_DEVICE_LOST") == 0);
    TRUE(strcmp(nimbus_result_name(12345), "NIMBUS_UNKNOWN_RESULT") == 0);
    TRUE(!empty(nimbus_result_message(NIMBUS_ERROR_INVALID_TARGET)));
    TRUE(!empty(nimbus_result_message(-7777)));
    TRUE(nimbus_version() == ((NIMBUS_VERSION_MAJOR << 16) | (NIMBUS_VERSION_MINOR << 8) | NIMBUS_VERSION_PATCH));
    TRUE(NIMBUS_ABI_VERSION == ((NIMBUS_VERSION_MAJOR << 16) | NIMBUS_VERSION_MINOR));
    TRUE(NIMBUS_ABI_MIN_MINOR >= 1 && NIMBUS_ABI_MIN_MINOR <= NIMBUS_VERSION_MINOR);
    {
        char want[32];
        sprintf(want, "%d.%d.%d", NIMBUS_VERSION_MAJOR, NIMBUS_VERSION_MINOR, NIMBUS_VERSION_PATCH);
        TRUE(strcmp(nimbus_version_string(), want) == 0);
    }
    TRUE(nimbus_context_adapter_name(NULL) == NULL);
    EXPECT(nimbus_set_log_callback(log_cb, NULL, 9), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_set_log_callback(log_cb, NULL, -1), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_set_log_callback(log_cb, NULL, 4), NIMBUS_OK);
}

/* Since ABI 0.6: the noise cache. Exported by test_noise_cache (or read from the file given
 * with --noise-cache, and written there when the file did not exist), chained to the later
 * creations, which then upload the volumes instead of baking them (valgrind runs the whole
 * matrix this way: baking under valgrind takes many minutes). */
static unsigned char *noise_cache = NULL;
static size_t noise_cache_size = 0;
static int noise_cache_loaded = 0;

/* Chains the exported cache in `nc` (flags 0) to `desc`, in front of what it holds. */
static void chain_noise_cache(NimbusContextDesc *desc, NimbusNoiseCacheExt *nc) {
    memset(nc, 0, sizeof *nc);
    nc->chain.s_type = NIMBUS_STYPE_NOISE_CACHE;
    nc->chain.next = desc->next;
    nc->data = noise_cache;
    nc->size = noise_cache_size;
    desc->next = &nc->chain;
}

static void test_create(void) {
    NimbusContextDesc desc = {0};
    NimbusContext *out = (NimbusContext *)&desc; /* must stay untouched on failure */
    NimbusContext *before = out;
    NimbusChainedStruct unknown = {999, NULL};
    NimbusSettingsExt s = {0}, s2 = {0};
    NimbusQualityExt q = {0};
    NimbusCloudShadowsExt cs = {0};
    NimbusNoiseCacheExt nc;
    NimbusCloudShadowInfo info;
    NimbusWindowHandle win = {0};

    EXPECT(nimbus_context_create(NULL, &out), NIMBUS_ERROR_NULL_POINTER);
    desc.abi_version = NIMBUS_ABI_VERSION;
    EXPECT(nimbus_context_create(&desc, NULL), NIMBUS_ERROR_NULL_POINTER);
    /* The ABI rule: same major, minor from NIMBUS_ABI_MIN_MINOR to ours; never 0. */
    desc.abi_version = 0;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION, "abi_version is 0");
    desc.abi_version = NIMBUS_ABI_VERSION + (1u << 16);
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = NIMBUS_ABI_VERSION + 1; /* a newer minor: may use unknown structs */
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = (NIMBUS_VERSION_MAJOR << 16) | (NIMBUS_ABI_MIN_MINOR - 1);
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &unknown;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT);
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    s.chain.next = &unknown;
    desc.next = &s.chain;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT);
    s2.chain.s_type = NIMBUS_STYPE_SETTINGS;
    s.chain.next = &s2.chain; /* the same extension twice */
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT, "twice");
    s.chain.next = NULL;
    s.jitter = 7;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.jitter = 0;
    s.initial_preset = 99;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.initial_preset = 0;
    s.march_min_steps = 500; /* above the default maximum of 96 */
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS, "march.min_steps");
    s.march_min_steps = 0;
    s.march_max_steps = 2000;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.march_max_steps = 0;
    s.planet_radius = -5.0f;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.planet_radius = NAN;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.planet_radius = -1e30f;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    TRUE(strlen(nimbus_context_last_error(NULL)) < 200); /* huge numbers print short */
    s.planet_radius = 0.0f;
    s.max_distance = -1.0f;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.max_distance = 0.0f;
    q.chain.s_type = NIMBUS_STYPE_QUALITY;
    q.quality = 5; /* levels are 0 (default) and 1..4 */
    s.chain.next = &q.chain;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT, "quality");
    q.quality = NIMBUS_QUALITY_HIGH;
    desc.window = &win;
    desc.width = 64; desc.height = 64;
    win.platform = 42;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    win.platform = NIMBUS_PLATFORM_X11;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    win.platform = NIMBUS_PLATFORM_WAYLAND;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    win.platform = NIMBUS_PLATFORM_WIN32;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT); /* HWND 0 */
    win.platform = NIMBUS_PLATFORM_APPKIT;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    desc.width = 0;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    TRUE(out == before); /* out untouched on every failure */
    desc.window = NULL;
    /* Since ABI 0.5: the cloud shadow map, its ranges checked like every setting. */
    cs.chain.s_type = NIMBUS_STYPE_CLOUD_SHADOWS;
    q.chain.next = &cs.chain;
    cs.resolution = 300;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS, "shadows.resolution");
    cs.resolution = 32;
    cs.extent = NAN;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS, "shadows.extent");
    cs.extent = 8000.0f;
    cs.update_slices = 99;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS, "shadows.update_slices");
    cs.update_slices = 1;
    cs.flags = 0x80;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT, "flags");
    cs.flags = NIMBUS_CLOUD_SHADOWS_MARCH_LIGHT;
    cs.reserved = 1;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT, "reserved");
    cs.reserved = 0;
    TRUE(out == before);
    /* The quality level first; the explicit step counts refine it. */
    s.march_max_steps = 64; s.march_min_steps = 32; s.jitter = NIMBUS_JITTER_OFF;
    if (noise_cache_loaded) {
        /* A file from an older build may be stale: then it is ignored and exported anew. */
        chain_noise_cache(&desc, &nc);
        nc.flags = NIMBUS_NOISE_CACHE_FALLBACK;
    }
    log_count = 0;
    EXPECT_ON(NULL, nimbus_context_create(&desc, &ctx), NIMBUS_OK);
    if (ctx && noise_cache_loaded) {
        uint32_t used = 0;
        EXPECT_ON(ctx, nimbus_context_noise_from_cache(ctx, &used), NIMBUS_OK);
        if (!used) {
            printf("the noise cache file is stale (another bake): ignored, written anew\n");
            free(noise_cache);
            noise_cache = NULL;
            noise_cache_loaded = 0;
        }
    }
    TRUE(log_count > 0); /* wgpu's device creation logs at debug level */
    TRUE(log_reentered);
    /* No frame yet: no map to report. */
    memset(&info, 0, sizeof info);
    EXPECT_MSG(ctx, nimbus_context_cloud_shadows(ctx, &info), NIMBUS_ERROR_NOT_READY, "render a frame");
}

/* Since ABI 0.5: the cloud shadow map's matrix and texels after a frame. */
static void test_cloud_shadows(void) {
    NimbusCloudShadowInfo info;
    NimbusChainedStruct unknown = {999, NULL};
    float *texels;
    size_t n, i, bad = 0, count;
    float u, v, cam[3] = {0.0f, 2.0f, 0.0f};
    const float *m;

    EXPECT_ON(ctx, render_ok(), NIMBUS_OK);
    memset(&info, 0, sizeof info);
    EXPECT(nimbus_context_cloud_shadows(NULL, &info), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_cloud_shadows(ctx, NULL), NIMBUS_ERROR_NULL_POINTER);
    info.next = &unknown;
    EXPECT_ON(ctx, nimbus_context_cloud_shadows(ctx, &info), NIMBUS_ERROR_UNKNOWN_STRUCT);
    info.next = NULL;
    EXPECT_ON(ctx, nimbus_context_cloud_shadows(ctx, &info), NIMBUS_OK);
    TRUE(info.resolution == 32 && info.extent == 8000.0f && info.reserved == 0);
    /* The camera sits inside the square the map covers, near its middle. */
    m = info.world_to_map;
    u = m[0] * cam[0] + m[4] * cam[1] + m[8] * cam[2] + m[12] - info.window_origin[0];
    v = m[1] * cam[0] + m[5] * cam[1] + m[9] * cam[2] + m[13] - info.window_origin[1];
    TRUE(u > 0.4f && u < 0.6f && v > 0.4f && v < 0.6f);
    n = (size_t)info.resolution;
    count = 4 * n * n;
    texels = malloc(count * sizeof *texels);
    if (!texels) return;
    EXPECT(nimbus_context_read_cloud_shadows(NULL, texels, count), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_read_cloud_shadows(ctx, NULL, count), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_MSG(ctx, nimbus_context_read_cloud_shadows(ctx, texels, count - 4), NIMBUS_ERROR_INVALID_TARGET, "float_count");
    EXPECT_ON(ctx, nimbus_context_read_cloud_shadows(ctx, texels, count), NIMBUS_OK);
    /* Every texel: transmittance in [0, 1] and exp(-optical depth). */
    for (i = 0; i < n * n; i++) {
        float tau = texels[4 * i + 2], t = texels[4 * i + 3];
        if (!(t >= 0.0f && t <= 1.0f && tau >= 0.0f && fabsf(t - expf(-tau)) < 2e-3f)) bad++;
    }
    TRUE(bad == 0);
    free(texels);

    /* The frame outputs: version, grid, and per grid pixel (T, front depth, depth, 0). */
    {
        NimbusFrameOutputs fo;
        uint32_t view = 0;
        float *px;
        memset(&fo, 0, sizeof fo);
        EXPECT(nimbus_context_frame_outputs(NULL, NIMBUS_VIEW_DEFAULT, &fo), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_ON(ctx, nimbus_context_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, NULL), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_MSG(ctx, nimbus_context_frame_outputs(ctx, 0xdeadbeefu, &fo), NIMBUS_ERROR_INVALID_ARGUMENT, "view");
        EXPECT_ON(ctx, nimbus_context_create_view(ctx, &view), NIMBUS_OK);
        EXPECT_MSG(ctx, nimbus_context_frame_outputs(ctx, view, &fo), NIMBUS_ERROR_NOT_READY, "not rendered");
        EXPECT_ON(ctx, nimbus_context_destroy_view(ctx, view), NIMBUS_OK);
        fo.next = &unknown;
        EXPECT_ON(ctx, nimbus_context_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, &fo), NIMBUS_ERROR_UNKNOWN_STRUCT);
        fo.next = NULL;
        EXPECT_ON(ctx, nimbus_context_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, &fo), NIMBUS_OK);
        TRUE(fo.version == NIMBUS_FRAME_OUTPUTS_VERSION && fo.has_cloud_shadows == 1);
        TRUE(fo.grid_width > 0 && fo.grid_width <= W && fo.grid_height > 0 && fo.grid_height <= H);
        count = 4 * (size_t)fo.grid_width * fo.grid_height;
        px = malloc(count * sizeof *px);
        if (!px) return;
        EXPECT_MSG(ctx, nimbus_context_read_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, px, count + 4), NIMBUS_ERROR_INVALID_TARGET, "float_count");
        EXPECT(nimbus_context_read_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, NULL, count), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_ON(ctx, nimbus_context_read_frame_outputs(ctx, NIMBUS_VIEW_DEFAULT, px, count), NIMBUS_OK);
        bad = 0;
        for (i = 0; i < count / 4; i++) {
            float t = px[4 * i], front = px[4 * i + 1], d = px[4 * i + 2];
            /* T in [0, 1]; no cloud means no depths; a cloud's front is not behind its depth. */
            if (!(t >= 0.0f && t <= 1.0f) || (d == 0.0f) != (front == 0.0f) || front > d + 1.0f) bad++;
        }
        TRUE(bad == 0);
        free(px);
    }

    /* Since ABI 0.7: the ambient light at the camera, above and below. */
    {
        NimbusAmbientLight al;
        uint32_t view = 0;
        int k;
        memset(&al, 0, sizeof al);
        EXPECT(nimbus_context_read_ambient_light(NULL, NIMBUS_VIEW_DEFAULT, &al), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_ON(ctx, nimbus_context_read_ambient_light(ctx, NIMBUS_VIEW_DEFAULT, NULL), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_MSG(ctx, nimbus_context_read_ambient_light(ctx, 0xdeadbeefu, &al), NIMBUS_ERROR_INVALID_ARGUMENT, "view");
        EXPECT_ON(ctx, nimbus_context_create_view(ctx, &view), NIMBUS_OK);
        EXPECT_MSG(ctx, nimbus_context_read_ambient_light(ctx, view, &al), NIMBUS_ERROR_NOT_READY, "not rendered");
        EXPECT_ON(ctx, nimbus_context_destroy_view(ctx, view), NIMBUS_OK);
        EXPECT_MSG(ctx, nimbus_context_read_ambient_light(ctx, view, &al), NIMBUS_ERROR_INVALID_ARGUMENT, "view");
        al.next = &unknown;
        EXPECT_ON(ctx, nimbus_context_read_ambient_light(ctx, NIMBUS_VIEW_DEFAULT, &al), NIMBUS_ERROR_UNKNOWN_STRUCT);
        al.next = NULL;
        EXPECT_ON(ctx, nimbus_context_read_ambient_light(ctx, NIMBUS_VIEW_DEFAULT, &al), NIMBUS_OK);
        TRUE(al.next == NULL);
        /* A camera on the ground under clouds: some sky hidden above, none below. */
        TRUE(al.above_sky_visibility >= 0.0f && al.above_sky_visibility < 1.0f);
        TRUE(al.below_sky_visibility == 1.0f);
        for (k = 0; k < 3; k++) {
            TRUE(isfinite(al.above_cloud_irradiance[k]) && al.above_cloud_irradiance[k] > 0.0f);
            TRUE(al.below_cloud_irradiance[k] == 0.0f);
        }
    }
}

static void test_noise_cache(void) {
    NimbusContextDesc desc = {0};
    NimbusNoiseCacheExt nc;
    NimbusSettingsExt s = {0};
    NimbusContext *c = NULL, *before = (NimbusContext *)&desc;
    size_t size = 0, expected = 48 + 4 * ((size_t)128 * 128 * 128 + 32 * 32 * 32);
    uint32_t from_cache = 7;
    unsigned char keep, *exported;

    EXPECT(nimbus_context_export_noise_cache(NULL, NULL, 0, &size), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_export_noise_cache(ctx, NULL, 0, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_export_noise_cache(ctx, NULL, 0, &size), NIMBUS_OK);
    TRUE(size == expected);
    exported = malloc(size);
    if (!exported) return;
    size = 0;
    EXPECT_MSG(ctx, nimbus_context_export_noise_cache(ctx, exported, expected - 1, &size), NIMBUS_ERROR_INVALID_TARGET, "capacity");
    TRUE(size == expected);
    EXPECT_ON(ctx, nimbus_context_export_noise_cache(ctx, exported, expected, &size), NIMBUS_OK);
    TRUE(memcmp(exported, "NIMBUSNC", 8) == 0);
    EXPECT(nimbus_context_noise_from_cache(NULL, &from_cache), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_noise_from_cache(ctx, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_noise_from_cache(ctx, &from_cache), NIMBUS_OK);
    if (noise_cache_loaded) {
        /* ctx uploaded the file's cache: exporting it gives those bytes back. */
        TRUE(from_cache == 1);
        TRUE(size == noise_cache_size && memcmp(exported, noise_cache, size) == 0);
        free(exported);
    } else {
        TRUE(from_cache == 0); /* ctx baked its volumes */
        noise_cache = exported;
        noise_cache_size = size;
    }

    /* Refused before any device work: bad fields, another seed, a damaged byte, an old header. */
    desc.abi_version = NIMBUS_ABI_VERSION;
    chain_noise_cache(&desc, &nc);
    nc.flags = 0x80;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_INVALID_ARGUMENT, "flags");
    nc.flags = 0;
    nc.reserved = 1;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_INVALID_ARGUMENT, "reserved");
    nc.reserved = 0;
    nc.data = NULL;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_NULL_POINTER, "data");
    nc.data = noise_cache;
    nc.size = 0;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_INVALID_ARGUMENT, "size");
    nc.size = noise_cache_size - 1;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_NOISE_CACHE, "truncated");
    nc.size = noise_cache_size;
    keep = noise_cache[100000];
    noise_cache[100000] ^= 1;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_NOISE_CACHE, "checksum");
    noise_cache[100000] = keep;
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    s.noise_seed = 2;
    nc.chain.next = &s.chain;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_NOISE_CACHE, "seed 2");
    nc.chain.next = NULL;
    desc.abi_version = (NIMBUS_VERSION_MAJOR << 16) | 5u;
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_UNKNOWN_STRUCT, "ABI 0.6");
    TRUE(c == NULL && before == (NimbusContext *)&desc);
    /* The cache is only read during the creation: later contexts use it (test_second_context). */
}

/* Since ABI 0.5: CPU queries, from two threads at once. */
struct query_worker { NimbusCloudQuery *q; float result; int failures; };
static void *query_frames(void *arg) {
    struct query_worker *w = (struct query_worker *)arg;
    float a[3] = {100.0f, 0.0f, -300.0f}, b[3] = {100.0f, 9000.0f, -300.0f};
    int i;
    for (i = 0; i < 200; i++)
        if (nimbus_cloud_query_transmittance(w->q, a, b, 12.5, &w->result) != NIMBUS_OK) w->failures++;
    return NULL;
}

static void test_cloud_query(void) {
    NimbusCloudQuery *q = NULL;
    float p[3] = {0.0f, 2000.0f, -4000.0f}, up[3] = {0.0f, 9000.0f, -4000.0f}, nan_p[3] = {0.0f, NAN, 0.0f};
    float v = -1.0f, again = -2.0f;
    EXPECT(nimbus_context_create_cloud_query(NULL, &q), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_create_cloud_query(ctx, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_create_cloud_query(ctx, &q), NIMBUS_OK);
    if (!q) return;
    EXPECT(nimbus_cloud_query_density(q, p, 0.0, &v), NIMBUS_OK);
    TRUE(v >= 0.0f && isfinite(v));
    EXPECT(nimbus_cloud_query_density(q, p, 0.0, &again), NIMBUS_OK);
    TRUE(v == again); /* same point, same time: same answer */
    EXPECT(nimbus_cloud_query_transmittance(q, p, up, 0.0, &v), NIMBUS_OK);
    TRUE(v >= 0.0f && v <= 1.0f);
    EXPECT(nimbus_cloud_query_coverage_above(q, p, 0.0, &v), NIMBUS_OK);
    TRUE(v >= 0.0f && v <= 1.0f);
    EXPECT(nimbus_cloud_query_density(NULL, p, 0.0, &v), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_cloud_query_density(q, NULL, 0.0, &v), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_cloud_query_density(q, p, 0.0, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_MSG(NULL, nimbus_cloud_query_density(q, nan_p, 0.0, &v), NIMBUS_ERROR_INVALID_ARGUMENT, "finite");
    EXPECT_MSG(NULL, nimbus_cloud_query_density(q, p, NAN, &v), NIMBUS_ERROR_INVALID_ARGUMENT, "time");
    EXPECT(nimbus_cloud_query_transmittance(q, p, NULL, 0.0, &v), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_cloud_query_transmittance(q, nan_p, up, 0.0, &v), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_cloud_query_coverage_above(q, p, INFINITY, &v), NIMBUS_ERROR_INVALID_ARGUMENT);
    {
        pthread_t ta, tb;
        struct query_worker wa, wb;
        wa.q = q; wa.failures = 0; wb.q = q; wb.failures = 0;
        pthread_create(&ta, NULL, query_frames, &wa);
        pthread_create(&tb, NULL, query_frames, &wb);
        pthread_join(ta, NULL);
        pthread_join(tb, NULL);
        TRUE(wa.failures == 0 && wb.failures == 0 && wa.result == wb.result);
    }
    nimbus_cloud_query_destroy(q);
    nimbus_cloud_query_destroy(NULL);
}

static void test_textures(void) {
    NimbusTextureDesc d = {0};
    NimbusTexture *t = NULL;
    NimbusChainedStruct unknown = {999, NULL};
    float buf[W * H * 4];
    size_t size = 0;

    EXPECT_ON(ctx, nimbus_texture_create(ctx, NULL, &t), NIMBUS_ERROR_NULL_POINTER);
    d.width = W; d.height = H; d.format = NIMBUS_FORMAT_RGBA16_FLOAT;
    EXPECT(nimbus_texture_create(NULL, &d, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, NULL), NIMBUS_ERROR_NULL_POINTER);
    d.format = 99;
    EXPECT_MSG(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "format");
    d.format = 0;
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.format = NIMBUS_FORMAT_RGBA16_FLOAT; d.width = 0;
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.width = 100000;
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.width = W; d.height = 0;
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.height = H; d.next = &unknown;
    EXPECT_ON(ctx, nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    TRUE(t == NULL); /* out untouched on failure */

    scene = make_texture(W, H, NIMBUS_FORMAT_RGBA32_FLOAT);
    output = make_texture(W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    depth = make_texture(W, H, NIMBUS_FORMAT_R32_FLOAT);
    small_tex = make_texture(W / 2, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    rgba32 = make_texture(W, H, NIMBUS_FORMAT_RGBA32_FLOAT);
    depth_rgba8 = make_texture(W, H, NIMBUS_FORMAT_RGBA8_UNORM);

    /* Texture calls take no context: their messages are the thread's. */
    EXPECT(nimbus_texture_byte_size(scene, &size), NIMBUS_OK);
    TRUE(size == sizeof buf);
    EXPECT(nimbus_texture_byte_size(NULL, &size), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_byte_size(scene, NULL), NIMBUS_ERROR_NULL_POINTER);
    memset(buf, 0, sizeof buf);
    EXPECT_MSG(NULL, nimbus_texture_write(scene, buf, sizeof buf - 4), NIMBUS_ERROR_INVALID_TARGET, "bytes");
    EXPECT(nimbus_texture_write(scene, buf, 0), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_write(scene, NULL, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_write(NULL, buf, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_read(scene, buf, 17), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_read(scene, buf, (size_t)-1), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_read(scene, NULL, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_read(NULL, buf, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    {
        int i;
        for (i = 0; i < W * H; i++) { buf[i * 4] = 0.2f; buf[i * 4 + 1] = 0.3f; buf[i * 4 + 2] = 0.6f; buf[i * 4 + 3] = 1.0f; }
    }
    EXPECT(nimbus_texture_write(scene, buf, sizeof buf), NIMBUS_OK);
    memset(buf, 0, sizeof buf);
    EXPECT(nimbus_texture_read(scene, buf, sizeof buf), NIMBUS_OK);
    TRUE(buf[1] == 0.3f);
    nimbus_texture_destroy(NULL); /* no-op */
}

/* How many pixels of the left (left != 0) or right half differ between two images. */
static size_t changed_in_half(const uint32_t *a, const uint32_t *b, int left) {
    size_t i, n = 0;
    for (i = 0; i < W * H; i++)
        if (((i % W) < W / 2) == (left != 0) && a[i] != b[i]) n++;
    return n;
}

/* Since ABI 0.3: BGRA8 (+ sRGB), RGB10A2 and (where renderable) RG11B10 color, and a real
 * D16 depth buffer, on the owned-texture path. Each color format is composited in place over a
 * D16 depth whose near half occludes: those pixels must come back unchanged. */
static void test_owned_formats(void) {
    static const uint32_t colors[] = {NIMBUS_FORMAT_BGRA8_UNORM, NIMBUS_FORMAT_BGRA8_UNORM_SRGB,
                                      NIMBUS_FORMAT_RGB10A2_UNORM, NIMBUS_FORMAT_RG11B10_UFLOAT};
    static uint16_t depth16[W * H];
    static uint32_t pixels[W * H], back[W * H];
    NimbusTexture *d16 = make_texture(W, H, NIMBUS_FORMAT_DEPTH16_UNORM), *c;
    NimbusTextureDesc desc = {0};
    NimbusFrame f;
    NimbusTargets t = {0};
    size_t size = 0, i, k;
    int32_t rc;

    EXPECT(nimbus_texture_byte_size(d16, &size), NIMBUS_OK);
    TRUE(size == sizeof depth16);
    /* Left half: depth 0.5 of a near = 1 m projection, about 2 m away (occluding everything);
     * right half: the far plane (sky). */
    for (i = 0; i < W * H; i++) depth16[i] = (i % W) < W / 2 ? 32768 : 65535;
    EXPECT(nimbus_texture_write(d16, depth16, sizeof depth16), NIMBUS_OK);
    frame_defaults(&f);
    t.scene_depth = d16;
    for (k = 0; k < sizeof colors / sizeof colors[0]; k++) {
        desc.width = W; desc.height = H; desc.format = colors[k];
        c = NULL;
        rc = nimbus_texture_create(ctx, &desc, &c);
        if (colors[k] == NIMBUS_FORMAT_RG11B10_UFLOAT && rc == NIMBUS_ERROR_INVALID_TARGET) {
            TRUE(strstr(nimbus_context_last_error(ctx), "RG11B10") != NULL); /* not renderable here */
            continue;
        }
        EXPECT_ON(ctx, rc, NIMBUS_OK);
        if (!c) continue;
        for (i = 0; i < W * H; i++) pixels[i] = 0x40506070u + (uint32_t)(i % 7);
        EXPECT(nimbus_texture_write(c, pixels, sizeof pixels), NIMBUS_OK);
        t.scene_color = c; t.output = c; /* in place */
        EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
        EXPECT(nimbus_texture_read(c, back, sizeof back), NIMBUS_OK);
        TRUE(changed_in_half(back, pixels, 1) == 0);
        TRUE(changed_in_half(back, pixels, 0) > 0); /* the sky half got its clouds */
        /* A depth format as color, a color format as depth. */
        t.scene_color = d16; t.output = c;
        EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "NIMBUS_FORMAT_DEPTH16_UNORM");
        t.scene_color = c; t.scene_depth = c;
        EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.scene_depth");
        t.scene_depth = d16;
        nimbus_texture_destroy(c);
    }
    EXPECT(nimbus_texture_write(d16, depth16, sizeof depth16 - 2), NIMBUS_ERROR_INVALID_TARGET);

    /* Since ABI 0.3: a viewport (the right half) chained to the targets; the left half stays. */
    {
        NimbusViewportExt vp;
        memset(&vp, 0, sizeof vp);
        vp.chain.s_type = NIMBUS_STYPE_VIEWPORT;
        vp.x = W / 2; vp.y = 0; vp.width = W / 2; vp.height = H;
        desc.width = W; desc.height = H; desc.format = NIMBUS_FORMAT_BGRA8_UNORM;
        c = NULL;
        EXPECT_ON(ctx, nimbus_texture_create(ctx, &desc, &c), NIMBUS_OK);
        if (c) {
            for (i = 0; i < W * H; i++) pixels[i] = 0x40506070u;
            EXPECT(nimbus_texture_write(c, pixels, sizeof pixels), NIMBUS_OK);
            t.scene_color = c; t.output = c; t.scene_depth = NULL; t.next = &vp.chain;
            EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
            EXPECT(nimbus_texture_read(c, back, sizeof back), NIMBUS_OK);
            TRUE(changed_in_half(back, pixels, 1) == 0);
            TRUE(changed_in_half(back, pixels, 0) > 0);
            vp.x = W / 2 + 1;
            EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "viewport");
            vp.x = 0; vp.height = 0;
            EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "viewport");
            t.next = NULL;
            nimbus_texture_destroy(c);
        }
    }
    nimbus_texture_destroy(d16);
}

/* Since ABI 0.4: views. A probe view at a quarter of the pixels renders between the default
 * view's frames with its own history and textures; ids are checked. */
static void test_views(void) {
    NimbusTexture *probe = make_texture(W / 2, H / 2, NIMBUS_FORMAT_RGBA16_FLOAT);
    NimbusFrame f;
    NimbusTargets t = {0};
    NimbusViewExt ve, twice;
    uint32_t view = 0, gone = 0;
    uint64_t main_bytes = 0, probe_bytes = 0, before = 0, shared = 0;
    int i;

    EXPECT(nimbus_context_create_view(NULL, &view), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_create_view(ctx, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_create_view(ctx, &view), NIMBUS_OK);
    TRUE(view != NIMBUS_VIEW_DEFAULT);
    EXPECT_ON(ctx, nimbus_context_view_memory(ctx, view, &before, NULL), NIMBUS_OK);
    memset(&ve, 0, sizeof ve);
    ve.chain.s_type = NIMBUS_STYPE_VIEW;
    ve.view = view;
    frame_defaults(&f);
    for (i = 0; i < 4; i++) {
        f.next = &ve.chain; t.scene_color = probe; t.output = probe;
        EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
        f.next = NULL; t.scene_color = scene; t.output = output;
        EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    }
    EXPECT_ON(ctx, nimbus_context_view_memory(ctx, view, &probe_bytes, &shared), NIMBUS_OK);
    EXPECT_ON(ctx, nimbus_context_view_memory(ctx, NIMBUS_VIEW_DEFAULT, &main_bytes, NULL), NIMBUS_OK);
    printf("     views: shared %llu B, default view %llu B (%dx%d), probe view %llu B (%dx%d)\n",
           (unsigned long long)shared, (unsigned long long)main_bytes, W, H,
           (unsigned long long)probe_bytes, W / 2, H / 2);
    TRUE(probe_bytes > before && shared > 0);
    TRUE(probe_bytes * 3 < main_bytes && probe_bytes * 5 > main_bytes);
    EXPECT(nimbus_context_view_memory(ctx, view, NULL, &shared), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_reset_view_history(ctx, view), NIMBUS_OK);

    /* Bad chains and ids. */
    f.next = &ve.chain; t.scene_color = probe; t.output = probe;
    ve.reserved = 1;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "reserved");
    ve.reserved = 0;
    twice = ve;
    ve.chain.next = &twice.chain;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT, "more than once");
    ve.chain.next = NULL;
    ve.view = 0xdeadbeefu;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "not a live view");
    gone = view;
    EXPECT_ON(ctx, nimbus_context_destroy_view(ctx, view), NIMBUS_OK);
    ve.view = gone;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "not a live view");
    EXPECT_MSG(ctx, nimbus_context_destroy_view(ctx, gone), NIMBUS_ERROR_INVALID_ARGUMENT, "not a live view");
    EXPECT_MSG(ctx, nimbus_context_reset_view_history(ctx, gone), NIMBUS_ERROR_INVALID_ARGUMENT, "not a live view");
    EXPECT_MSG(ctx, nimbus_context_view_memory(ctx, gone, &probe_bytes, NULL), NIMBUS_ERROR_INVALID_ARGUMENT, "view");
    EXPECT_MSG(ctx, nimbus_context_destroy_view(ctx, NIMBUS_VIEW_DEFAULT), NIMBUS_ERROR_INVALID_ARGUMENT, "default view");
    EXPECT_ON(ctx, nimbus_context_create_view(ctx, &view), NIMBUS_OK);
    TRUE(view != gone); /* the slot is reused, the id is not */
    EXPECT_ON(ctx, nimbus_context_destroy_view(ctx, view), NIMBUS_OK);
    /* The context still renders its default view. */
    f.next = NULL; t.scene_color = scene; t.output = output;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    nimbus_texture_destroy(probe);
}

static void test_render(void) {
    NimbusFrame f;
    NimbusTargets t = {0};
    NimbusChainedStruct unknown = {999, NULL};

    frame_defaults(&f);
    t.scene_color = scene; t.output = output;
    EXPECT(nimbus_context_render(NULL, &f, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_render(ctx, NULL, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, NULL), NIMBUS_ERROR_NULL_POINTER);
    t.scene_color = NULL;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_NULL_POINTER);
    t.scene_color = scene;
    t.output = NULL;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "no window");
    t.output = small_tex;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "32x36");
    t.output = rgba32; t.scene_color = rgba32;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "NIMBUS_FORMAT_RGBA32_FLOAT");
    TRUE(strstr(nimbus_context_last_error(ctx), "ColorTargets") == NULL); /* no Rust names */
    t.scene_color = depth; t.output = output;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.scene_color");
    t.scene_color = scene; t.output = depth;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.output");
    t.output = output; t.scene_depth = depth_rgba8;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "NIMBUS_FORMAT_R32_FLOAT");
    t.scene_depth = depth;
    t.next = &unknown;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    t.next = NULL;
    f.next = &unknown;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    f.next = NULL;
    f.view[5] = NAN;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    memset(f.projection, 0, sizeof f.projection);
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    memset(f.view, 0, sizeof f.view);
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.projection[11] = 0.0f; f.projection[15] = 1.0f; /* orthographic */
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME, "perspective");
    frame_defaults(&f);
    f.depth_flags = NIMBUS_DEPTH_REVERSED_Z; /* the projection is not reversed */
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME, "reversed");
    f.depth_flags = NIMBUS_DEPTH_INFINITE_FAR; /* it has a far plane */
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME, "far plane");
    f.depth_flags = 0x80;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "0x80");
    frame_defaults(&f);
    mat_perspective(f.projection, 1.2f, (float)W / (float)H, 0.01f, 1e12f); /* infinite in f32 */
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME, "f32");
    f.depth_flags = NIMBUS_DEPTH_INFINITE_FAR;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    frame_defaults(&f);
    f.sun_direction[0] = f.sun_direction[1] = f.sun_direction[2] = 0.0f;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.sun_direction[1] = INFINITY;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.sun_illuminance = NAN;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    f.sun_illuminance = -1.0f;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.sun_color[0] = -1.0f;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.time = INFINITY;
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    f.time = -1e300;
    /* Finite: accepted (weather before time 0 is the initial weather). */
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    /* Still usable: with depth, then in place, then an OpenGL-style projection with its flag. */
    frame_defaults(&f);
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    t.scene_color = output; t.output = output; /* in place (RGBA16F blends) */
    EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    {
        /* glFrustum-style: z_clip in [-w, w]. */
        float n = 1.0f, fa = 100000.0f, y = 1.0f / tanf(0.6f);
        memset(f.projection, 0, sizeof f.projection);
        f.projection[0] = y * (float)H / (float)W; f.projection[5] = y;
        f.projection[10] = -(fa + n) / (fa - n); f.projection[11] = -1.0f;
        f.projection[14] = -2.0f * fa * n / (fa - n);
        f.depth_flags = NIMBUS_DEPTH_GL_CLIP_Z;
        EXPECT_ON(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    }
    EXPECT_ON(ctx, render_ok(), NIMBUS_OK);
}

static void test_weather_and_resize(void) {
    FILE *fp;
    const char *bad = "nimbus_api_test_bad_preset.toml";
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, 0, 0, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, 99, 0, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0x40, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, 0.0, NAN), NIMBUS_ERROR_WEATHER);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, 0.0, -1.0), NIMBUS_ERROR_WEATHER);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, INFINITY, 1.0), NIMBUS_ERROR_WEATHER);
    EXPECT(nimbus_context_set_weather(NULL, NIMBUS_PRESET_STORMY, 0, 0.0, 1.0), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, NIMBUS_WEATHER_CIRRUS, 5.0, 10.0), NIMBUS_OK);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_CLEAR, 0, 4.0, 1.0), NIMBUS_ERROR_WEATHER); /* out of order */
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_OVERCAST, NIMBUS_WEATHER_HORIZON_GRADIENT, 8.0, 3.0), NIMBUS_OK);
    EXPECT_ON(ctx, nimbus_context_load_weather(ctx, NULL, 9.0, 1.0), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, nimbus_context_load_weather(ctx, "/nonexistent/weather.toml", 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
    EXPECT_MSG(ctx, nimbus_context_load_weather(ctx, "/dev/zero", 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "larger than");
    EXPECT_ON(ctx, nimbus_context_load_weather(ctx, "/", 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE); /* a directory */
    EXPECT_ON(ctx, nimbus_context_load_weather(ctx, "\xff\xfe", 9.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT); /* not UTF-8 */
    fp = fopen(bad, "w");
    if (fp) {
        fputs("name = \"bad\"\n[clouds]\ncoverage = 3.5\n", fp);
        fclose(fp);
        EXPECT_MSG(ctx, nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "line 3");
        fp = fopen(bad, "w");
        if (fp) { fputs("[clouds\n", fp); fclose(fp); }
        EXPECT_ON(ctx, nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
        fp = fopen(bad, "w");
        if (fp) { fputs("clouds = 3\n", fp); fclose(fp); }
        EXPECT_MSG(ctx, nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "table");
        TRUE(strstr(nimbus_context_last_error(ctx), "struct") == NULL); /* no Rust type names */
        fp = fopen(bad, "w");
        if (fp) { fputs("# only a comment\n\n", fp); fclose(fp); }
        EXPECT_MSG(ctx, nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "no settings");
        remove(bad);
    }
    /* Presets from memory, templates out, the transition's state, and cancelling. */
    {
        const char *mine = "name = \"mine\"\n[clouds]\ncoverage = 0.3\n";
        char small[8], *tmpl;
        size_t need = 0, cap;
        NimbusWeatherState st;
        NimbusChainedStruct unknown = {999, NULL};
        memset(&st, 0, sizeof st);
        EXPECT_ON(ctx, nimbus_context_set_weather_toml(ctx, NULL, 10, 20.0, 1.0), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_MSG(ctx, nimbus_context_set_weather_toml(ctx, mine, 1u << 20, 20.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "at most");
        EXPECT_MSG(ctx, nimbus_context_set_weather_toml(ctx, "[clouds]\ncoverage = 9\n", 22, 20.0, 1.0), NIMBUS_ERROR_PRESET_FILE, "line 2");
        EXPECT_ON(ctx, nimbus_context_set_weather_toml(ctx, "\xff\xfe", 2, 20.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
        EXPECT_ON(ctx, nimbus_context_set_weather_toml(ctx, mine, strlen(mine), 20.0, 10.0), NIMBUS_OK);
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 25.0, NULL), NIMBUS_ERROR_NULL_POINTER);
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, NAN, &st), NIMBUS_ERROR_INVALID_ARGUMENT);
        st.next = &unknown;
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 25.0, &st), NIMBUS_ERROR_UNKNOWN_STRUCT);
        st.next = NULL;
        /* Since ABI 0.7: the default 512² map is generated over 16 frames; until it is ready a
         * request is PENDING (the first of those waiting: stormy at 5 s, then overcast at 8 s
         * and mine at 20 s), then it enters at max(its start, the frame's time). */
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 25.0, &st), NIMBUS_OK);
        TRUE(strncmp(st.to_name, "stormy", 6) == 0 && st.phase == NIMBUS_TRANSITION_PENDING);
        TRUE(st.progress == 0.0f && st.start == 5.0 && st.duration == 10.0);
        {
            int frames = 0;
            while (st.phase == NIMBUS_TRANSITION_PENDING && frames < 80) {
                EXPECT_ON(ctx, render_ok(), NIMBUS_OK);
                EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 25.0, &st), NIMBUS_OK);
                frames++;
            }
            printf("the three requested weathers' maps took %d frames\n", frames);
            TRUE(frames == 48);
        }
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 25.0, &st), NIMBUS_OK);
        TRUE(strcmp(st.to_name, "mine") == 0 && st.phase == NIMBUS_TRANSITION_RUNNING);
        TRUE(st.progress > 0.0f && st.progress < 1.0f && st.start == 20.0 && st.duration == 10.0);
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 15.0, &st), NIMBUS_OK);
        TRUE(st.phase == NIMBUS_TRANSITION_SCHEDULED && st.progress == 0.0f);
        EXPECT_ON(ctx, nimbus_context_cancel_weather(ctx, NAN), NIMBUS_ERROR_WEATHER);
        EXPECT_ON(ctx, nimbus_context_cancel_weather(ctx, 25.0), NIMBUS_OK);
        EXPECT_ON(ctx, nimbus_context_weather_state(ctx, 99.0, &st), NIMBUS_OK);
        TRUE(st.phase == NIMBUS_TRANSITION_DONE && st.duration == 0.0);
        EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_OVERCAST, 0, NULL, NULL), NIMBUS_ERROR_NULL_POINTER);
        EXPECT(nimbus_preset_write_toml(42, 0, NULL, &need), NIMBUS_ERROR_INVALID_ARGUMENT);
        EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_OVERCAST, 0x40, NULL, &need), NIMBUS_ERROR_INVALID_ARGUMENT);
        EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_OVERCAST, NIMBUS_WEATHER_CIRRUS, NULL, &need), NIMBUS_OK);
        TRUE(need > 100);
        cap = sizeof small;
        EXPECT_MSG(NULL, nimbus_preset_write_toml(NIMBUS_PRESET_OVERCAST, NIMBUS_WEATHER_CIRRUS, small, &cap), NIMBUS_ERROR_INVALID_ARGUMENT, "needs");
        TRUE(cap == sizeof small); /* untouched on failure */
        tmpl = (char *)malloc(need);
        cap = need;
        EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_OVERCAST, NIMBUS_WEATHER_CIRRUS, tmpl, &cap), NIMBUS_OK);
        TRUE(cap == need && strlen(tmpl) + 1 == need && strstr(tmpl, "overcast") != NULL);
        /* The template loads back (after the held sky's time). */
        EXPECT_ON(ctx, nimbus_context_set_weather_toml(ctx, tmpl, strlen(tmpl), 30.0, 0.0), NIMBUS_OK);
        free(tmpl);
    }
    EXPECT_ON(ctx, nimbus_context_resize(ctx, 0, 10), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT_ON(ctx, nimbus_context_resize(ctx, 10, 1000000), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_resize(NULL, 10, 10), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_ON(ctx, render_ok(), NIMBUS_OK); /* render after a failed resize */
    EXPECT_ON(ctx, nimbus_context_reset_history(ctx), NIMBUS_OK);
    EXPECT(nimbus_context_reset_history(NULL), NIMBUS_ERROR_NULL_POINTER);
}

/* ---- a second context: textures belong to their context; two threads at once --------------- */
struct worker { NimbusContext *c; NimbusTexture *color, *out; int failures; };

static void *render_frames(void *arg) {
    struct worker *w = (struct worker *)arg;
    int i;
    for (i = 0; i < 12; i++)
        if (render_on(w->c, w->color, w->out, i / 30.0) != NIMBUS_OK) w->failures++;
    return NULL;
}

static void test_second_context(void) {
    NimbusContextDesc desc = {0};
    NimbusSettingsExt s = {0};
    NimbusNoiseCacheExt nc;
    NimbusContext *b = NULL;
    NimbusTexture *b_color, *b_out, *b_depth, *orphan;
    NimbusTargets t = {0};
    NimbusFrame f;
    uint32_t garbage = 0xdeadbeefu;
    float px[4 * 4 * 4];
    size_t size = 0;

    /* ABI 0.2: the settings struct's tail padding is ignored, whatever it holds; and a
     * maximum step count alone no longer clashes with the defaulted minimum. */
    desc.abi_version = NIMBUS_ABI_VERSION;
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    s.march_max_steps = 10;
    memcpy((char *)&s + 44, &garbage, sizeof garbage);
    desc.next = &s.chain;
    if (noise_cache) chain_noise_cache(&desc, &nc);
    EXPECT_ON(NULL, nimbus_context_create(&desc, &b), NIMBUS_OK);
    if (!b) return;
    {
        /* Made from ctx's noise cache: the same volumes, not baked again. */
        uint32_t from_cache = 0;
        EXPECT_ON(b, nimbus_context_noise_from_cache(b, &from_cache), NIMBUS_OK);
        TRUE(from_cache == (noise_cache ? 1u : 0u));
    }
    {
        /* Made without NimbusCloudShadowsExt: no map, even after a frame. */
        NimbusCloudShadowInfo info;
        float texel[4];
        memset(&info, 0, sizeof info);
        EXPECT_MSG(b, nimbus_context_cloud_shadows(b, &info), NIMBUS_ERROR_NOT_READY, "NimbusCloudShadowsExt");
        EXPECT_ON(b, nimbus_context_read_cloud_shadows(b, texel, 4), NIMBUS_ERROR_NOT_READY);
    }
    b_color = make_texture_on(b, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    b_out = make_texture_on(b, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    b_depth = make_texture_on(b, W, H, NIMBUS_FORMAT_R32_FLOAT);
    orphan = make_texture_on(b, 4, 4, NIMBUS_FORMAT_RGBA32_FLOAT);

    /* Textures of b given to ctx: refused, naming the argument; nothing is drawn. */
    frame_defaults(&f);
    t.scene_color = b_color; t.output = output;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.scene_color was created by another context");
    t.scene_color = scene; t.output = b_out;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.output");
    t.output = output; t.scene_depth = b_depth;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.scene_depth");
    t.scene_color = b_color; t.output = b_color; t.scene_depth = depth; /* and the reverse */
    EXPECT_MSG(b, nimbus_context_render(b, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "targets.scene_depth");
    EXPECT_ON(ctx, render_ok(), NIMBUS_OK);

    /* Two contexts rendering at once on two threads (the header allows it). The log
     * callback could run on both threads: errors only, so it stays quiet. */
    EXPECT(nimbus_set_log_callback(log_cb, NULL, 1), NIMBUS_OK);
    {
        pthread_t ta, tb;
        struct worker wa, wb;
        wa.c = ctx; wa.color = scene; wa.out = output; wa.failures = 0;
        wb.c = b; wb.color = b_color; wb.out = b_out; wb.failures = 0;
        pthread_create(&ta, NULL, render_frames, &wa);
        pthread_create(&tb, NULL, render_frames, &wb);
        pthread_join(ta, NULL);
        pthread_join(tb, NULL);
        TRUE(wa.failures == 0 && wb.failures == 0);
    }

    nimbus_texture_destroy(b_color); nimbus_texture_destroy(b_out); nimbus_texture_destroy(b_depth);
    {
        /* A query outlives its context. */
        NimbusCloudQuery *q = NULL;
        float p[3] = {0.0f, 1500.0f, 0.0f}, before = -1.0f, after = -2.0f;
        EXPECT_ON(b, nimbus_context_create_cloud_query(b, &q), NIMBUS_OK);
        EXPECT(nimbus_cloud_query_density(q, p, 3.0, &before), NIMBUS_OK);
        nimbus_context_destroy(b);
        EXPECT(nimbus_cloud_query_density(q, p, 3.0, &after), NIMBUS_OK);
        TRUE(before == after);
        nimbus_cloud_query_destroy(q);
    }
    /* A texture outliving its context: only destroy works. */
    EXPECT_MSG(NULL, nimbus_texture_write(orphan, px, sizeof px), NIMBUS_ERROR_INVALID_TARGET, "destroyed");
    EXPECT(nimbus_texture_read(orphan, px, sizeof px), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_byte_size(orphan, &size), NIMBUS_ERROR_INVALID_TARGET);
    t.scene_color = orphan; t.output = output; t.scene_depth = NULL;
    EXPECT_MSG(ctx, nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "destroyed");
    nimbus_texture_destroy(orphan);
    EXPECT_ON(ctx, render_ok(), NIMBUS_OK);
}

static void test_old_header_and_device_loss(void) {
#ifdef NIMBUS_TEST_HOOKS
    NimbusContextDesc desc = {0};
    NimbusSettingsExt s = {0};
    NimbusContext *c = NULL;
    NimbusTexture *color, *out;
    NimbusNoiseCacheExt nc;
    uint32_t bad_level = 77, low = NIMBUS_QUALITY_LOW;

    /* A header of ABI 0.1 declared `quality` at offset 44 of NimbusSettingsExt: read there. */
    desc.abi_version = (NIMBUS_VERSION_MAJOR << 16) | 1u;
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    desc.next = &s.chain;
    memcpy((char *)&s + 44, &bad_level, sizeof bad_level);
    EXPECT_MSG(NULL, nimbus_context_create(&desc, &c), NIMBUS_ERROR_INVALID_ARGUMENT, "quality");
    memcpy((char *)&s + 44, &low, sizeof low);
    EXPECT_ON(NULL, nimbus_context_create(&desc, &c), NIMBUS_OK);
    if (!c) return;
    color = make_texture_on(c, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    out = make_texture_on(c, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    EXPECT_ON(c, render_on(c, color, out, 0.0), NIMBUS_OK);
    /* A 0.1 header knows no NIMBUS_TRANSITION_PENDING: a request whose map is still being
     * made reads as scheduled. */
    {
        NimbusWeatherState st;
        memset(&st, 0, sizeof st);
        EXPECT_ON(c, nimbus_context_set_weather(c, NIMBUS_PRESET_STORMY, 0, 5.0, 1.0), NIMBUS_OK);
        EXPECT_ON(c, nimbus_context_weather_state(c, 6.0, &st), NIMBUS_OK);
        TRUE(st.phase == NIMBUS_TRANSITION_SCHEDULED && strcmp(st.to_name, "stormy") == 0);
    }

    /* The device goes away: every call says so; destroy works; a new context works. */
    EXPECT_ON(c, nimbus_test_hook_lose_device(c), NIMBUS_OK);
    EXPECT_MSG(c, render_on(c, color, out, 0.1), NIMBUS_ERROR_DEVICE_LOST, "lost");
    EXPECT_ON(c, nimbus_context_set_weather(c, NIMBUS_PRESET_CLEAR, 0, 1.0, 1.0), NIMBUS_ERROR_DEVICE_LOST);
    EXPECT_ON(c, nimbus_context_reset_history(c), NIMBUS_ERROR_DEVICE_LOST);
    nimbus_texture_destroy(color); nimbus_texture_destroy(out);
    nimbus_context_destroy(c);
    c = NULL;
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = NULL;
    if (noise_cache) chain_noise_cache(&desc, &nc);
    EXPECT_ON(NULL, nimbus_context_create(&desc, &c), NIMBUS_OK);
    if (c) {
        color = make_texture_on(c, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
        out = make_texture_on(c, W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
        EXPECT_ON(c, render_on(c, color, out, 0.0), NIMBUS_OK);
        nimbus_texture_destroy(color); nimbus_texture_destroy(out);
        nimbus_context_destroy(c);
    }
#endif
}

static void test_poison(void) {
#ifdef NIMBUS_TEST_HOOKS
    log_panics = 0;
    EXPECT_MSG(ctx, nimbus_test_hook_panic(ctx), NIMBUS_ERROR_PANIC, "panic inside Nimbus");
    TRUE(log_panics == 1); /* the panic went to the log callback, not to stderr */
    EXPECT_MSG(ctx, nimbus_context_reset_history(ctx), NIMBUS_ERROR_POISONED, "poisoned");
    EXPECT_ON(ctx, render_ok(), NIMBUS_ERROR_POISONED);
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_CLEAR, 0, 100.0, 1.0), NIMBUS_ERROR_POISONED);
    EXPECT_ON(ctx, nimbus_context_resize(ctx, 10, 10), NIMBUS_ERROR_POISONED);
#else
    printf("no test hooks: the panic and device-loss paths are not exercised\n");
    failed++;
#endif
    nimbus_texture_destroy(scene); nimbus_texture_destroy(output); nimbus_texture_destroy(depth);
    nimbus_texture_destroy(small_tex); nimbus_texture_destroy(rgba32); nimbus_texture_destroy(depth_rgba8);
    nimbus_context_destroy(ctx);
    nimbus_context_destroy(NULL); /* no-op */
    ctx = NULL;
    EXPECT(nimbus_set_log_callback(NULL, NULL, 0), NIMBUS_OK);
}

/* The cases that fail before any GPU device exists: what valgrind runs (a context creation
 * JIT-compiles shaders in Mesa's llvmpipe, far too slow under valgrind). */
static void test_without_device(void) {
    NimbusContextDesc desc = {0};
    NimbusContext *out = NULL;
    NimbusChainedStruct unknown = {999, NULL};
    NimbusSettingsExt s = {0};
    NimbusQualityExt q = {0};
    NimbusWindowHandle win = {0};
    float buf[16];
    size_t size = 0;
    char small[4];
    EXPECT(nimbus_context_create(NULL, &out), NIMBUS_ERROR_NULL_POINTER);
    desc.abi_version = 0;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = NIMBUS_ABI_VERSION + 1;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = NIMBUS_ABI_VERSION;
    EXPECT(nimbus_context_create(&desc, NULL), NIMBUS_ERROR_NULL_POINTER);
    desc.next = &unknown;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT);
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    desc.next = &s.chain;
    s.jitter = 9;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.jitter = 0; s.planet_radius = -1e30f;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.planet_radius = 0.0f;
    q.chain.s_type = NIMBUS_STYPE_QUALITY; q.quality = 8;
    s.chain.next = &q.chain;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    q.quality = 0;
    desc.window = &win; desc.width = 64; desc.height = 64;
    win.platform = 77;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    win.platform = NIMBUS_PLATFORM_X11;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    TRUE(out == NULL);
    EXPECT(nimbus_texture_create(NULL, NULL, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_write(NULL, buf, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_read(NULL, buf, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_byte_size(NULL, &size), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_render(NULL, NULL, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_set_weather_toml(NULL, "x", 1, 0.0, 0.0), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_weather_state(NULL, 0.0, NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_cancel_weather(NULL, 0.0), NIMBUS_ERROR_NULL_POINTER);
    size = sizeof small;
    EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_STORMY, 0, small, &size), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_preset_write_toml(NIMBUS_PRESET_STORMY, 0, NULL, &size), NIMBUS_OK);
    EXPECT(nimbus_set_log_callback(log_cb, NULL, 6), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_set_log_callback(NULL, NULL, 0), NIMBUS_OK);
    nimbus_context_destroy(NULL);
    nimbus_texture_destroy(NULL);
}

/* One context, one frame, its textures, errors on it, destroy: the device path under valgrind. */
static void test_one_frame(void) {
    NimbusContextDesc desc = {0};
    NimbusNoiseCacheExt nc;
    NimbusTexture *color, *out;
    desc.abi_version = NIMBUS_ABI_VERSION;
    if (noise_cache_loaded) {
        chain_noise_cache(&desc, &nc);
        nc.flags = NIMBUS_NOISE_CACHE_FALLBACK;
    }
    EXPECT_ON(NULL, nimbus_context_create(&desc, &ctx), NIMBUS_OK);
    if (!ctx) return;
    color = make_texture(W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    out = make_texture(W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    EXPECT_ON(ctx, render_on(ctx, color, out, 0.0), NIMBUS_OK);
    EXPECT_ON(ctx, render_on(ctx, color, NULL, 0.0), NIMBUS_ERROR_INVALID_TARGET); /* no window */
    EXPECT_ON(ctx, nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, 0.0, 1.0), NIMBUS_OK);
    nimbus_texture_destroy(color);
    nimbus_texture_destroy(out);
    nimbus_context_destroy(ctx);
    ctx = NULL;
}

/* Reads the noise cache file `path` into noise_cache; 0 if there is none. */
static int load_noise_cache(const char *path) {
    FILE *f = fopen(path, "rb");
    long n;
    if (!f) return 0;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (noise_cache = malloc((size_t)n)) != NULL && fread(noise_cache, 1, (size_t)n, f) == (size_t)n) {
        noise_cache_size = (size_t)n;
        noise_cache_loaded = 1;
    } else {
        free(noise_cache);
        noise_cache = NULL;
    }
    fclose(f);
    return noise_cache_loaded;
}

/* Writes the exported cache to `path` for the next runs. */
static void save_noise_cache(const char *path) {
    FILE *f = fopen(path, "wb");
    TRUE(f != NULL);
    if (!f) return;
    TRUE(fwrite(noise_cache, 1, noise_cache_size, f) == noise_cache_size);
    fclose(f);
    printf("wrote the noise cache %s\n", path);
}

/* Usage: api_test [--one-frame | --no-device] [--noise-cache FILE] */
int main(int argc, char **argv) {
    const char *mode = "", *cache_path = NULL;
    int i;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--noise-cache") == 0 && i + 1 < argc) cache_path = argv[++i];
        else mode = argv[i];
    }
    if (cache_path && load_noise_cache(cache_path)) printf("noise cache from %s\n", cache_path);
    if (strcmp(mode, "--one-frame") == 0) {
        test_one_frame();
        free(noise_cache);
        printf("%d passed, %d failed\n", passed, failed);
        return failed == 0 ? 0 : 1;
    }
    if (strcmp(mode, "--no-device") == 0) {
        test_results_and_versions();
        test_without_device();
        free(noise_cache);
        printf("bad-input cases: %d\n", bad_cases);
        printf("%d passed, %d failed\n", passed, failed);
        return failed == 0 ? 0 : 1;
    }
    test_results_and_versions();
    test_create();
    if (!ctx) { printf("no context: %s\n", nimbus_context_last_error(NULL)); return 1; }
    test_textures();
    test_render();
    test_owned_formats();
    test_views();
    test_cloud_shadows();
    test_noise_cache();
    if (cache_path && !noise_cache_loaded && noise_cache) save_noise_cache(cache_path);
    test_cloud_query();
    test_weather_and_resize();
    test_second_context();
    test_old_header_and_device_loss();
    test_poison();
    free(noise_cache);
    printf("bad-input cases: %d\n", bad_cases);
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
