/* The Vulkan hand-off's bad-input matrix: every bad instance, device, context description,
 * image, layout and semaphore gets its documented code and a message naming the problem (in
 * nimbus_context_last_error(NULL), and in the context's own when there is one), nothing bad is
 * submitted, and the context renders a good frame after each bad one. Plus the accepted
 * layouts walked through, semaphores, the queue lock, and context lifetimes on one device.
 *
 * Runs entirely under VK_LAYER_KHRONOS_validation with synchronization validation: any
 * validation warning or error, Nimbus's or the test's own (vkDestroyDevice reports leftover
 * objects), fails it. Built with -std=c99 -Wall -Wextra -Werror -pedantic.
 * Ends with "vulkan_test: N cases, M checks, F failures" (N: bad-input cases). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nimbus.h"
#include "camera.h"
#include "scene.h"
#include "vulkan_setup.h"

/* Struct layouts are part of the ABI (64-bit targets). */
#define PIN(name, cond) typedef char pin_##name[(cond) ? 1 : -1]
PIN(instance_size, sizeof(NimbusVulkanInstance) == 32);
PIN(device_ext_size, sizeof(NimbusVulkanDeviceExt) == 128);
PIN(image_size, sizeof(NimbusVulkanImage) == 48);
PIN(semaphore_size, sizeof(NimbusVulkanSemaphore) == 24);
PIN(targets_size, sizeof(NimbusVulkanTargets) == 136);
PIN(ext_instance_at, offsetof(NimbusVulkanDeviceExt, instance) == 16);
PIN(ext_features_at, offsetof(NimbusVulkanDeviceExt, enabled_features) == 80);
PIN(ext_lock_at, offsetof(NimbusVulkanDeviceExt, lock_queue) == 104);
PIN(targets_depth_at, offsetof(NimbusVulkanTargets, depth) == 56);
PIN(targets_waits_at, offsetof(NimbusVulkanTargets, waits) == 112);
/* The new code is an enum constant. */
PIN(requirement_code, 0 - NIMBUS_ERROR_VULKAN_REQUIREMENT == 13);

#define W 64
#define H 36

static int cases = 0, checks = 0, failures = 0;
static int validation = 1; /* the layer with synchronization validation (always, but for --no-validation) */

static int empty(const char *s) { return s == NULL || s[0] == '\0'; }

/* Whether `msg` contains one of the '|'-separated needles (ASCII case-insensitive). */
static int contains_any(const char *msg, const char *needles) {
    const char *n = needles;
    while (*n) {
        size_t len = strcspn(n, "|"), i, j;
        for (i = 0; msg[i]; i++) {
            for (j = 0; j < len && msg[i + j]; j++) {
                char a = msg[i + j], b = n[j];
                if (a >= 'A' && a <= 'Z') a = (char)(a - 'A' + 'a');
                if (b >= 'A' && b <= 'Z') b = (char)(b - 'A' + 'a');
                if (a != b) break;
            }
            if (j == len && len > 0) return 1;
        }
        n += len;
        if (*n == '|') n++;
    }
    return 0;
}

/* A call's code and messages: on failure the thread's message (and the context's, when `on`
 * is given: the same text) is set and names the problem (`needle`); on success both are empty. */
