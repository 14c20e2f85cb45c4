/* The Nimbus GLFW sample host: a window full of clouds, over a small CPU-rendered scene whose
 * depth occludes them. Uses only include/nimbus.h and the shared library.
 *
 * Usage: glfw_sample [--size WIDTHxHEIGHT] [--frames N --screenshot FILE.png]
 *                    [--no-cloud-shadows] [--no-ambient-light] [--preset 1-5]
 *                    [--noise-cache FILE | --no-noise-cache]
 * With --frames it runs N frames on a fixed 1/30 s clock and writes the last one as a PNG
 * (for headless runs under Xvfb). The baked noise volumes are kept in a noise cache file
 * ($XDG_CACHE_HOME/nimbus-noise.cache, else ~/.cache/nimbus-noise.cache): the first start bakes
 * and writes it, later starts upload it instead of baking (seconds faster on software Vulkan). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
/* X11 by default; build with -DNIMBUS_SAMPLE_WAYLAND against a Wayland GLFW for Wayland. */
#ifdef NIMBUS_SAMPLE_WAYLAND
#define GLFW_EXPOSE_NATIVE_WAYLAND
#else
#define GLFW_EXPOSE_NATIVE_X11
#endif
#include <GLFW/glfw3native.h>

#include "nimbus.h"
#include "camera.h"
#include "png_write.h"
#include "scene.h"

static const char *HELP =
    "Nimbus GLFW sample\n"
    "  mouse (hold left button)  look around\n"
    "  W A S D                   move (faster with Shift)\n"
    "  R / F                     climb / descend through the cloud layer\n"
    "  1 2 3 4 5                 weather: clear, sparse, cloudy, overcast, stormy (8 s transition)\n"
    "  6 / 7                     toggle cirrus / horizon gradient\n"
    "  Left / Right              sun azimuth;  Up / Down  sun elevation (time of day)\n"
    "  Esc                       quit\n";

typedef struct {
    NimbusContext *ctx;
    NimbusTexture *scene, *depth;
    float *color_buf, *depth_buf;
    int width, height;
    vec3 eye;
    float yaw, pitch;
    float sun_elevation, sun_azimuth;
    uint32_t preset, options;
    double mouse_x, mouse_y;
    int looking;
    /* The cloud shadow map, read back after each frame for the CPU scene's sunlight. */
    float *shadow_texels;
    SceneShadows shadows;
    /* The light at the camera (nimbus_context_read_ambient_light): the scene's sky ambient
     * dims under the clouds and takes their light. Off with --no-ambient-light. */
    NimbusAmbientLight ambient;
    int use_ambient;
} App;

static int fail(App *app, const char *what, int32_t rc) {
    fprintf(stderr, "%s failed (%d): %s\n", what, rc, nimbus_context_last_error(app ? app->ctx : NULL));
    return 1;
}

static int make_targets(App *app) {
    NimbusTextureDesc d = {0};
    nimbus_texture_destroy(app->scene);
    nimbus_texture_destroy(app->depth);
    app->scene = app->depth = NULL;
    free(app->color_buf);
    free(app->depth_buf);
    app->color_buf = (float *)malloc((size_t)app->width * app->height * 4 * sizeof(float));
    app->depth_buf = (float *)malloc((size_t)app->width * app->height * sizeof(float));
    if (!app->color_buf || !app->depth_buf) return 1;
    d.width = (uint32_t)app->width;
    d.height = (uint32_t)app->height;
    d.format = NIMBUS_FORMAT_RGBA32_FLOAT;
    if (nimbus_texture_create(app->ctx, &d, &app->scene) != NIMBUS_OK) return 1;
    d.format = NIMBUS_FORMAT_R32_FLOAT;
    if (nimbus_texture_create(app->ctx, &d, &app->depth) != NIMBUS_OK) return 1;
    return 0;
}

