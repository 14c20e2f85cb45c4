/* C API tests: every kind of bad input gets its documented code and a message, and the context
 * stays usable. Built with -std=c99 -Wall -Wextra -Werror -pedantic and AddressSanitizer.
 * Ends with "N passed, N failed". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nimbus.h"
#include "camera.h"

/* Struct layouts are part of the ABI: pin them (64-bit targets). */
#define ASSERT_SIZE(type, size) typedef char assert_size_##type[(sizeof(type) == (size)) ? 1 : -1]
ASSERT_SIZE(NimbusChainedStruct, 16);
ASSERT_SIZE(NimbusWindowHandle, 32);
ASSERT_SIZE(NimbusContextDesc, 32);
ASSERT_SIZE(NimbusSettingsExt, 48);
ASSERT_SIZE(NimbusFrame, 176);
ASSERT_SIZE(NimbusTextureDesc, 24);
ASSERT_SIZE(NimbusTargets, 32);

static int passed = 0, failed = 0;
static NimbusContext *ctx = NULL;

static void expect(int32_t got, int32_t want, const char *what, int line) {
    const char *msg = nimbus_context_last_error(ctx);
    if (got != want) {
        printf("FAIL line %d: %s returned %d, expected %d (%s)\n", line, what, got, want, msg);
        failed++;
        return;
    }
    if (want < 0 && (msg == NULL || msg[0] == '\0')) {
        /* Calls without a context report on the thread's last error. */
        msg = nimbus_context_last_error(NULL);
        if (msg == NULL || msg[0] == '\0') {
            printf("FAIL line %d: %s gave no message\n", line, what);
            failed++;
            return;
        }
    }
    if (want < 0) printf("ok   %-58s -> %4d: %s\n", what, got, msg);
    passed++;
}
#define EXPECT(call, code) expect((call), (code), #call, __LINE__)

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

static int render_ok(void) {
    NimbusFrame f;
    NimbusTargets t = {0};
    frame_defaults(&f);
    t.scene_color = scene;
    t.output = output;
    return nimbus_context_render(ctx, &f, &t);
}

static NimbusTexture *make_texture(uint32_t w, uint32_t h, uint32_t format) {
    NimbusTextureDesc d = {0};
    NimbusTexture *t = NULL;
    d.width = w; d.height = h; d.format = format;
    if (nimbus_texture_create(ctx, &d, &t) != NIMBUS_OK) {
        printf("could not create a %ux%u texture: %s\n", w, h, nimbus_context_last_error(ctx));
        exit(1);
    }
    return t;
}

static void test_create(void) {
    NimbusContextDesc desc = {0};
    NimbusContext *out = (NimbusContext *)&desc; /* must stay untouched on failure */
    NimbusContext *before = out;
    NimbusChainedStruct unknown = {999, NULL};
    NimbusSettingsExt s = {0};
    NimbusWindowHandle win = {0};

    EXPECT(nimbus_context_create(NULL, &out), NIMBUS_ERROR_NULL_POINTER);
    desc.abi_version = NIMBUS_ABI_VERSION;
    EXPECT(nimbus_context_create(&desc, NULL), NIMBUS_ERROR_NULL_POINTER);
    desc.abi_version = NIMBUS_ABI_VERSION + (1u << 16);
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_ABI_VERSION);
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &unknown;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT);
    s.chain.s_type = NIMBUS_STYPE_SETTINGS;
    s.chain.next = &unknown;
    desc.next = &s.chain;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_UNKNOWN_STRUCT);
    s.chain.next = NULL;
    s.jitter = 7;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.jitter = 0;
    s.initial_preset = 99;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.initial_preset = 0;
    s.march_min_steps = 500; /* above the default maximum of 96 */
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.march_min_steps = 0;
    s.planet_radius = -5.0f;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.planet_radius = NAN;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_SETTINGS);
    s.planet_radius = 0.0f;
    s.quality = 5; /* levels are 0 (default) and 1..4 */
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    s.quality = NIMBUS_QUALITY_DEFAULT;
    desc.window = &win;
    desc.width = 64; desc.height = 64;
    win.platform = 42;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    win.platform = NIMBUS_PLATFORM_X11;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    win.platform = NIMBUS_PLATFORM_WAYLAND;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_NULL_POINTER);
    desc.width = 0;
    EXPECT(nimbus_context_create(&desc, &out), NIMBUS_ERROR_INVALID_ARGUMENT);
    if (out != before) { printf("FAIL: out was written on failure\n"); failed++; }
    desc.window = NULL;
    s.quality = NIMBUS_QUALITY_HIGH; /* the explicit step counts below refine the level */
    s.march_max_steps = 64; s.march_min_steps = 32; s.jitter = NIMBUS_JITTER_OFF;
    EXPECT(nimbus_context_create(&desc, &ctx), NIMBUS_OK);
}