static void check(int32_t got, int32_t want, NimbusContext *on, const char *needle, const char *what, int line) {
    const char *thread_msg = nimbus_context_last_error(NULL);
    const char *ctx_msg = on ? nimbus_context_last_error(on) : NULL;
    checks++;
    if (want < 0) cases++;
    if (got != want) {
        printf("FAIL line %d: %s returned %s (%d), expected %s: %s\n", line, what, nimbus_result_name(got), got,
               nimbus_result_name(want), thread_msg);
        failures++;
        return;
    }
    if (want < 0) {
        checks++;
        if (empty(thread_msg) || (on && empty(ctx_msg))) {
            printf("FAIL line %d: %s gave no message (thread: '%s', context: '%s')\n", line, what, thread_msg,
                   ctx_msg ? ctx_msg : "-");
            failures++;
            return;
        }
        if (on && strcmp(thread_msg, ctx_msg) != 0) {
            printf("FAIL line %d: %s: thread and context messages differ\n", line, what);
            failures++;
            return;
        }
        if (needle) {
            checks++;
            if (!contains_any(thread_msg, needle)) {
                printf("FAIL line %d: %s: message '%s' names none of '%s'\n", line, what, thread_msg, needle);
                failures++;
                return;
            }
        }
        printf("ok   %-58s -> %-32s %s\n", what, nimbus_result_name(got), thread_msg);
    } else {
        checks++;
        if (!empty(thread_msg) || (on && !empty(ctx_msg))) {
            printf("FAIL line %d: %s succeeded but a message remains: '%s'\n", line, what, thread_msg);
            failures++;
        }
    }
}
#define EXPECT(call, code) check((call), (code), NULL, NULL, #call, __LINE__)
#define EXPECT_MSG(c, call, code, needle) check((call), (code), (c), (needle), #call, __LINE__)
#define TRUE(cond)                                                                                  \
    do {                                                                                            \
        checks++;                                                                                   \
        if (!(cond)) {                                                                              \
            printf("FAIL line %d: %s\n", __LINE__, #cond);                                          \
            failures++;                                                                             \
        }                                                                                           \
    } while (0)

/* ---- the good device, its context and images ----------------------------------------------- */
static VkSetup G;
static NimbusContext *ctx = NULL;
static NimbusSettingsExt settings;
static NimbusVulkanDeviceExt good_ext;
static VksImage color, depth;     /* the good pair: R16G16B16A16_SFLOAT and D32_SFLOAT */
static VksBuffer staging, readback;
static unsigned char *noise_cache = NULL;
static NimbusNoiseCacheExt noise_ext;
static float scene_color[W * H * 4], scene_depth[W * H];

/* The queue lock of the main context: calls counted, nesting and balance checked. */
static pthread_mutex_t queue_mutex = PTHREAD_MUTEX_INITIALIZER;
static long lock_calls = 0, unlock_calls = 0, lock_depth = 0, lock_errors = 0;
static void lock_queue(void *user) {
    (void)user;
    pthread_mutex_lock(&queue_mutex);
    lock_calls++;
    if (++lock_depth != 1) lock_errors++;
}
static void unlock_queue(void *user) {
    (void)user;
    if (--lock_depth != 0) lock_errors++;
    unlock_calls++;
    pthread_mutex_unlock(&queue_mutex);
}
static void host_lock(void *user) { (void)user; pthread_mutex_lock(&queue_mutex); }
static void host_unlock(void *user) { (void)user; pthread_mutex_unlock(&queue_mutex); }

static void frame_defaults(NimbusFrame *f) {
    vec3 sun = sun_from_angles(40.0f, 30.0f);
    memset(f, 0, sizeof *f);
    mat_look_at(f->view, v3(0.0f, 60.0f, 0.0f), v3(0.0f, 400.0f, -1200.0f), v3(0.0f, 1.0f, 0.0f));
    mat_perspective(f->projection, 1.2f, (float)W / (float)H, 1.0f, 100000.0f);
    f->sun_direction[0] = sun.x; f->sun_direction[1] = sun.y; f->sun_direction[2] = sun.z;
    f->sun_illuminance = 10.0f;
}

/* The good images in the layouts they are in, left there. */
static void good_targets(NimbusVulkanTargets *t) {
    memset(t, 0, sizeof *t);
    t->color = vks_nimbus_image(&color, VK_IMAGE_LAYOUT_UNDEFINED);
    t->depth = vks_nimbus_image(&depth, VK_IMAGE_LAYOUT_UNDEFINED);
}

static int32_t render(NimbusContext *c, const NimbusVulkanTargets *t) {
    NimbusFrame f;
    frame_defaults(&f);
    return nimbus_context_render_vulkan(c, &f, t);
}

static int32_t good_frame_on(NimbusContext *c) {
    NimbusVulkanTargets t;
    good_targets(&t);
    return render(c, &t);
}

/* A bad render, then a good one on the same context. */
static void bad_render(const NimbusVulkanTargets *t, int32_t want, const char *needle, const char *what, int line) {
    check(render(ctx, t), want, ctx, needle, what, line);
    check(good_frame_on(ctx), NIMBUS_OK, ctx, NULL, "  then a good frame", line);
}
#define BAD(t, code, needle, what) bad_render(&(t), (code), (needle), (what), __LINE__)

static int make_image(VksImage *img, VkFormat format, VkImageUsageFlags usage, uint32_t w, uint32_t h) {
    if (vks_image_create(&G, img, format, usage, w, h)) {
        printf("FAIL: %s\n", G.error);
        failures++;
        return 1;
    }
    return 0;
}

static int32_t create_on_good_device(NimbusContext **out) {
    NimbusContextDesc desc = {0};
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &good_ext.chain;
    return nimbus_context_create(&desc, out);
}

/* ---- the requirement calls -------------------------------------------------------------- */
static void test_requirement_calls(void) {
    const char *names[VKS_MAX_NAMES], *sentinel = "untouched";
    uint32_t n = 0, m, family = 99, i;
    NimbusVulkanInstance inst;
    NimbusVulkanDeviceRequirements *req = NULL;
    VkPhysicalDeviceFeatures2 f2;

    EXPECT_MSG(NULL, nimbus_vulkan_instance_extensions(NULL, &n, NULL), NIMBUS_ERROR_NULL_POINTER, "get_instance_proc_addr");
    EXPECT_MSG(NULL, nimbus_vulkan_instance_extensions(vks_gipa(), NULL, NULL), NIMBUS_ERROR_NULL_POINTER, "count");
    EXPECT(nimbus_vulkan_instance_extensions(vks_gipa(), &n, NULL), NIMBUS_OK);
    TRUE(n > 0 && n <= VKS_MAX_NAMES);
    if (n > 0 && n <= VKS_MAX_NAMES) {
        m = n - 1;
        for (i = 0; i < VKS_MAX_NAMES; i++) names[i] = sentinel;
        EXPECT_MSG(NULL, nimbus_vulkan_instance_extensions(vks_gipa(), &m, names), NIMBUS_ERROR_INVALID_ARGUMENT, "count");
        TRUE(m == n - 1 && names[0] == sentinel); /* nothing written on failure */
        m = n;
        EXPECT(nimbus_vulkan_instance_extensions(vks_gipa(), &m, names), NIMBUS_OK);
        TRUE(m == n && names[0] != sentinel && names[n - 1] != sentinel);
        for (i = 0; i < n; i++) TRUE(strncmp(names[i], "VK_", 3) == 0);
    }

    vks_nimbus_instance(&G, &inst);
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(NULL, (void *)G.physical_device, &req), NIMBUS_ERROR_NULL_POINTER, "instance");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, NULL, &req), NIMBUS_ERROR_NULL_POINTER, "physical_device");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, NULL), NIMBUS_ERROR_NULL_POINTER, "out");
    inst.get_instance_proc_addr = NULL;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, &req), NIMBUS_ERROR_NULL_POINTER, "get_instance_proc_addr");
    vks_nimbus_instance(&G, &inst);
    inst.instance = NULL;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, &req), NIMBUS_ERROR_NULL_POINTER, "instance");
    vks_nimbus_instance(&G, &inst);
    inst.api_version = VK_API_VERSION_1_0;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, &req), NIMBUS_ERROR_VULKAN_REQUIREMENT, "apiVersion|1.1");
    vks_nimbus_instance(&G, &inst);
    inst.extensions = NULL;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, &req), NIMBUS_ERROR_NULL_POINTER, "extensions");
    TRUE(req == NULL);

    vks_nimbus_instance(&G, &inst);
    EXPECT(nimbus_vulkan_device_requirements_create(&inst, (void *)G.physical_device, &req), NIMBUS_OK);
    if (!req) return;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_extensions(NULL, &n, NULL), NIMBUS_ERROR_NULL_POINTER, "req");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_extensions(req, NULL, NULL), NIMBUS_ERROR_NULL_POINTER, "count");
    EXPECT(nimbus_vulkan_device_requirements_extensions(req, &n, NULL), NIMBUS_OK);
    if (n > 0 && n <= VKS_MAX_NAMES) {
        m = n - 1;
        names[0] = sentinel;
        EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_extensions(req, &m, names), NIMBUS_ERROR_INVALID_ARGUMENT, "count");
        TRUE(m == n - 1 && names[0] == sentinel);
        m = VKS_MAX_NAMES; /* more room than needed is fine; the count comes back */
        EXPECT(nimbus_vulkan_device_requirements_extensions(req, &m, names), NIMBUS_OK);
        TRUE(m == n);
    }
    memset(&f2, 0, sizeof f2);
    f2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_merge_features(NULL, &f2), NIMBUS_ERROR_NULL_POINTER, "req");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_merge_features(req, NULL), NIMBUS_ERROR_NULL_POINTER, "features2");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_queue_family(NULL, &family), NIMBUS_ERROR_NULL_POINTER, "req");
    EXPECT_MSG(NULL, nimbus_vulkan_device_requirements_queue_family(req, NULL), NIMBUS_ERROR_NULL_POINTER, "family");
    TRUE(family == 99);
    EXPECT(nimbus_vulkan_device_requirements_queue_family(req, &family), NIMBUS_OK);
    TRUE(family == 0);
    nimbus_vulkan_device_requirements_destroy(req);
    nimbus_vulkan_device_requirements_destroy(NULL); /* no-op */
}

/* ---- context creation on the good device, described wrongly -------------------------------- */
static void expect_create(const NimbusVulkanDeviceExt *ext, const NimbusWindowHandle *window, uint32_t abi,
                          int32_t want, const char *needle, const char *what, int line) {
    NimbusContextDesc desc = {0};
    NimbusContext *out = (NimbusContext *)&desc, *before = out;
    desc.abi_version = abi;
    desc.next = &ext->chain;
    desc.window = window;
    if (window) { desc.width = 64; desc.height = 64; }
    check(nimbus_context_create(&desc, &out), want, NULL, needle, what, line);
    if (want < 0) TRUE(out == before); /* untouched on failure */
    else nimbus_context_destroy(out);
}
#define CREATE(ext, code, needle, what) expect_create(&(ext), NULL, NIMBUS_ABI_VERSION, (code), (needle), (what), __LINE__)