static void set_weather(App *app, double now) {
    static const char *names[] = {"", "clear", "sparse", "cloudy", "overcast", "stormy"};
    int32_t rc = nimbus_context_set_weather(app->ctx, app->preset, app->options, now, 8.0);
    if (rc != NIMBUS_OK) fail(app, "nimbus_context_set_weather", rc);
    else printf("weather -> %s%s%s\n", names[app->preset],
                app->options & NIMBUS_WEATHER_CIRRUS ? " + cirrus" : "",
                app->options & NIMBUS_WEATHER_HORIZON_GRADIENT ? " + horizon gradient" : "");
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods) {
    App *app = (App *)glfwGetWindowUserPointer(w);
    (void)scancode; (void)mods;
    if (action != GLFW_PRESS) return;
    if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(w, 1);
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_5) {
        app->preset = (uint32_t)(key - GLFW_KEY_1) + NIMBUS_PRESET_CLEAR;
        set_weather(app, glfwGetTime());
    }
    if (key == GLFW_KEY_6) { app->options ^= NIMBUS_WEATHER_CIRRUS; set_weather(app, glfwGetTime()); }
    if (key == GLFW_KEY_7) { app->options ^= NIMBUS_WEATHER_HORIZON_GRADIENT; set_weather(app, glfwGetTime()); }
}

static void on_mouse_button(GLFWwindow *w, int button, int action, int mods) {
    App *app = (App *)glfwGetWindowUserPointer(w);
    (void)mods;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        app->looking = action == GLFW_PRESS;
        glfwGetCursorPos(w, &app->mouse_x, &app->mouse_y);
    }
}

static void on_resize(GLFWwindow *w, int width, int height) {
    App *app = (App *)glfwGetWindowUserPointer(w);
    int32_t rc;
    if (width <= 0 || height <= 0) return; /* minimised */
    rc = nimbus_context_resize(app->ctx, (uint32_t)width, (uint32_t)height);
    if (rc != NIMBUS_OK) { fail(app, "nimbus_context_resize", rc); return; }
    app->width = width;
    app->height = height;
    if (make_targets(app)) fail(app, "creating the scene textures", -1);
}

static void update_camera(App *app, GLFWwindow *w, float dt) {
    vec3 fwd = v3(cosf(app->pitch) * sinf(app->yaw), sinf(app->pitch), -cosf(app->pitch) * cosf(app->yaw));
    vec3 flat = v3_norm(v3(fwd.x, 0.0f, fwd.z)), right = v3_norm(v3_cross(flat, v3(0.0f, 1.0f, 0.0f)));
    float speed = 150.0f + 0.5f * app->eye.y;
    if (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS) speed *= 5.0f;
    if (app->looking) {
        double x, y;
        glfwGetCursorPos(w, &x, &y);
        app->yaw += (float)(x - app->mouse_x) * 0.004f;
        app->pitch -= (float)(y - app->mouse_y) * 0.004f;
        app->pitch = app->pitch > 1.5f ? 1.5f : app->pitch < -1.5f ? -1.5f : app->pitch;
        app->mouse_x = x; app->mouse_y = y;
    }
    if (glfwGetKey(w, GLFW_KEY_W) == GLFW_PRESS) app->eye = v3_add(app->eye, v3_scale(flat, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_S) == GLFW_PRESS) app->eye = v3_sub(app->eye, v3_scale(flat, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_D) == GLFW_PRESS) app->eye = v3_add(app->eye, v3_scale(right, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_A) == GLFW_PRESS) app->eye = v3_sub(app->eye, v3_scale(right, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_R) == GLFW_PRESS) app->eye.y += speed * dt;
    if (glfwGetKey(w, GLFW_KEY_F) == GLFW_PRESS) app->eye.y -= speed * dt;
    if (app->eye.y < 2.0f) app->eye.y = 2.0f;
    if (glfwGetKey(w, GLFW_KEY_LEFT) == GLFW_PRESS) app->sun_azimuth -= 30.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_RIGHT) == GLFW_PRESS) app->sun_azimuth += 30.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_UP) == GLFW_PRESS) app->sun_elevation += 10.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_DOWN) == GLFW_PRESS) app->sun_elevation -= 10.0f * dt;
    app->sun_elevation = app->sun_elevation > 89.0f ? 89.0f : app->sun_elevation < -10.0f ? -10.0f : app->sun_elevation;
}