static void test_textures(void) {
    NimbusTextureDesc d = {0};
    NimbusTexture *t = NULL;
    NimbusChainedStruct unknown = {999, NULL};
    float buf[W * H * 4];
    size_t size = 0;

    EXPECT(nimbus_texture_create(ctx, NULL, &t), NIMBUS_ERROR_NULL_POINTER);
    d.width = W; d.height = H; d.format = NIMBUS_FORMAT_RGBA16_FLOAT;
    EXPECT(nimbus_texture_create(NULL, &d, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_create(ctx, &d, NULL), NIMBUS_ERROR_NULL_POINTER);
    d.format = 99;
    EXPECT(nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.format = NIMBUS_FORMAT_RGBA16_FLOAT; d.width = 0;
    EXPECT(nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.width = 100000;
    EXPECT(nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    d.width = W; d.next = &unknown;
    EXPECT(nimbus_texture_create(ctx, &d, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    if (t != NULL) { printf("FAIL: texture out written on failure\n"); failed++; }

    scene = make_texture(W, H, NIMBUS_FORMAT_RGBA32_FLOAT);
    output = make_texture(W, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    depth = make_texture(W, H, NIMBUS_FORMAT_R32_FLOAT);
    small_tex = make_texture(W / 2, H, NIMBUS_FORMAT_RGBA16_FLOAT);
    rgba32 = make_texture(W, H, NIMBUS_FORMAT_RGBA32_FLOAT);
    depth_rgba8 = make_texture(W, H, NIMBUS_FORMAT_RGBA8_UNORM);

    EXPECT(nimbus_texture_byte_size(scene, &size), NIMBUS_OK);
    if (size != sizeof buf) { printf("FAIL: byte size %zu\n", size); failed++; }
    EXPECT(nimbus_texture_byte_size(NULL, &size), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_byte_size(scene, NULL), NIMBUS_ERROR_NULL_POINTER);
    memset(buf, 0, sizeof buf);
    EXPECT(nimbus_texture_write(scene, buf, sizeof buf - 4), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_write(scene, NULL, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_write(NULL, buf, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_texture_read(scene, buf, 17), NIMBUS_ERROR_INVALID_TARGET);
    EXPECT(nimbus_texture_read(scene, NULL, sizeof buf), NIMBUS_ERROR_NULL_POINTER);
    {
        int i;
        for (i = 0; i < W * H; i++) { buf[i * 4] = 0.2f; buf[i * 4 + 1] = 0.3f; buf[i * 4 + 2] = 0.6f; buf[i * 4 + 3] = 1.0f; }
    }
    EXPECT(nimbus_texture_write(scene, buf, sizeof buf), NIMBUS_OK);
    memset(buf, 0, sizeof buf);
    EXPECT(nimbus_texture_read(scene, buf, sizeof buf), NIMBUS_OK);
    if (buf[1] != 0.3f) { printf("FAIL: texture round trip gave %f\n", (double)buf[1]); failed++; }
    nimbus_texture_destroy(NULL); /* no-op */
}

static void test_render(void) {
    NimbusFrame f;
    NimbusTargets t = {0};
    NimbusChainedStruct unknown = {999, NULL};

    frame_defaults(&f);
    t.scene_color = scene; t.output = output;
    EXPECT(nimbus_context_render(NULL, &f, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_render(ctx, NULL, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_render(ctx, &f, NULL), NIMBUS_ERROR_NULL_POINTER);
    t.scene_color = NULL;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_NULL_POINTER);
    t.scene_color = scene;
    t.output = NULL;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET); /* headless: no window */
    t.output = small_tex;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET);
    t.output = rgba32; t.scene_color = rgba32;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET); /* RGBA32F in place */
    t.scene_color = depth; t.output = output;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET); /* R32F as color */
    t.scene_color = scene; t.scene_depth = depth_rgba8;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET);
    t.scene_depth = depth;
    t.next = &unknown;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    t.next = NULL;
    f.next = &unknown;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT);
    f.next = NULL;
    f.view[5] = NAN;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    memset(f.projection, 0, sizeof f.projection);
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    memset(f.view, 0, sizeof f.view);
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.depth_flags = NIMBUS_DEPTH_REVERSED_Z; /* the projection is not reversed */
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    f.depth_flags = 0x80;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT);
    frame_defaults(&f);
    f.sun_direction[0] = f.sun_direction[1] = f.sun_direction[2] = 0.0f;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.sun_illuminance = NAN;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    frame_defaults(&f);
    f.time = INFINITY;
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME);
    /* Still usable: with depth, then in place. */
    frame_defaults(&f);
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    t.scene_color = output; t.output = output; /* in place (RGBA16F blends) */
    EXPECT(nimbus_context_render(ctx, &f, &t), NIMBUS_OK);
    EXPECT(render_ok(), NIMBUS_OK);
}

static void test_weather_and_resize(void) {
    FILE *fp;
    const char *bad = "nimbus_api_test_bad_preset.toml";
    EXPECT(nimbus_context_set_weather(ctx, 0, 0, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_set_weather(ctx, 99, 0, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0x40, 0.0, 1.0), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, 0.0, NAN), NIMBUS_ERROR_WEATHER);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, 0, 0.0, -1.0), NIMBUS_ERROR_WEATHER);
    EXPECT(nimbus_context_set_weather(NULL, NIMBUS_PRESET_STORMY, 0, 0.0, 1.0), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_STORMY, NIMBUS_WEATHER_CIRRUS, 5.0, 10.0), NIMBUS_OK);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_CLEAR, 0, 4.0, 1.0), NIMBUS_ERROR_WEATHER); /* out of order */
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_OVERCAST, NIMBUS_WEATHER_HORIZON_GRADIENT, 8.0, 3.0), NIMBUS_OK);
    EXPECT(nimbus_context_load_weather(ctx, NULL, 9.0, 1.0), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_load_weather(ctx, "/nonexistent/weather.toml", 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
    fp = fopen(bad, "w");
    if (fp) {
        fputs("name = \"bad\"\n[clouds]\ncoverage = 3.5\n", fp);
        fclose(fp);
        EXPECT(nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
        if (!strstr(nimbus_context_last_error(ctx), "line 3")) { printf("FAIL: no line in message\n"); failed++; }
        fp = fopen(bad, "w");
        if (fp) { fputs("[clouds\n", fp); fclose(fp); }
        EXPECT(nimbus_context_load_weather(ctx, bad, 9.0, 1.0), NIMBUS_ERROR_PRESET_FILE);
        remove(bad);
    }
    EXPECT(nimbus_context_resize(ctx, 0, 10), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_resize(ctx, 10, 1000000), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_context_resize(NULL, 10, 10), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(render_ok(), NIMBUS_OK); /* render after a failed resize */
}

static void log_cb(int32_t level, const char *message, void *user) {
    (void)level; (void)message;
    ++*(int *)user;
}

static void test_misc_and_poison(void) {
    static int logs = 0;
    EXPECT(nimbus_set_log_callback(log_cb, &logs, 9), NIMBUS_ERROR_INVALID_ARGUMENT);
    EXPECT(nimbus_set_log_callback(log_cb, &logs, 2), NIMBUS_OK);
    EXPECT(nimbus_set_log_callback(NULL, NULL, 0), NIMBUS_OK);
    if (nimbus_version() != ((NIMBUS_VERSION_MAJOR << 16) | (NIMBUS_VERSION_MINOR << 8) | NIMBUS_VERSION_PATCH)) {
        printf("FAIL: nimbus_version() disagrees with the header\n"); failed++;
    } else passed++;
    if (strncmp(nimbus_version_string(), "0.1", 3) != 0) { printf("FAIL: version string\n"); failed++; } else passed++;
    if (nimbus_context_adapter_name(NULL) != NULL) { printf("FAIL: adapter name of NULL\n"); failed++; } else passed++;
    printf("adapter: %s\n", nimbus_context_adapter_name(ctx));

    EXPECT(nimbus_context_reset_history(NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT(nimbus_context_reset_history(ctx), NIMBUS_OK);
    EXPECT(render_ok(), NIMBUS_OK);

    EXPECT(nimbus_context_debug_panic(ctx), NIMBUS_ERROR_PANIC);
    EXPECT(nimbus_context_reset_history(ctx), NIMBUS_ERROR_POISONED);
    EXPECT(render_ok(), NIMBUS_ERROR_POISONED);
    EXPECT(nimbus_context_set_weather(ctx, NIMBUS_PRESET_CLEAR, 0, 100.0, 1.0), NIMBUS_ERROR_POISONED);
    nimbus_texture_destroy(scene); nimbus_texture_destroy(output); nimbus_texture_destroy(depth);
    nimbus_texture_destroy(small_tex); nimbus_texture_destroy(rgba32); nimbus_texture_destroy(depth_rgba8);
    nimbus_context_destroy(ctx);
    nimbus_context_destroy(NULL); /* no-op */
    ctx = NULL;
}

int main(void) {
    test_create();
    if (!ctx) { printf("no context: %s\n", nimbus_context_last_error(NULL)); return 1; }
    test_textures();
    test_render();
    test_weather_and_resize();
    test_misc_and_poison();
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