static void test_create_described_wrongly(void) {
    NimbusVulkanDeviceExt e, twice;
    NimbusWindowHandle win;
    const char *fewer[VKS_MAX_NAMES];
    uint32_t i, n;
    const char *surface = VK_KHR_SURFACE_EXTENSION_NAME;

    e = good_ext; e.enabled_features = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "enabled_features", "enabled_features NULL");
    e = good_ext; e.device = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "device", "device NULL");
    e = good_ext; e.physical_device = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "physical_device", "physical_device NULL");
    e = good_ext; e.queue = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "queue", "queue NULL");
    e = good_ext; e.instance.instance = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "instance", "instance.instance NULL");
    e = good_ext; e.instance.get_instance_proc_addr = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "get_instance_proc_addr", "instance.get_instance_proc_addr NULL");
    e = good_ext; e.extensions = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "extensions", "extensions NULL with extension_count > 0");
    e = good_ext; e.instance.extensions = NULL;
    CREATE(e, NIMBUS_ERROR_NULL_POINTER, "extensions", "instance.extensions NULL with a count");
    e = good_ext; e.lock_queue = lock_queue;
    CREATE(e, NIMBUS_ERROR_INVALID_ARGUMENT, "lock", "lock_queue without unlock_queue");
    e = good_ext; e.queue_family_index = 1;
    CREATE(e, NIMBUS_ERROR_VULKAN_REQUIREMENT, "queue family", "queue_family_index 1");
    e = good_ext; e.queue_index = 1;
    CREATE(e, NIMBUS_ERROR_VULKAN_REQUIREMENT, "queue", "queue_index 1");
    e = good_ext; e.instance.api_version = VK_API_VERSION_1_0;
    CREATE(e, NIMBUS_ERROR_VULKAN_REQUIREMENT, "apiVersion|1.1", "instance.api_version 1.0");
    /* The instance as described without VK_KHR_surface (the real one follows below). */
    e = good_ext;
    n = 0;
    for (i = 0; i < G.instance_extension_count; i++)
        if (strcmp(G.instance_extensions[i], surface) != 0) fewer[n++] = G.instance_extensions[i];
    TRUE(n + 1 == G.instance_extension_count); /* Nimbus asked for it */
    e.instance.extension_count = n;
    e.instance.extensions = fewer;
    CREATE(e, NIMBUS_ERROR_VULKAN_REQUIREMENT, surface, "instance extensions without VK_KHR_surface");
    /* Both Vulkan and a window. A window with a NULL display: refused as a combination. */
    memset(&win, 0, sizeof win);
    win.platform = NIMBUS_PLATFORM_X11;
    expect_create(&good_ext, &win, NIMBUS_ABI_VERSION, NIMBUS_ERROR_INVALID_ARGUMENT, "window",
                  "desc.window set with NimbusVulkanDeviceExt", __LINE__);
    /* A header of ABI 0.2 cannot know the struct. */
    expect_create(&good_ext, NULL, (NIMBUS_VERSION_MAJOR << 16) | 2u, NIMBUS_ERROR_UNKNOWN_STRUCT, "0.3",
                  "NimbusVulkanDeviceExt with abi_version 0.2", __LINE__);
    /* The same extension twice. */
    twice = good_ext;
    e = good_ext;
    e.chain.next = &twice.chain;
    twice.chain.next = NULL;
    CREATE(e, NIMBUS_ERROR_UNKNOWN_STRUCT, "twice", "NimbusVulkanDeviceExt twice in the chain");
}

/* ---- real instances and devices lacking something -------------------------------------------- */
static void test_real_misconfigurations(void) {
    VksOptions o;
    VkSetup s;
    NimbusVulkanInstance inst;
    NimbusVulkanDeviceRequirements *req = NULL;
    NimbusVulkanDeviceExt e;
    const char *omitted;

    /* An instance created without VK_KHR_surface: its requirements already name it. */
    memset(&o, 0, sizeof o);
    o.validation = validation;
    o.omit_instance_extension = VK_KHR_SURFACE_EXTENSION_NAME;
    if (vks_create_instance(&s, &o)) {
        printf("FAIL: instance without VK_KHR_surface: %s\n", s.error);
        failures++;
    } else {
        TRUE(s.omitted_instance_extension != NULL);
        vks_nimbus_instance(&s, &inst);
        check(nimbus_vulkan_device_requirements_create(&inst, (void *)s.physical_device, &req),
              NIMBUS_ERROR_VULKAN_REQUIREMENT, NULL, VK_KHR_SURFACE_EXTENSION_NAME,
              "requirements of an instance created without VK_KHR_surface", __LINE__);
        TRUE(req == NULL);
    }
    vks_destroy(&s);

    /* A device created without Nimbus's first device extension. */
    memset(&o, 0, sizeof o);
    o.validation = validation;
    o.omit_first_device_extension = 1;
    if (vks_create(&s, &o)) {
        printf("FAIL: device without an extension: %s\n", s.error);
        failures++;
    } else if (!s.omitted_device_extension) {
        printf("skip: Nimbus asks for no device extension\n");
    } else {
        omitted = s.omitted_device_extension;
        vks_device_ext(&s, &e);
        expect_create(&e, NULL, NIMBUS_ABI_VERSION, NIMBUS_ERROR_VULKAN_REQUIREMENT, omitted,
                      "device created without Nimbus's first device extension", __LINE__);
        printf("     (it was %s)\n", omitted);
    }
    vks_destroy(&s);

    /* A device created without the feature merge, and without the host's timeline semaphores. */
    memset(&o, 0, sizeof o);
    o.validation = validation;
    o.skip_feature_merge = 1;
    o.no_host_timeline = 1;
    if (vks_create(&s, &o)) {
        printf("FAIL: device without the merge: %s\n", s.error);
        failures++;
    } else {
        vks_device_ext(&s, &e);
        expect_create(&e, NULL, NIMBUS_ABI_VERSION, NIMBUS_ERROR_VULKAN_REQUIREMENT, "timelineSemaphore",
                      "device created without the feature merge", __LINE__);
    }
    vks_destroy(&s);

    /* The merge, then timelineSemaphore taken out again (when Nimbus asks for it). */
    memset(&o, 0, sizeof o);
    o.validation = validation;
    o.no_host_timeline = 1;
    o.clear_timeline_after_merge = 1;
    if (vks_create(&s, &o)) {
        printf("FAIL: device without timeline semaphores: %s\n", s.error);
        failures++;
    } else if (!s.merge_set_timeline) {
        printf("skip: Nimbus does not ask for timelineSemaphore\n");
    } else {
        vks_device_ext(&s, &e);
        expect_create(&e, NULL, NIMBUS_ABI_VERSION, NIMBUS_ERROR_VULKAN_REQUIREMENT, "timelineSemaphore",
                      "device with every feature but timelineSemaphore", __LINE__);
    }
    vks_destroy(&s);
}