/* One frame: the CPU scene, uploaded, then clouds over it into `output` (NULL: the window). */
static int32_t draw(App *app, double time, NimbusTexture *output) {
    NimbusFrame frame = {0};
    NimbusTargets targets = {0};
    vec3 fwd = v3(cosf(app->pitch) * sinf(app->yaw), sinf(app->pitch), -cosf(app->pitch) * cosf(app->yaw));
    vec3 sun = sun_from_angles(app->sun_elevation, app->sun_azimuth);
    float low = app->sun_elevation < 20.0f ? (20.0f - app->sun_elevation) / 20.0f : 0.0f;
    vec3 sun_color = v3(1.0f, 1.0f - 0.4f * low, 1.0f - 0.65f * low);
    float illuminance = app->sun_elevation > 0.0f ? 10.0f * (1.0f - 0.5f * low) : 0.0f;
    float view_proj[16], fov = 1.1f;
    int32_t rc;
    size_t pixels = (size_t)app->width * app->height;

    mat_look_at(frame.view, app->eye, v3_add(app->eye, fwd), v3(0.0f, 1.0f, 0.0f));
    mat_perspective(frame.projection, fov, (float)app->width / (float)app->height, 1.0f, 400000.0f);
    mat_mul(view_proj, frame.projection, frame.view);
    /* The ground and towers darken under the clouds: the last frame's shadow map (none before
     * the first frame). A GPU host would bind the map instead of reading it back. */
    app->shadows.texels = NULL;
    if (nimbus_context_cloud_shadows(app->ctx, &app->shadows.info) == NIMBUS_OK) {
        size_t floats = 4 * (size_t)app->shadows.info.resolution * app->shadows.info.resolution;
        if (!app->shadow_texels) app->shadow_texels = malloc(floats * sizeof(float));
        if (app->shadow_texels &&
            nimbus_context_read_cloud_shadows(app->ctx, app->shadow_texels, floats) == NIMBUS_OK)
            app->shadows.texels = app->shadow_texels;
    }
    app->shadows.ambient = NULL;
    app->ambient.next = NULL;
    if (app->use_ambient &&
        nimbus_context_read_ambient_light(app->ctx, NIMBUS_VIEW_DEFAULT, &app->ambient) == NIMBUS_OK)
        app->shadows.ambient = &app->ambient;
    scene_render(app->color_buf, app->depth_buf, app->width, app->height, app->eye, fwd, fov, view_proj,
                 sun, sun_color, illuminance, &app->shadows);
    rc = nimbus_texture_write(app->scene, app->color_buf, pixels * 4 * sizeof(float));
    if (rc != NIMBUS_OK) return rc;
    rc = nimbus_texture_write(app->depth, app->depth_buf, pixels * sizeof(float));
    if (rc != NIMBUS_OK) return rc;
    frame.sun_direction[0] = sun.x; frame.sun_direction[1] = sun.y; frame.sun_direction[2] = sun.z;
    frame.sun_color[0] = sun_color.x; frame.sun_color[1] = sun_color.y; frame.sun_color[2] = sun_color.z;
    frame.sun_illuminance = illuminance;
    frame.time = time;
    targets.scene_color = app->scene;
    targets.scene_depth = app->depth;
    targets.output = output;
    return nimbus_context_render(app->ctx, &frame, &targets);
}

static int screenshot(App *app, double time, const char *path) {
    NimbusTextureDesc d = {0};
    NimbusTexture *out = NULL;
    uint8_t *rgba;
    size_t bytes = 0;
    int32_t rc;
    d.width = (uint32_t)app->width; d.height = (uint32_t)app->height; d.format = NIMBUS_FORMAT_RGBA8_UNORM_SRGB;
    if ((rc = nimbus_texture_create(app->ctx, &d, &out)) != NIMBUS_OK) return fail(app, "nimbus_texture_create", rc);
    if ((rc = draw(app, time, out)) != NIMBUS_OK) return fail(app, "nimbus_context_render", rc);
    nimbus_texture_byte_size(out, &bytes);
    rgba = (uint8_t *)malloc(bytes);
    if (!rgba) return 1;
    if ((rc = nimbus_texture_read(out, rgba, bytes)) != NIMBUS_OK) return fail(app, "nimbus_texture_read", rc);
    if (png_write_rgba8(path, rgba, d.width, d.height) != 0) { fprintf(stderr, "cannot write %s\n", path); return 1; }
    printf("wrote %s (%ux%u)\n", path, d.width, d.height);
    free(rgba);
    nimbus_texture_destroy(out);
    return 0;
}

static void log_to_stderr(int32_t level, const char *message, void *user) {
    (void)user;
    fprintf(stderr, "[nimbus %s] %s\n", level <= 1 ? "error" : "warning", message);
}

