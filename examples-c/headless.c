/* Renders one view through the Nimbus C API only (no window, no GPU API of its own), reads the
 * result back and writes a PNG. The view is the Rust demo's "ground_looking_up" over a plain
 * sky color, so tests can compare it with a Rust render of the same view.
 *
 * Usage: headless OUT.png [WIDTH HEIGHT] */
#include <stdio.h>
#include <stdlib.h>

#include "nimbus.h"
#include "camera.h"
#include "png_write.h"

#define CHECK(call)                                                                          \
    do {                                                                                     \
        int32_t rc_ = (call);                                                                \
        if (rc_ < 0) {                                                                       \
            fprintf(stderr, "%s failed (%d): %s\n", #call, rc_, nimbus_context_last_error(ctx)); \
            return 1;                                                                        \
        }                                                                                    \
    } while (0)

int main(int argc, char **argv) {
    NimbusContext *ctx = NULL;
    NimbusTexture *scene = NULL, *output = NULL;
    NimbusContextDesc desc = {0};
    NimbusSettingsExt settings = {0};
    NimbusTextureDesc tex = {0};
    NimbusFrame frame = {0};
    NimbusTargets targets = {0};
    uint32_t w = 160, h = 90, i;
    float *pixels;
    uint8_t *rgba;
    size_t bytes;
    vec3 sun;

    if (argc != 2 && argc != 4) {
        fprintf(stderr, "usage: %s OUT.png [WIDTH HEIGHT]\n", argv[0]);
        return 2;
    }
    if (argc == 4) {
        w = (uint32_t)atoi(argv[2]);
        h = (uint32_t)atoi(argv[3]);
    }

    settings.chain.s_type = NIMBUS_STYPE_SETTINGS;
    settings.jitter = NIMBUS_JITTER_OFF; /* deterministic, for comparison */
    desc.next = &settings.chain;
    desc.abi_version = NIMBUS_ABI_VERSION;
    CHECK(nimbus_context_create(&desc, &ctx));
    printf("nimbus %s on %s\n", nimbus_version_string(), nimbus_context_adapter_name(ctx));

    tex.width = w;
    tex.height = h;
    tex.format = NIMBUS_FORMAT_RGBA32_FLOAT;
    CHECK(nimbus_texture_create(ctx, &tex, &scene));
    tex.format = NIMBUS_FORMAT_RGBA8_UNORM_SRGB;
    CHECK(nimbus_texture_create(ctx, &tex, &output));

    /* A plain linear sky color behind the clouds. */
    pixels = (float *)malloc((size_t)w * h * 4 * sizeof(float));
    if (!pixels) return 1;
    for (i = 0; i < w * h; i++) {
        pixels[i * 4 + 0] = 0.2f; pixels[i * 4 + 1] = 0.35f; pixels[i * 4 + 2] = 0.7f; pixels[i * 4 + 3] = 1.0f;
    }
    CHECK(nimbus_texture_write(scene, pixels, (size_t)w * h * 4 * sizeof(float)));
    free(pixels);

    mat_look_at(frame.view, v3(0.0f, 2.0f, 0.0f), v3(0.0f, 1000.0f, -1200.0f), v3(0.0f, 1.0f, 0.0f));
    mat_perspective(frame.projection, 75.0f * 0.01745329252f, (float)w / (float)h, 1.0f, 400000.0f);
    sun = sun_from_angles(55.0f, 150.0f);
    frame.sun_direction[0] = sun.x; frame.sun_direction[1] = sun.y; frame.sun_direction[2] = sun.z;
    frame.sun_illuminance = 10.0f; /* sun_color left zero: white */
    frame.time = 0.0;

    targets.scene_color = scene;
    targets.output = output;
    /* The default level traces one pixel in 16 per frame and accumulates the rest from earlier
       frames: a still view has every pixel of its own after 16 frames. */
    for (i = 0; i < 16; i++) {
        CHECK(nimbus_context_render(ctx, &frame, &targets));
    }

    CHECK(nimbus_texture_byte_size(output, &bytes));
    rgba = (uint8_t *)malloc(bytes);
    if (!rgba) return 1;
    CHECK(nimbus_texture_read(output, rgba, bytes));
    if (png_write_rgba8(argv[1], rgba, w, h) != 0) {
        fprintf(stderr, "could not write %s\n", argv[1]);
        return 1;
    }
    printf("wrote %s (%ux%u)\n", argv[1], w, h);
    free(rgba);
    nimbus_texture_destroy(scene);
    nimbus_texture_destroy(output);
    nimbus_context_destroy(ctx);
    return 0;
}