/* ---- bad images, layouts, semaphores ------------------------------------------------------ */
static void test_render_inputs(void) {
    NimbusVulkanTargets t;
    NimbusFrame f;
    NimbusChainedStruct unknown = {999, NULL};
    NimbusVulkanSemaphore sems[17];
    VksImage rgba32f, r8, s8, r32f, color_no_attachment, color_no_src, color_no_sampled, depth_no_sampled,
        depth_no_attachment, depth_small;
    VkFormatProperties fp;
    int have_s8;
    const VkImageUsageFlags cu = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    const VkImageUsageFlags du = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;

    vkGetPhysicalDeviceFormatProperties(G.physical_device, VK_FORMAT_S8_UINT, &fp);
    have_s8 = (fp.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT) != 0;
    memset(&s8, 0, sizeof s8);
    /* Real images for every bad case, so a check that let one through would show up under
     * the validation layer. They stay in VK_IMAGE_LAYOUT_UNDEFINED: nothing may touch them. */
    if (make_image(&rgba32f, VK_FORMAT_R32G32B32A32_SFLOAT, cu, W, H) || make_image(&r8, VK_FORMAT_R8_UNORM, cu, W, H) ||
        (have_s8 && make_image(&s8, VK_FORMAT_S8_UINT, du, W, H)) || make_image(&r32f, VK_FORMAT_R32_SFLOAT, cu, W, H) ||
        make_image(&color_no_attachment, VK_FORMAT_R16G16B16A16_SFLOAT,
                   VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        make_image(&color_no_src, VK_FORMAT_R16G16B16A16_SFLOAT, cu | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        make_image(&color_no_sampled, VK_FORMAT_R16G16B16A16_SFLOAT,
                   VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, W, H) ||
        make_image(&depth_no_sampled, VK_FORMAT_D32_SFLOAT,
                   VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        make_image(&depth_no_attachment, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        make_image(&depth_small, VK_FORMAT_D32_SFLOAT, du, W / 2, H))
        return;
    /* The bad images claim the layouts the good ones are in. */
    rgba32f.layout = r8.layout = r32f.layout = color_no_attachment.layout = color_no_src.layout =
        color_no_sampled.layout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    s8.layout = depth_no_sampled.layout = depth_no_attachment.layout = depth_small.layout =
        VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;

    good_targets(&t);
    frame_defaults(&f);
    EXPECT(nimbus_context_render_vulkan(NULL, &f, &t), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, NULL, &t), NIMBUS_ERROR_NULL_POINTER, "frame");
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, NULL), NIMBUS_ERROR_NULL_POINTER, "targets");
    EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);

    /* Images. */
    good_targets(&t); t.color.image = 0;
    BAD(t, NIMBUS_ERROR_NULL_POINTER, "color", "color.image 0");
    good_targets(&t); t.color = vks_nimbus_image(&rgba32f, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "color R32G32B32A32_SFLOAT (unsupported)");
    good_targets(&t); t.color = vks_nimbus_image(&r8, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "color R8_UNORM (unsupported)");
    good_targets(&t); t.color.format = 12345;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "color format 12345 (no VkFormat)");
    if (have_s8) {
        good_targets(&t); t.depth = vks_nimbus_image(&s8, 0);
        BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "depth S8_UINT (no depth aspect)");
    }
    good_targets(&t); t.depth = vks_nimbus_image(&r32f, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "depth R32_SFLOAT (a color format)");
    good_targets(&t); t.depth = vks_nimbus_image(&color, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "the color image passed as depth");
    good_targets(&t); t.color = vks_nimbus_image(&depth, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "format", "the depth image passed as color");
    good_targets(&t); t.color = vks_nimbus_image(&color_no_attachment, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "usage", "color usage without COLOR_ATTACHMENT");
    good_targets(&t); t.depth = vks_nimbus_image(&depth_no_sampled, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "usage", "depth usage without SAMPLED");
    good_targets(&t); t.depth = vks_nimbus_image(&depth_small, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "size", "depth 32x36, color 64x36");
    good_targets(&t); t.color.width = 0;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "size", "color width 0");
    good_targets(&t); t.color.height = 0;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "size", "color height 0");
    good_targets(&t); t.depth.width = 0;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "size", "depth width 0");
    good_targets(&t); t.color.width = 100000;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "size", "color width 100000");
    good_targets(&t); t.color.mip_level = 1;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "mip", "color mip_level 1 of 1");
    good_targets(&t); t.depth.mip_level = 3; t.depth.mip_levels = 2;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "mip", "depth mip_level 3 of 2");
    good_targets(&t); t.color.array_layer = 1;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layer", "color array_layer 1 of 1");

    /* Layouts outside the accepted sets, as entry and as final. */
    good_targets(&t); t.color.layout = VK_IMAGE_LAYOUT_PREINITIALIZED;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "color layout PREINITIALIZED");
    good_targets(&t); t.color.final_layout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "color final_layout DEPTH_STENCIL_READ_ONLY");
    good_targets(&t); t.color.layout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "color layout DEPTH_STENCIL_ATTACHMENT");
    good_targets(&t); t.color.final_layout = VK_IMAGE_LAYOUT_PREINITIALIZED;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "color final_layout PREINITIALIZED");
    good_targets(&t); t.depth.layout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "depth layout PRESENT_SRC_KHR (color only)");
    good_targets(&t); t.depth.final_layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "depth final_layout SHADER_READ_ONLY (color only)");
    good_targets(&t); t.depth.layout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "depth layout COLOR_ATTACHMENT");
    good_targets(&t); t.depth.final_layout = 0x7fff;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "layout", "depth final_layout 0x7fff (no VkImageLayout)");
    /* Accepted layouts needing a usage the image lacks. */
    good_targets(&t); t.color = vks_nimbus_image(&color_no_src, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "TRANSFER_SRC", "color final TRANSFER_SRC without TRANSFER_SRC usage");
    good_targets(&t); t.color = vks_nimbus_image(&color_no_sampled, 0);
    t.color.layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "SAMPLED", "color layout SHADER_READ_ONLY without SAMPLED usage");
    good_targets(&t); t.color = vks_nimbus_image(&color_no_sampled, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "TRANSFER_DST", "color final TRANSFER_DST without TRANSFER_DST usage");
    good_targets(&t); t.depth = vks_nimbus_image(&depth_no_attachment, 0);
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "DEPTH_STENCIL_ATTACHMENT", "depth layout DS_ATTACHMENT without DS_ATTACHMENT usage");
    good_targets(&t); t.depth = vks_nimbus_image(&depth_no_attachment, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    t.depth.layout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL;
    BAD(t, NIMBUS_ERROR_INVALID_TARGET, "TRANSFER_SRC", "depth final TRANSFER_SRC without TRANSFER_SRC usage");

    /* Semaphores. */
    memset(sems, 0, sizeof sems);
    good_targets(&t); t.wait_count = 1;
    BAD(t, NIMBUS_ERROR_NULL_POINTER, "waits", "wait_count 1, waits NULL");
    good_targets(&t); t.signal_count = 1;
    BAD(t, NIMBUS_ERROR_NULL_POINTER, "signals", "signal_count 1, signals NULL");
    good_targets(&t); t.wait_count = 1; t.waits = sems; /* semaphore 0 */
    BAD(t, NIMBUS_ERROR_NULL_POINTER, "semaphore", "a wait on semaphore 0");
    sems[0].semaphore = 1; /* never used: the check comes first */
    sems[0].reserved = 1;
    good_targets(&t); t.signal_count = 1; t.signals = sems;
    BAD(t, NIMBUS_ERROR_INVALID_ARGUMENT, "reserved", "a signal with reserved 1");
    good_targets(&t); t.wait_count = 17; t.waits = sems;
    BAD(t, NIMBUS_ERROR_INVALID_ARGUMENT, "16", "wait_count 17");

    /* Chains and frames. */
    {
        /* Since ABI 0.3: a viewport chained to the targets. */
        NimbusViewportExt vp;
        memset(&vp, 0, sizeof vp);
        vp.chain.s_type = NIMBUS_STYPE_VIEWPORT;
        vp.x = W / 2; vp.y = 0; vp.width = W / 2; vp.height = H;
        good_targets(&t);
        t.next = &vp.chain;
        check(render(ctx, &t), NIMBUS_OK, ctx, NULL, "a viewport: the right half", __LINE__);
        good_targets(&t);
        t.next = &vp.chain;
        vp.x = W / 2 + 1;
        BAD(t, NIMBUS_ERROR_INVALID_TARGET, "viewport", "a viewport past the right edge");
        vp.x = 0; vp.width = 0;
        BAD(t, NIMBUS_ERROR_INVALID_TARGET, "viewport", "a viewport of width 0");
        vp.width = W; vp.chain.next = &unknown;
        BAD(t, NIMBUS_ERROR_UNKNOWN_STRUCT, NULL, "a viewport with an unknown struct after it");
    }
    {
        /* Since ABI 0.4: split screen on the host's images, a view per half (each its own
         * history), then the destroyed view refused. */
        NimbusViewportExt vp;
        NimbusViewExt ve;
        uint32_t view = 0;
        int i, half;
        memset(&vp, 0, sizeof vp);
        memset(&ve, 0, sizeof ve);
        vp.chain.s_type = NIMBUS_STYPE_VIEWPORT;
        vp.width = W / 2; vp.height = H;
        ve.chain.s_type = NIMBUS_STYPE_VIEW;
        EXPECT_MSG(ctx, nimbus_context_create_view(ctx, &view), NIMBUS_OK, NULL);
        ve.view = view;
        for (i = 0; i < 3; i++) {
            for (half = 0; half < 2; half++) {
                good_targets(&t);
                t.next = &vp.chain;
                vp.x = half ? W / 2 : 0;
                frame_defaults(&f);
                f.next = half ? &ve.chain : NULL;
                EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_OK, NULL);
            }
        }
        EXPECT_MSG(ctx, nimbus_context_destroy_view(ctx, view), NIMBUS_OK, NULL);
        good_targets(&t);
        frame_defaults(&f);
        f.next = &ve.chain;
        EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "not a live view");
        EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);
    }
    good_targets(&t); t.next = &unknown;
    BAD(t, NIMBUS_ERROR_UNKNOWN_STRUCT, NULL, "targets->next with s_type 999");
    good_targets(&t);
    frame_defaults(&f);
    f.next = &unknown;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_UNKNOWN_STRUCT, NULL);
    frame_defaults(&f);
    f.view[5] = NAN;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_FRAME, NULL);
    frame_defaults(&f);
    f.depth_flags = 0x80;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "0x80");
    EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);
    /* No depth image: nothing occludes. */
    good_targets(&t);
    memset(&t.depth, 0, sizeof t.depth);
    EXPECT_MSG(ctx, render(ctx, &t), NIMBUS_OK, NULL);

    EXPECT(nimbus_context_release_vulkan_images(NULL), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_MSG(ctx, nimbus_context_release_vulkan_images(ctx), NIMBUS_OK, NULL);
    EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);
    EXPECT_MSG(ctx, nimbus_context_release_vulkan_images(ctx), NIMBUS_OK, NULL); /* before destroying any */
    vks_image_destroy(&G, &rgba32f);
    vks_image_destroy(&G, &r8);
    if (have_s8) vks_image_destroy(&G, &s8);
    vks_image_destroy(&G, &r32f);
    vks_image_destroy(&G, &color_no_attachment);
    vks_image_destroy(&G, &color_no_src);
    vks_image_destroy(&G, &color_no_sampled);
    vks_image_destroy(&G, &depth_no_sampled);
    vks_image_destroy(&G, &depth_no_attachment);
    vks_image_destroy(&G, &depth_small);
}