/* The whole file at `path` in a malloc'd buffer (NULL if it cannot be read). */
static unsigned char *read_file(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (buf = malloc((size_t)n)) != NULL && fread(buf, 1, (size_t)n, f) == (size_t)n) {
        *size = (size_t)n;
    } else {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    return buf;
}

/* Writes the context's noise volumes to `path` for the next start. */
static void write_noise_cache(NimbusContext *ctx, const char *path) {
    size_t size = 0;
    unsigned char *buf;
    FILE *f;
    if (nimbus_context_export_noise_cache(ctx, NULL, 0, &size) != NIMBUS_OK) return;
    buf = malloc(size);
    if (!buf) return;
    if (nimbus_context_export_noise_cache(ctx, buf, size, &size) == NIMBUS_OK && (f = fopen(path, "wb"))) {
        if (fwrite(buf, 1, size, f) == size) printf("wrote the noise cache %s (%lu bytes)\n", path, (unsigned long)size);
        fclose(f);
    }
    free(buf);
}

int main(int argc, char **argv) {
    App app;
    GLFWwindow *window;
    NimbusContextDesc desc = {0};
    NimbusWindowHandle handle = {0};
    NimbusCloudShadowsExt shadows_ext = {0};
    NimbusNoiseCacheExt cache_ext = {0};
    unsigned char *cache = NULL;
    size_t cache_size = 0;
    uint32_t from_cache = 0;
    char cache_path[1024] = "";
    const char *shot = NULL;
    int frames = 0, frame, i, w = 960, h = 540, no_shadows = 0, no_ambient = 0, start_preset = 0;
    double last, title_time, frame_ms = 0.0, started;
    char title[160];

    if (getenv("XDG_CACHE_HOME") && getenv("XDG_CACHE_HOME")[0])
        snprintf(cache_path, sizeof cache_path, "%s/nimbus-noise.cache", getenv("XDG_CACHE_HOME"));
    else if (getenv("HOME"))
        snprintf(cache_path, sizeof cache_path, "%s/.cache/nimbus-noise.cache", getenv("HOME"));

    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--screenshot") && i + 1 < argc) shot = argv[++i];
        else if (!strcmp(argv[i], "--no-cloud-shadows")) no_shadows = 1;
        else if (!strcmp(argv[i], "--no-ambient-light")) no_ambient = 1;
        else if (!strcmp(argv[i], "--preset") && i + 1 < argc && atoi(argv[i + 1]) >= 1 && atoi(argv[i + 1]) <= 5)
            start_preset = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--noise-cache") && i + 1 < argc) snprintf(cache_path, sizeof cache_path, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--no-noise-cache")) cache_path[0] = '\0';
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &w, &h) == 2) i++;
        else { fprintf(stderr, "usage: %s [--size WxH] [--frames N --screenshot FILE.png] [--no-cloud-shadows] [--no-ambient-light] [--preset 1-5] [--noise-cache FILE | --no-noise-cache]\n", argv[0]); return 2; }
    }
    if (shot && frames <= 0) frames = 1;

    memset(&app, 0, sizeof app);
    app.eye = v3(0.0f, 60.0f, 0.0f);
    app.pitch = 0.25f;
    app.sun_elevation = 35.0f;
    app.sun_azimuth = 150.0f;
    app.preset = NIMBUS_PRESET_SPARSE;
    app.use_ambient = !no_ambient;
    printf("%s", HELP);
    nimbus_set_log_callback(log_to_stderr, NULL, 2);

    if (!glfwInit()) { fprintf(stderr, "glfwInit failed\n"); return 1; }
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    window = glfwCreateWindow(w, h, "Nimbus", NULL, NULL);
    if (!window) { fprintf(stderr, "cannot open a window\n"); glfwTerminate(); return 1; }
    glfwGetFramebufferSize(window, &app.width, &app.height);

#ifdef NIMBUS_SAMPLE_WAYLAND
    handle.platform = NIMBUS_PLATFORM_WAYLAND;
    handle.display = glfwGetWaylandDisplay();
    handle.surface = glfwGetWaylandWindow(window);
#else
    handle.platform = NIMBUS_PLATFORM_X11;
    handle.display = glfwGetX11Display();
    handle.window = (uint64_t)glfwGetX11Window(window);