/* ---- what works: every accepted layout, semaphores, the host's own use afterwards ----------- */
static void test_layouts_and_semaphores(void) {
    static const VkImageLayout walk[][4] = {
        /* color in, color out, depth in, depth out */
        {VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL},
        {VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL},
        {VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
         VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL},
        {VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
         VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
        /* Since ABI 0.4: the layouts wgpu has no state for, which Nimbus's own barriers move. */
        {VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL},
        {VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL},
        {VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_GENERAL,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
        {VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
    };
    NimbusVulkanTargets t;
    NimbusVulkanSemaphore wait, signal;
    VkSemaphore timeline, binary_in, binary_out;
    VkSemaphoreWaitInfo wi;
    VkPipelineStageFlags stage = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
    uint64_t value = 1, reached = 0;
    size_t i, k;
    int finite = 1;
    VkCommandBuffer cmd;

    for (i = 0; i < sizeof walk / sizeof walk[0]; i++) {
        TRUE(color.layout == walk[i][0] && depth.layout == walk[i][2]);
        t.next = NULL;
        good_targets(&t);
        t.color.final_layout = (uint32_t)walk[i][1];
        t.depth.final_layout = (uint32_t)walk[i][3];
        EXPECT_MSG(ctx, render(ctx, &t), NIMBUS_OK, NULL);
        color.layout = walk[i][1];
        depth.layout = walk[i][3];
    }
    /* The host's next use starts from the promised layouts (the validation layer checks). */
    TRUE(vks_read_color(&G, &color, &readback, NULL) == 0);
    for (k = 0; k < (size_t)W * H * 4; k++)
        if (!isfinite(vks_load_channel(color.format, readback.mapped, k / 4, (int)(k % 4)))) finite = 0;
    TRUE(finite);
    cmd = vks_begin_once(&G);
    vks_transition(cmd, &color, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    vks_transition(cmd, &depth, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
    TRUE(vks_end_once(&G, cmd) == 0);

    /* A timeline semaphore: the host signals 1, Nimbus waits on it and signals 2. */
    timeline = vks_semaphore(&G, 1, 0);
    binary_in = vks_semaphore(&G, 0, 0);
    binary_out = vks_semaphore(&G, 0, 0);
    TRUE(timeline && binary_in && binary_out);
    TRUE(vks_submit(&G, VK_NULL_HANDLE, 0, NULL, NULL, NULL, 1, &timeline, &value, VK_NULL_HANDLE) == VK_SUCCESS);
    memset(&wait, 0, sizeof wait);
    memset(&signal, 0, sizeof signal);
    wait.semaphore = VKS_HANDLE(timeline);
    wait.value = 1;
    wait.stage = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                 VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                 VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT;
    signal.semaphore = VKS_HANDLE(timeline);
    signal.value = 2;
    good_targets(&t);
    t.wait_count = 1; t.waits = &wait;
    t.signal_count = 1; t.signals = &signal;
    EXPECT_MSG(ctx, render(ctx, &t), NIMBUS_OK, NULL);
    memset(&wi, 0, sizeof wi);
    wi.sType = VK_STRUCTURE_TYPE_SEMAPHORE_WAIT_INFO;
    wi.semaphoreCount = 1;
    wi.pSemaphores = &timeline;
    value = 2;
    wi.pValues = &value;
    TRUE(vkWaitSemaphores(G.device, &wi, 30ull * 1000000000ull) == VK_SUCCESS);
    TRUE(vkGetSemaphoreCounterValue(G.device, timeline, &reached) == VK_SUCCESS && reached == 2);
    /* Binary semaphores: the host signals one, Nimbus waits on it and signals another. */
    TRUE(vks_submit(&G, VK_NULL_HANDLE, 0, NULL, NULL, NULL, 1, &binary_in, NULL, VK_NULL_HANDLE) == VK_SUCCESS);
    wait.semaphore = VKS_HANDLE(binary_in);
    wait.value = 0;
    wait.stage = 0; /* ALL_COMMANDS */
    signal.semaphore = VKS_HANDLE(binary_out);
    signal.value = 0;
    EXPECT_MSG(ctx, render(ctx, &t), NIMBUS_OK, NULL);
    TRUE(vks_submit(&G, VK_NULL_HANDLE, 1, &binary_out, NULL, &stage, 0, NULL, NULL, VK_NULL_HANDLE) == VK_SUCCESS);
    vks_wait_idle(&G);
    vkDestroySemaphore(G.device, timeline, NULL);
    vkDestroySemaphore(G.device, binary_in, NULL);
    vkDestroySemaphore(G.device, binary_out, NULL);
    EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);
}

/* ---- since ABI 0.4: one mip and one layer of a bigger image ----------------------------------- */

/* A color barrier over mips [mip, mip + mips) and layers [layer, layer + layers) of `image`. */
static void levels_barrier(VkCommandBuffer cmd, VkImage image, uint32_t mip, uint32_t mips, uint32_t layer,
                           uint32_t layers, VkImageLayout from, VkImageLayout to) {
    vks_image_barrier_range(cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, mip, mips, layer, layers, from, to);
}

/* A 2W x 2H image with 2 mips and 2 layers: Nimbus composites into mip 1 (W x H) of layer 1,
 * reading the W x H depth image. That subresource must equal the same frame composited into
 * the plain W x H color image (each on a fresh view, so both are a first frame), and the three
 * other subresources must keep their clear colors exactly. */
static void test_mips_and_layers(void) {
    static const float clears[4][4] = {
        {0.9f, 0.1f, 0.1f, 1.0f}, {0.1f, 0.9f, 0.1f, 1.0f}, {0.1f, 0.1f, 0.9f, 1.0f}, {0.2f, 0.35f, 0.7f, 1.0f}};
    const VkImageLayout att = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, src = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        dst = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    VksImage big;
    VksBuffer back;
    VkCommandBuffer cmd;
    VkBufferImageCopy regions[4];
    VkImageSubresourceRange range;
    VkClearColorValue clear;
    NimbusVulkanTargets t;
    NimbusFrame f;
    NimbusViewExt ve;
    uint32_t views[2] = {0, 0}, m, l, k, c;
    VkDeviceSize offsets[4], at = 0;
    size_t i, kept = 0, keep_total = 0, clouded = 0;
    const uint16_t *px;

    if (vks_image_create_levels(&G, &big, color.format,
                                VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                    VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                2 * W, 2 * H, 2, 2)) {
        printf("FAIL: %s\n", G.error);
        failures++;
        return;
    }
    for (k = 0; k < 4; k++) { /* k = mip * 2 + layer */
        offsets[k] = at;
        at += (VkDeviceSize)((2 * W) >> (k / 2)) * ((2 * H) >> (k / 2)) * 8;
    }
    if (vks_buffer_create(&G, &back, at, VK_BUFFER_USAGE_TRANSFER_DST_BIT)) {
        printf("FAIL: %s\n", G.error);
        failures++;
        vks_image_destroy(&G, &big);
        return;
    }
    /* Clear each subresource of the big image, and the plain image with mip 1 / layer 1's color. */
    cmd = vks_begin_once(&G);
    levels_barrier(cmd, big.image, 0, 2, 0, 2, VK_IMAGE_LAYOUT_UNDEFINED, dst);
    memset(&range, 0, sizeof range);
    range.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    range.levelCount = 1;
    range.layerCount = 1;
    for (k = 0; k < 4; k++) {
        range.baseMipLevel = k / 2;
        range.baseArrayLayer = k % 2;
        memcpy(clear.float32, clears[k], sizeof clear.float32);
        vkCmdClearColorImage(cmd, big.image, dst, &clear, 1, &range);
    }
    levels_barrier(cmd, big.image, 0, 2, 0, 2, dst, att);
    vks_transition(cmd, &color, dst);
    range.baseMipLevel = 0;
    range.baseArrayLayer = 0;
    memcpy(clear.float32, clears[3], sizeof clear.float32);
    vkCmdClearColorImage(cmd, color.image, dst, &clear, 1, &range);
    vks_transition(cmd, &color, att);
    TRUE(vks_end_once(&G, cmd) == 0);

    EXPECT_MSG(ctx, nimbus_context_create_view(ctx, &views[0]), NIMBUS_OK, NULL);
    EXPECT_MSG(ctx, nimbus_context_create_view(ctx, &views[1]), NIMBUS_OK, NULL);
    memset(&ve, 0, sizeof ve);
    ve.chain.s_type = NIMBUS_STYPE_VIEW;
    frame_defaults(&f);
    f.next = &ve.chain;
    /* The plain image. */
    good_targets(&t);
    t.color.final_layout = (uint32_t)src;
    ve.view = views[0];
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_OK, NULL);
    color.layout = src;
    /* Mip 1 of layer 1. */
    good_targets(&t);
    t.color = vks_nimbus_image(&big, src);
    t.color.mip_levels = 2;
    t.color.array_layers = 2;
    t.color.mip_level = 1;
    t.color.array_layer = 1;
    t.color.layout = (uint32_t)att;
    ve.view = views[1];
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_OK, NULL);
    /* Out of range, and sizes compared at the used mips. */
    t.color.mip_level = 2;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "mip_level 2");
    t.color.mip_level = 0;
    t.color.layout = (uint32_t)att;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "at mip 0");
    t.color.mip_level = 1;
    t.color.array_layer = 2;
    EXPECT_MSG(ctx, nimbus_context_render_vulkan(ctx, &f, &t), NIMBUS_ERROR_INVALID_TARGET, "array_layer 2");
    EXPECT_MSG(ctx, nimbus_context_destroy_view(ctx, views[0]), NIMBUS_OK, NULL);
    EXPECT_MSG(ctx, nimbus_context_destroy_view(ctx, views[1]), NIMBUS_OK, NULL);
    EXPECT_MSG(ctx, nimbus_context_release_vulkan_images(ctx), NIMBUS_OK, NULL);

    /* Read back every subresource: mip 1 / layer 1 is in TRANSFER_SRC, the rest still in
     * COLOR_ATTACHMENT (Nimbus touched only what it was given). */
    cmd = vks_begin_once(&G);
    levels_barrier(cmd, big.image, 0, 1, 0, 2, att, src);
    levels_barrier(cmd, big.image, 1, 1, 0, 1, att, src);
    memset(regions, 0, sizeof regions);
    for (k = 0; k < 4; k++) {
        regions[k].bufferOffset = offsets[k];
        regions[k].imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
        regions[k].imageSubresource.mipLevel = k / 2;
        regions[k].imageSubresource.baseArrayLayer = k % 2;
        regions[k].imageSubresource.layerCount = 1;
        regions[k].imageExtent.width = (2 * W) >> (k / 2);
        regions[k].imageExtent.height = (2 * H) >> (k / 2);
        regions[k].imageExtent.depth = 1;
    }
    vkCmdCopyImageToBuffer(cmd, big.image, src, back.buffer, 4, regions);
    TRUE(vks_end_once(&G, cmd) == 0);
    TRUE(vks_read_color(&G, &color, &readback, NULL) == 0);
    for (k = 0; k < 3; k++) {
        m = k / 2;
        l = k % 2;
        px = (const uint16_t *)((const uint8_t *)back.mapped + offsets[k]);
        for (i = 0; i < (size_t)((2 * W) >> m) * ((2 * H) >> m); i++) {
            int same = 1;
            for (c = 0; c < 4; c++)
                if (px[i * 4 + c] != vks_float_to_half(clears[k][c])) same = 0;
            kept += (size_t)same;
            keep_total++;
        }
        (void)l;
    }
    px = (const uint16_t *)((const uint8_t *)back.mapped + offsets[3]);
    for (i = 0; i < (size_t)W * H; i++)
        for (c = 0; c < 3; c++)
            if (px[i * 4 + c] != vks_float_to_half(clears[3][c])) { clouded++; break; }
    printf("     mip 1 of layer 1: %zu of %d pixels with clouds, %s the plain image's; other subresources: %zu of %zu pixels kept\n",
           clouded, W * H, memcmp(px, readback.mapped, (size_t)W * H * 8) == 0 ? "identical to" : "DIFFERENT from",
           kept, keep_total);
    TRUE(memcmp(px, readback.mapped, (size_t)W * H * 8) == 0);
    TRUE(clouded > (size_t)W * H / 4);
    TRUE(kept == keep_total);
    vks_buffer_destroy(&G, &back);
    vks_image_destroy(&G, &big);
}

/* ---- an owned context has no host device ----------------------------------------------------- */
static void test_owned_context(void) {
    NimbusContextDesc desc = {0};
    NimbusContext *owned = NULL;
    NimbusVulkanTargets t;
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &settings.chain;
    EXPECT(nimbus_context_create(&desc, &owned), NIMBUS_OK);
    if (!owned) return;
    good_targets(&t);
    EXPECT_MSG(owned, render(owned, &t), NIMBUS_ERROR_INVALID_ARGUMENT, "NimbusVulkanDeviceExt");
    EXPECT_MSG(owned, nimbus_context_release_vulkan_images(owned), NIMBUS_ERROR_INVALID_ARGUMENT, "NimbusVulkanDeviceExt");
    {
        NimbusVulkanShadowImage img;
        memset(&img, 0, sizeof img);
        EXPECT_MSG(owned, nimbus_context_cloud_shadow_vulkan_image(owned, &img), NIMBUS_ERROR_INVALID_ARGUMENT, "NimbusVulkanDeviceExt");
    }
    nimbus_context_destroy(owned);
}

/* ---- contexts come and go on one device ---------------------------------------------------- */
/* `cycles` create / render one frame / destroy cycles on `dev` (ext: its description, images
 * its own). RSS is read after every cycle; with `judge`, growth beyond 8 MiB from the lowest
 * reading of cycles 5-9 (after the device's first contexts warm it up) to the lowest of cycles
 * 20-24 fails: a leak of 0.6 MiB a context would. The lowest of five, because the driver's
 * worker threads now and then still hold ~30 MiB of heap for a moment after a context is gone
 * (seen on llvmpipe under load: one cycle reads 160 MiB RSS between neighbours at 133, and
 * mallinfo2 55.8 MiB of heap in use against 24.3): a leak raises every later reading, a
 * passing spike only one. (The validation layer's own
 * bookkeeping grows by about 0.5 MiB per context with sync validation, Nimbus's RSS not at all,
 * so RSS is judged on a device without the layer.) */