#endif
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.width = (uint32_t)app.width;
    desc.height = (uint32_t)app.height;
    desc.window = &handle;
    /* Cloud shadows on the CPU scene: a 40 km square around the camera, 128 texels a side
     * (312 m), refreshed over 4 frames. */
    shadows_ext.chain.s_type = NIMBUS_STYPE_CLOUD_SHADOWS;
    shadows_ext.extent = 40000.0f;
    shadows_ext.resolution = 128;
    desc.next = no_shadows ? NULL : &shadows_ext.chain;
    /* The noise volumes from the last start, if there is a cache: a stale or damaged one
     * (another library version) is ignored and the volumes baked (FALLBACK). */
    if (cache_path[0] && (cache = read_file(cache_path, &cache_size)) != NULL) {
        cache_ext.chain.s_type = NIMBUS_STYPE_NOISE_CACHE;
        cache_ext.chain.next = desc.next;
        cache_ext.data = cache;
        cache_ext.size = cache_size;
        cache_ext.flags = NIMBUS_NOISE_CACHE_FALLBACK;
        desc.next = &cache_ext.chain;
    }
    started = glfwGetTime();
    i = nimbus_context_create(&desc, &app.ctx);
    free(cache); /* read during the creation only */
    if (i != NIMBUS_OK) { fail(NULL, "nimbus_context_create", i); return 1; }
    nimbus_context_noise_from_cache(app.ctx, &from_cache);
    printf("nimbus %s on %s (noise %s)\n", nimbus_version_string(), nimbus_context_adapter_name(app.ctx),
           from_cache ? "from the cache" : "baked");
    if (make_targets(&app)) return fail(&app, "creating the scene textures", -1);
    /* --preset: start in another weather at once (1 clear ... 5 stormy, as the keys). */
    if (start_preset) {
        app.preset = (uint32_t)start_preset - 1u + NIMBUS_PRESET_CLEAR;
        i = nimbus_context_set_weather(app.ctx, app.preset, 0, 0.0, 0.0);
        if (i != NIMBUS_OK) return fail(&app, "nimbus_context_set_weather", i);
    }

    glfwSetWindowUserPointer(window, &app);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_mouse_button);
    glfwSetFramebufferSizeCallback(window, on_resize);

    last = title_time = glfwGetTime();
    for (frame = 0; !glfwWindowShouldClose(window) && (frames == 0 || frame < frames); frame++) {
        double now = frames ? frame / 30.0 : glfwGetTime();
        double wall = glfwGetTime();
        int32_t rc;
        glfwPollEvents();
        update_camera(&app, window, (float)(frames ? 1.0 / 30.0 : wall - last));
        rc = draw(&app, now, NULL);
        if (rc < 0) return fail(&app, "nimbus_context_render", rc);
        if (frame == 0) {
            /* The creation only submits the noise bake: the first frame waits for it. */
            printf("first frame %.0f ms after the context's creation began\n", (glfwGetTime() - started) * 1000.0);
            if (cache_path[0] && !from_cache) write_noise_cache(app.ctx, cache_path);
        }
        frame_ms = 0.9 * frame_ms + 0.1 * (glfwGetTime() - wall) * 1000.0;
        last = wall;
        if (wall - title_time > 0.5 || frames) {
            snprintf(title, sizeof title, "Nimbus | %.1f ms | altitude %.0f m | sun %.0f deg", frame_ms,
                     (double)app.eye.y, (double)app.sun_elevation);
            glfwSetWindowTitle(window, title);
            title_time = wall;
        }
    }
    if (shot && screenshot(&app, (frames - 1) / 30.0, shot)) return 1;
    printf("%d frames, last frame %.1f ms\n", frame, frame_ms);
    if (app.shadows.ambient)
        printf("ambient light from above: clouds' irradiance (%.3f, %.3f, %.3f), sky visibility %.3f\n",
               app.ambient.above_cloud_irradiance[0], app.ambient.above_cloud_irradiance[1],
               app.ambient.above_cloud_irradiance[2], app.ambient.above_sky_visibility);

    nimbus_texture_destroy(app.scene);
    nimbus_texture_destroy(app.depth);
    nimbus_context_destroy(app.ctx);
    free(app.color_buf);
    free(app.depth_buf);
    free(app.shadow_texels);
    glfwDestroyWindow(window);
    glfwTerminate();
    return 0;
}