static void lifetimes(VkSetup *dev, NimbusVulkanDeviceExt *ext, VksImage *c_img, VksImage *d_img, int cycles,
                      int judge, const char *label) {
    NimbusContextDesc desc = {0};
    double early = 1e30, late = 1e30, rss;
    int i;
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &ext->chain;
    for (i = 1; i <= cycles; i++) {
        NimbusContext *c = NULL;
        NimbusVulkanTargets t;
        int32_t rc = nimbus_context_create(&desc, &c);
        if (rc != NIMBUS_OK) {
            printf("FAIL: %s cycle %d: nimbus_context_create: %s: %s\n", label, i, nimbus_result_name(rc),
                   nimbus_context_last_error(NULL));
            failures++;
            return;
        }
        memset(&t, 0, sizeof t);
        t.color = vks_nimbus_image(c_img, 0);
        t.depth = vks_nimbus_image(d_img, 0);
        rc = render(c, &t);
        checks++;
        if (rc != NIMBUS_OK) {
            printf("FAIL: %s cycle %d: render: %s: %s\n", label, i, nimbus_result_name(rc), nimbus_context_last_error(c));
            failures++;
        }
        nimbus_context_destroy(c); /* releases the images, waits for its work */
        rss = vks_rss_mib();
        if (i >= 5 && i <= 9 && rss < early) early = rss;
        if (i >= 20 && i <= 24 && rss < late) late = rss;
        if (i == 5 || i == 24) printf("     %s: context cycle %d: RSS %.1f MiB\n", label, i, rss);
    }
    (void)dev;
    if (judge && cycles >= 24) {
        checks++;
        if (late - early > 8.0) {
            printf("FAIL: %s: RSS grew by %.1f MiB from cycles 5-9 to 20-24 (lowest of each: %.1f, %.1f)\n",
                   label, late - early, early, late);
            failures++;
        } else {
            printf("ok   %s: RSS grew by %.1f MiB from cycles 5-9 to 20-24 (lowest of each; at most 8)\n", label,
                   late - early);
        }
    }
}

/* The RSS case on a device without the validation layer (its own images). */
static void test_lifetimes_without_layer(void) {
    VkSetup d;
    VksOptions o;
    NimbusVulkanDeviceExt e;
    VksImage c_img, d_img;
    VksBuffer up;
    memset(&o, 0, sizeof o);
    if (vks_create(&d, &o) ||
        vks_image_create(&d, &c_img, VK_FORMAT_R16G16B16A16_SFLOAT,
                         VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        vks_image_create(&d, &d_img, VK_FORMAT_D32_SFLOAT,
                         VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                             VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        vks_buffer_create(&d, &up, vks_staging_size(c_img.format, d_img.format, W, H), VK_BUFFER_USAGE_TRANSFER_SRC_BIT)) {
        printf("FAIL: a device without the layer: %s\n", d.error);
        failures++;
        vks_destroy(&d);
        return;
    }
    vks_write_scene(&up, c_img.format, d_img.format, W, H, scene_color, scene_depth);
    if (vks_upload_scene(&d, &up, &c_img, &d_img, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL) == 0) {
        vks_device_ext(&d, &e);
        e.chain.next = good_ext.chain.next; /* the noise cache and the settings */
        lifetimes(&d, &e, &c_img, &d_img, 24, 1, "without the layer");
    }
    vks_image_destroy(&d, &c_img);
    vks_image_destroy(&d, &d_img);
    vks_buffer_destroy(&d, &up);
    vks_destroy(&d);
}

/* ---- the cloud shadow map as the host's VkImage (since ABI 0.6) --------------------------- */

/* A context with a 32² shadow map: its VkImage is reported in SHADER_READ_ONLY_OPTIMAL after
 * each frame; the host copies it with its own commands (transitioning it out and back, which
 * the layer checks against the layout Nimbus really left), gets the texels
 * nimbus_context_read_cloud_shadows gives (read first: the read-back must restore the layout),
 * and Nimbus's next frame finds the layout it expects. */
static void test_cloud_shadow_image(void) {
    NimbusContextDesc desc = {0};
    NimbusCloudShadowsExt cs = {0};
    NimbusVulkanShadowImage img;
    NimbusChainedStruct unknown = {999, NULL};
    NimbusContext *c = NULL;
    float texels[4 * 32 * 32];
    VkCommandBuffer cmd;
    VkBufferImageCopy region;
    size_t i, bad = 0, shaded = 0;

    memset(&img, 0, sizeof img);
    EXPECT(nimbus_context_cloud_shadow_vulkan_image(NULL, &img), NIMBUS_ERROR_NULL_POINTER);
    EXPECT_MSG(ctx, nimbus_context_cloud_shadow_vulkan_image(ctx, &img), NIMBUS_ERROR_NOT_READY, "NimbusCloudShadowsExt");
    cs.chain.s_type = NIMBUS_STYPE_CLOUD_SHADOWS;
    cs.chain.next = &good_ext.chain;
    cs.extent = 8000.0f;
    cs.resolution = 32;
    cs.update_slices = 1;
    desc.abi_version = NIMBUS_ABI_VERSION;
    desc.next = &cs.chain;
    EXPECT(nimbus_context_create(&desc, &c), NIMBUS_OK);
    if (!c) return;
    EXPECT_MSG(c, nimbus_context_cloud_shadow_vulkan_image(c, &img), NIMBUS_ERROR_NOT_READY, "render a frame");
    EXPECT_MSG(c, good_frame_on(c), NIMBUS_OK, NULL);
    EXPECT_MSG(c, nimbus_context_cloud_shadow_vulkan_image(c, NULL), NIMBUS_ERROR_NULL_POINTER, "out");
    img.next = &unknown;
    EXPECT_MSG(c, nimbus_context_cloud_shadow_vulkan_image(c, &img), NIMBUS_ERROR_UNKNOWN_STRUCT, NULL);
    img.next = NULL;
    EXPECT_MSG(c, nimbus_context_cloud_shadow_vulkan_image(c, &img), NIMBUS_OK, NULL);
    TRUE(img.image != 0 && img.format == VK_FORMAT_R16G16B16A16_SFLOAT && img.resolution == 32);
    TRUE(img.layout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    TRUE((img.usage & (VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT)) ==
         (VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT));

    /* Nimbus's own read-back first: it must leave the image in the layout it reports. */
    EXPECT_MSG(c, nimbus_context_read_cloud_shadows(c, texels, 4 * 32 * 32), NIMBUS_OK, NULL);
    /* The host's copy, on its queue after Nimbus's work (submission order: no semaphore). */
    cmd = vks_begin_once(&G);
    TRUE(cmd != VK_NULL_HANDLE);
    if (!cmd) { nimbus_context_destroy(c); return; }
    vks_image_barrier(cmd, (VkImage)(uintptr_t)img.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                      VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    memset(&region, 0, sizeof region);
    region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    region.imageSubresource.layerCount = 1;
    region.imageExtent.width = img.resolution;
    region.imageExtent.height = img.resolution;
    region.imageExtent.depth = 1;
    vkCmdCopyImageToBuffer(cmd, (VkImage)(uintptr_t)img.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback.buffer, 1, &region);
    vks_image_barrier(cmd, (VkImage)(uintptr_t)img.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    TRUE(vks_end_once(&G, cmd) == 0);
    for (i = 0; i < 4 * 32 * 32; i++) {
        float host = vks_half_to_float(((const uint16_t *)readback.mapped)[i]);
        if (host != texels[i]) bad++;
        if (i % 4 == 3 && texels[i] < 0.999f) shaded++;
    }
    printf("     shadow map VkImage: %lu of %d values differ from the read-back, %lu of 1024 texels shaded\n",
           (unsigned long)bad, 4 * 32 * 32, (unsigned long)shaded);
    TRUE(bad == 0 && shaded > 0);
    /* Nimbus's next frames start from the layout the host returned the image to. */
    EXPECT_MSG(c, good_frame_on(c), NIMBUS_OK, NULL);
    EXPECT_MSG(c, good_frame_on(c), NIMBUS_OK, NULL);
    vks_wait_idle(&G);
    nimbus_context_destroy(c);
}

int main(int argc, char **argv) {
    VksOptions o;
    int32_t rc;

    setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the validation layer's stderr */
    if (argc > 1 && strcmp(argv[1], "--no-validation") == 0) {
        /* For measuring without the layer (e.g. RSS); the test proper runs with it. */
        validation = 0;
        printf("vulkan_test: WITHOUT the validation layer\n");
    } else if (argc > 1) {
        printf("usage: %s [--no-validation]\n", argv[0]);
        return 2;
    }
    /* The good device: validation with synchronization validation, host lock hooks. */
    memset(&o, 0, sizeof o);
    o.validation = validation;
    o.lock = host_lock;
    o.unlock = host_unlock;
    if (vks_create(&G, &o)) {
        printf("vulkan_test: cannot set up Vulkan: %s\n", G.error);
        vks_destroy(&G);
        return 1;
    }
    printf("device %s, %u instance and %u device extensions, requirements %s after vkCreateDevice\n",
           G.properties.deviceName, G.instance_extension_count, G.device_extension_count,
           G.requirements ? "kept (their structs are in the chain)" : "destroyed");

    if (make_image(&color, VK_FORMAT_R16G16B16A16_SFLOAT,
                   VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                       VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        make_image(&depth, VK_FORMAT_D32_SFLOAT,
                   VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                       VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, W, H) ||
        vks_buffer_create(&G, &staging, vks_staging_size(color.format, depth.format, W, H), VK_BUFFER_USAGE_TRANSFER_SRC_BIT) ||
        vks_buffer_create(&G, &readback, (VkDeviceSize)W * H * 8, VK_BUFFER_USAGE_TRANSFER_DST_BIT)) {
        printf("vulkan_test: %s\n", G.error);
        return 1;
    }
    {
        NimbusFrame f;
        float vp[16];
        vec3 eye = v3(0.0f, 60.0f, 0.0f), fwd = v3_norm(v3(0.0f, 340.0f, -1200.0f));
        frame_defaults(&f);
        mat_mul(vp, f.projection, f.view);
        scene_render(scene_color, scene_depth, W, H, eye, fwd, 1.2f, vp, sun_from_angles(40.0f, 30.0f),
                     v3(1.0f, 1.0f, 1.0f), 10.0f, NULL);
        vks_write_scene(&staging, color.format, depth.format, W, H, scene_color, scene_depth);
        if (vks_upload_scene(&G, &staging, &color, &depth, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                             VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL)) {
            printf("vulkan_test: upload: %s\n", G.error);
            return 1;
        }
    }

    test_requirement_calls();

    settings.chain.s_type = NIMBUS_STYPE_SETTINGS;
    settings.jitter = NIMBUS_JITTER_OFF;
    vks_device_ext(&G, &good_ext);
    test_create_described_wrongly();

    /* The main context, with the queue lock. */
    good_ext.chain.next = &settings.chain;
    good_ext.lock_queue = lock_queue;
    good_ext.unlock_queue = unlock_queue;
    rc = create_on_good_device(&ctx);
    check(rc, NIMBUS_OK, NULL, NULL, "nimbus_context_create on the host's device", __LINE__);
    if (!ctx) {
        printf("vulkan_test: no context\n");
        return 1;
    }
    printf("nimbus %s on %s\n", nimbus_version_string(), nimbus_context_adapter_name(ctx));
    EXPECT_MSG(ctx, good_frame_on(ctx), NIMBUS_OK, NULL);
    /* Every later context on this device starts from ctx's noise cache (since ABI 0.6) instead
     * of baking the noise again: the lifetime cycles below make dozens. */
    {
        size_t size = 0;
        EXPECT_MSG(ctx, nimbus_context_export_noise_cache(ctx, NULL, 0, &size), NIMBUS_OK, NULL);
        noise_cache = malloc(size);
        if (noise_cache) {
            EXPECT_MSG(ctx, nimbus_context_export_noise_cache(ctx, noise_cache, size, &size), NIMBUS_OK, NULL);
            memset(&noise_ext, 0, sizeof noise_ext);
            noise_ext.chain.s_type = NIMBUS_STYPE_NOISE_CACHE;
            noise_ext.chain.next = good_ext.chain.next;
            noise_ext.data = noise_cache;
            noise_ext.size = size;
            good_ext.chain.next = &noise_ext.chain;
        }
    }

    test_render_inputs();
    test_layouts_and_semaphores();
    test_mips_and_layers();
    test_cloud_shadow_image();
    vks_wait_idle(&G);
    printf("     queue lock: %ld lock and %ld unlock calls, %ld out of order\n", lock_calls, unlock_calls, lock_errors);
    TRUE(lock_calls > 0 && lock_calls == unlock_calls && lock_errors == 0 && lock_depth == 0);
    nimbus_context_destroy(ctx);
    ctx = NULL;

    good_ext.lock_queue = good_ext.unlock_queue = NULL;
    good_ext.lock_user_data = NULL;
    /* Contexts come and go: under the layer (which checks each one and, at vkDestroyDevice,
     * that nothing was left behind), then on a device without it for RSS. */
    lifetimes(&G, &good_ext, &color, &depth, validation ? 5 : 24, !validation, "under the layer");
    if (validation) test_lifetimes_without_layer();
    test_owned_context();
    test_real_misconfigurations();

    vks_image_destroy(&G, &color);
    vks_image_destroy(&G, &depth);
    vks_buffer_destroy(&G, &staging);
    vks_buffer_destroy(&G, &readback);
    vks_destroy(&G); /* leftovers on the device would be reported here */
    free(noise_cache);
    {
        int n = vks_validation_messages();
        printf("validation messages: %d\n", n);
        checks++;
        if (n != 0) failures++;
    }
    if (!validation) printf("vulkan_test: WITHOUT the validation layer\n");
    printf("vulkan_test: %d cases, %d checks, %d failures\n", cases, checks, failures);
    return failures == 0 ? 0 : 1;
}
