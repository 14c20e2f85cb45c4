/* The Nimbus Vulkan host: a plain C Vulkan program written from nimbus.h alone, bringing its
 * own device. It creates its instance and device with Nimbus's requirements merged into its
 * own (vulkan_setup.h), draws its scene into its own color image and a real D32_SFLOAT depth
 * image, hands both to Nimbus every frame (nimbus_context_render_vulkan) in the layouts its
 * render pass left them in, gets the color back in the layout it blits from and shows it in a
 * GLFW window (its swapchain, vkCmdBlitImage), or writes it to a PNG with no window at all.
 *
 * The scene is scene.h's, rendered on the CPU (linear color and clip depth) and uploaded; a
 * real engine's render pass would draw it. The render pass here (loadOp LOAD on both
 * attachments, drawing nothing) stands for that pass: its final layouts are the layouts the
 * images are in when Nimbus's work runs.
 *
 * Usage: vulkan_host [--size WxH] [--frames N] [--screenshot FILE.png] [--validation]
 *                    [--layouts K] [--semaphores] [--recreate N] [--owned] [--lock]
 *                    [--time-handoff] [--check-occluded] [--format rgba16f|srgb8]
 *   --screenshot     no window: N frames (default 1) on a fixed 1/30 s clock with the camera
 *                    moving deterministically; the last frame is written as an sRGB PNG
 *   --validation     VK_LAYER_KHRONOS_validation with synchronization validation; prints
 *                    "validation messages: N" at exit and fails when N > 0
 *   --layouts K      the (entry, final) layouts of color and depth handed to Nimbus (0..3)
 *   --semaphores     a timeline semaphore between the host's submissions and Nimbus's
 *                    (otherwise same-queue submission order)
 *   --recreate N     then creates, renders one frame with and destroys the context N more
 *                    times on the same VkDevice, printing RSS each time
 *   --owned          the same frames on an owned Nimbus context with NimbusTextures (for
 *                    comparing the two PNGs)
 *   --lock           queue lock callbacks around a mutex; prints "queue lock calls: N"
 *   --time-handoff   prints the average CPU time of nimbus_context_render_vulkan
 *   --check-occluded fails when a pixel nearer than 1000 m changed (Nimbus must not touch it)
 *   --format         the color image format: R16G16B16A16_SFLOAT (default) or R8G8B8A8_SRGB */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "nimbus.h"
#include "camera.h"
#include "png_write.h"
#include "scene.h"
#include "vulkan_setup.h" /* includes vulkan.h: GLFW then declares its Vulkan functions */

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

static const char *HELP =
    "Nimbus Vulkan host (the host's own VkDevice)\n"
    "  mouse (hold left button)  look around\n"
    "  W A S D                   move (faster with Shift)\n"
    "  R / F                     climb / descend through the cloud layer\n"
    "  1 2 3 4 5                 weather: clear, sparse, cloudy, overcast, stormy (8 s transition)\n"
    "  6 / 7                     toggle cirrus / horizon gradient\n"
    "  Left / Right              sun azimuth;  Up / Down  sun elevation (time of day)\n"
    "  Esc                       quit\n";

#define NEAR_PLANE 1.0f
#define FAR_PLANE 400000.0f
#define FOV_Y 1.1f
#define OCCLUDED_METERS 1000.0f
#define MAX_SWAP_IMAGES 8

/* The (entry, final) layouts of the images handed to Nimbus. The entry layouts are the final
 * layouts of the host's render pass; after Nimbus, the host's next use of each image starts
 * from the promised final layout (so the validation layer checks that Nimbus kept its word). */
typedef struct {
    const char *name;
    VkImageLayout color_in, color_out, depth_in, depth_out; /* out UNDEFINED: the same as in */
} LayoutPair;

static const LayoutPair LAYOUTS[4] = {
    {"color COLOR_ATTACHMENT -> TRANSFER_SRC, depth DEPTH_STENCIL_ATTACHMENT -> (the same)",
     VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
     VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_UNDEFINED},
    {"color TRANSFER_DST -> TRANSFER_SRC, depth DEPTH_STENCIL_READ_ONLY -> DEPTH_STENCIL_ATTACHMENT",
     VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
     VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
    {"color SHADER_READ_ONLY -> COLOR_ATTACHMENT (then the host -> TRANSFER_SRC), depth TRANSFER_DST -> DEPTH_STENCIL_READ_ONLY",
     VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
     VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL},
    {"color TRANSFER_SRC -> SHADER_READ_ONLY (then the host -> TRANSFER_SRC), depth TRANSFER_SRC -> TRANSFER_DST",
     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL},
};

static VkImageLayout out_layout(VkImageLayout in, VkImageLayout out) {
    return out == VK_IMAGE_LAYOUT_UNDEFINED ? in : out;
}

/* The usage a layout needs (Nimbus checks it; so does the validation layer). */
static VkImageUsageFlags usage_for(VkImageLayout layout) {
    switch (layout) {
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: return VK_IMAGE_USAGE_SAMPLED_BIT;
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: return VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: return VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL: return VK_IMAGE_USAGE_SAMPLED_BIT;
    default: return 0;
    }
}

typedef struct {
    /* options */
    int width, height, frames, layouts, validation, semaphores, recreate, owned, lock, time_handoff, check_occluded;
    const char *shot;
    VkFormat color_format;
    /* camera and sky */
    vec3 eye;
    float yaw, pitch, sun_elevation, sun_azimuth;
    uint32_t preset, options;
    double mouse_x, mouse_y, start;
    int looking;
    /* window */
    GLFWwindow *window;
    int resized;
    VkSurfaceKHR surface;
    VkSwapchainKHR swapchain;
    VkFormat swap_format;
    VkExtent2D swap_extent;
    uint32_t swap_count;
    VkImage swap_images[MAX_SWAP_IMAGES];
    VkSemaphore acquired, presented[MAX_SWAP_IMAGES];
    /* the host's Vulkan objects */
    VkSetup vk;
    VksImage color, depth;
    VkImageView color_view, depth_view;
    VkRenderPass pass;
    VkFramebuffer framebuffer;
    VksBuffer upload, readback;
    VkCommandPool pool;
    VkCommandBuffer cmd_scene, cmd_after;
    VkFence fence;
    int fence_pending;
    VkSemaphore timeline;
    uint64_t timeline_value;
    /* Nimbus */
    NimbusContext *ctx;
    NimbusContextDesc desc;
    NimbusSettingsExt settings;
    NimbusVulkanDeviceExt device_ext;
    float *color_buf, *depth_buf;
    float projection[16];
    /* counters */
    pthread_mutex_t queue_mutex;
    long lock_calls;
    double handoff_seconds, handoff_first;
    long handoff_calls, occluded_checked, occluded_failures;
} App;

static double now_seconds(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static int fail(App *a, const char *what, int32_t rc) {
    fprintf(stderr, "%s failed (%s, %d): %s\n", what, nimbus_result_name(rc), rc,
            nimbus_context_last_error(a ? a->ctx : NULL));
    return 1;
}

static int vk_fail(const char *what, VkResult r) {
    fprintf(stderr, "%s failed (VkResult %d)\n", what, (int)r);
    return 1;
}

/* ---- the queue lock: Nimbus's calls are counted, the host's own are not ------------------- */
static void nimbus_lock_queue(void *user) {
    App *a = (App *)user;
    pthread_mutex_lock(&a->queue_mutex);
    a->lock_calls++;
}
static void nimbus_unlock_queue(void *user) { pthread_mutex_unlock(&((App *)user)->queue_mutex); }
static void host_lock_queue(void *user) { pthread_mutex_lock(&((App *)user)->queue_mutex); }
static void host_unlock_queue(void *user) { pthread_mutex_unlock(&((App *)user)->queue_mutex); }

/* ---- camera and frame (the same for the Vulkan and the owned path) -------------------------- */
static vec3 forward(const App *a) {
    return v3(cosf(a->pitch) * sinf(a->yaw), sinf(a->pitch), -cosf(a->pitch) * cosf(a->yaw));
}

static void update_camera(App *a, float dt) {
    GLFWwindow *w = a->window;
    vec3 fwd = forward(a);
    vec3 flat = v3_norm(v3(fwd.x, 0.0f, fwd.z)), right = v3_norm(v3_cross(flat, v3(0.0f, 1.0f, 0.0f)));
    float speed = 150.0f + 0.5f * a->eye.y;
    if (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS) speed *= 5.0f;
    if (a->looking) {
        double x, y;
        glfwGetCursorPos(w, &x, &y);
        a->yaw += (float)(x - a->mouse_x) * 0.004f;
        a->pitch -= (float)(y - a->mouse_y) * 0.004f;
        a->pitch = a->pitch > 1.5f ? 1.5f : a->pitch < -1.5f ? -1.5f : a->pitch;
        a->mouse_x = x; a->mouse_y = y;
    }
    if (glfwGetKey(w, GLFW_KEY_W) == GLFW_PRESS) a->eye = v3_add(a->eye, v3_scale(flat, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_S) == GLFW_PRESS) a->eye = v3_sub(a->eye, v3_scale(flat, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_D) == GLFW_PRESS) a->eye = v3_add(a->eye, v3_scale(right, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_A) == GLFW_PRESS) a->eye = v3_sub(a->eye, v3_scale(right, speed * dt));
    if (glfwGetKey(w, GLFW_KEY_R) == GLFW_PRESS) a->eye.y += speed * dt;
    if (glfwGetKey(w, GLFW_KEY_F) == GLFW_PRESS) a->eye.y -= speed * dt;
    if (a->eye.y < 2.0f) a->eye.y = 2.0f;
    if (glfwGetKey(w, GLFW_KEY_LEFT) == GLFW_PRESS) a->sun_azimuth -= 30.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_RIGHT) == GLFW_PRESS) a->sun_azimuth += 30.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_UP) == GLFW_PRESS) a->sun_elevation += 10.0f * dt;
    if (glfwGetKey(w, GLFW_KEY_DOWN) == GLFW_PRESS) a->sun_elevation -= 10.0f * dt;
    a->sun_elevation = a->sun_elevation > 89.0f ? 89.0f : a->sun_elevation < -10.0f ? -10.0f : a->sun_elevation;
}

/* Headless runs: a slow yaw and a forward drift, the same every run. */
static void auto_camera(App *a, float dt) {
    vec3 fwd = forward(a), flat = v3_norm(v3(fwd.x, 0.0f, fwd.z));
    a->yaw += 0.06f * dt;
    a->eye = v3_add(a->eye, v3_scale(flat, 40.0f * dt));
}

/* The CPU scene into color_buf/depth_buf and the NimbusFrame of this camera. */
static void build_frame(App *a, double time, uint32_t w, uint32_t h, NimbusFrame *frame) {
    vec3 fwd = forward(a), sun = sun_from_angles(a->sun_elevation, a->sun_azimuth);
    float low = a->sun_elevation < 20.0f ? (20.0f - a->sun_elevation) / 20.0f : 0.0f;
    vec3 sun_color = v3(1.0f, 1.0f - 0.4f * low, 1.0f - 0.65f * low);
    float illuminance = a->sun_elevation > 0.0f ? 10.0f * (1.0f - 0.5f * low) : 0.0f;
    float view_proj[16];
    memset(frame, 0, sizeof *frame);
    mat_look_at(frame->view, a->eye, v3_add(a->eye, fwd), v3(0.0f, 1.0f, 0.0f));
    mat_perspective(frame->projection, FOV_Y, (float)w / (float)h, NEAR_PLANE, FAR_PLANE);
    memcpy(a->projection, frame->projection, sizeof a->projection);
    mat_mul(view_proj, frame->projection, frame->view);
    scene_render(a->color_buf, a->depth_buf, (int)w, (int)h, a->eye, fwd, FOV_Y, view_proj, sun, sun_color,
                 illuminance, NULL);
    frame->depth_flags = 0;
    frame->sun_direction[0] = sun.x; frame->sun_direction[1] = sun.y; frame->sun_direction[2] = sun.z;
    frame->sun_color[0] = sun_color.x; frame->sun_color[1] = sun_color.y; frame->sun_color[2] = sun_color.z;
    frame->sun_illuminance = illuminance;
    frame->time = time;
}

static int alloc_cpu_buffers(App *a, uint32_t w, uint32_t h) {
    free(a->color_buf);
    free(a->depth_buf);
    a->color_buf = (float *)malloc((size_t)w * h * 4 * sizeof(float));
    a->depth_buf = (float *)malloc((size_t)w * h * sizeof(float));
    return a->color_buf && a->depth_buf ? 0 : 1;
}

/* ---- images, render pass, swapchain ------------------------------------------------------ */
static int create_render_pass(App *a) {
    const LayoutPair *lp = &LAYOUTS[a->layouts];
    VkAttachmentDescription att[2];
    VkAttachmentReference color_ref = {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth_ref = {1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub;
    VkSubpassDependency dep[2];
    VkRenderPassCreateInfo ci;
    VkResult r;
    memset(att, 0, sizeof att);
    att[0].format = a->color_format;
    att[0].samples = VK_SAMPLE_COUNT_1_BIT;
    att[0].loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
    att[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    att[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    att[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    att[0].initialLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL; /* after the upload */
    att[0].finalLayout = lp->color_in;                            /* what Nimbus is told */
    att[1] = att[0];
    att[1].format = VK_FORMAT_D32_SFLOAT;
    att[1].finalLayout = lp->depth_in;
    memset(&sub, 0, sizeof sub);
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &color_ref;
    sub.pDepthStencilAttachment = &depth_ref;
    memset(dep, 0, sizeof dep);
    /* The upload's copies before the attachments' loads. */
    dep[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    dep[0].dstSubpass = 0;
    dep[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
    dep[0].srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    dep[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                          VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    dep[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                           VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    /* The stores (and the final layout transitions) before whatever comes next. */
    dep[1].srcSubpass = 0;
    dep[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    dep[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                          VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    dep[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    dep[1].dstStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
    dep[1].dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO;
    ci.attachmentCount = 2;
    ci.pAttachments = att;
    ci.subpassCount = 1;
    ci.pSubpasses = &sub;
    ci.dependencyCount = 2;
    ci.pDependencies = dep;
    r = vkCreateRenderPass(a->vk.device, &ci, NULL, &a->pass);
    return r == VK_SUCCESS ? 0 : vk_fail("vkCreateRenderPass", r);
}

static void destroy_size_objects(App *a) {
    VkDevice d = a->vk.device;
    if (a->framebuffer) vkDestroyFramebuffer(d, a->framebuffer, NULL);
    if (a->color_view) vkDestroyImageView(d, a->color_view, NULL);
    if (a->depth_view) vkDestroyImageView(d, a->depth_view, NULL);
    a->framebuffer = VK_NULL_HANDLE;
    a->color_view = a->depth_view = VK_NULL_HANDLE;
    vks_image_destroy(&a->vk, &a->color);
    vks_image_destroy(&a->vk, &a->depth);
    vks_buffer_destroy(&a->vk, &a->upload);
    vks_buffer_destroy(&a->vk, &a->readback);
}

/* The color and depth images (with the usage each layout of the chosen pair needs), their
 * framebuffer and the staging buffers, at w x h. */
static int create_size_objects(App *a, uint32_t w, uint32_t h) {
    const LayoutPair *lp = &LAYOUTS[a->layouts];
    VkImageUsageFlags color_usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                    VK_IMAGE_USAGE_TRANSFER_SRC_BIT | usage_for(lp->color_in) | usage_for(lp->color_out);
    VkImageUsageFlags depth_usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                    VK_IMAGE_USAGE_TRANSFER_DST_BIT | usage_for(lp->depth_in) | usage_for(lp->depth_out);
    VkImageView views[2];
    VkFramebufferCreateInfo fi;
    if (vks_image_create(&a->vk, &a->color, a->color_format, color_usage, w, h) ||
        vks_image_create(&a->vk, &a->depth, VK_FORMAT_D32_SFLOAT, depth_usage, w, h) ||
        vks_buffer_create(&a->vk, &a->upload, vks_staging_size(a->color_format, VK_FORMAT_D32_SFLOAT, w, h),
                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT) ||
        vks_buffer_create(&a->vk, &a->readback, (VkDeviceSize)w * h * vks_color_bytes(a->color_format),
                          VK_BUFFER_USAGE_TRANSFER_DST_BIT)) {
        fprintf(stderr, "%s\n", a->vk.error);
        return 1;
    }
    a->color_view = vks_image_view(&a->vk, &a->color);
    a->depth_view = vks_image_view(&a->vk, &a->depth);
    if (!a->color_view || !a->depth_view) return vk_fail("vkCreateImageView", VK_ERROR_UNKNOWN);
    views[0] = a->color_view;
    views[1] = a->depth_view;
    memset(&fi, 0, sizeof fi);
    fi.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
    fi.renderPass = a->pass;
    fi.attachmentCount = 2;
    fi.pAttachments = views;
    fi.width = w;
    fi.height = h;
    fi.layers = 1;
    if (vkCreateFramebuffer(a->vk.device, &fi, NULL, &a->framebuffer) != VK_SUCCESS)
        return vk_fail("vkCreateFramebuffer", VK_ERROR_UNKNOWN);
    a->width = (int)w;
    a->height = (int)h;
    return alloc_cpu_buffers(a, w, h);
}

static void destroy_swapchain_semaphores(App *a) {
    uint32_t i;
    for (i = 0; i < MAX_SWAP_IMAGES; i++) {
        if (a->presented[i]) vkDestroySemaphore(a->vk.device, a->presented[i], NULL);
        a->presented[i] = VK_NULL_HANDLE;
    }
}

static int create_swapchain(App *a) {
    VkSurfaceCapabilitiesKHR caps;
    VkSurfaceFormatKHR formats[64];
    uint32_t n = 64, i, count;
    VkSwapchainCreateInfoKHR ci;
    VkSwapchainKHR old = a->swapchain;
    VkFormatProperties fp;
    VkSurfaceFormatKHR chosen;
    int fw, fh;
    VkResult r;

    vkGetPhysicalDeviceSurfaceCapabilitiesKHR(a->vk.physical_device, a->surface, &caps);
    vkGetPhysicalDeviceSurfaceFormatsKHR(a->vk.physical_device, a->surface, &n, formats);
    if (n == 0) return vk_fail("vkGetPhysicalDeviceSurfaceFormatsKHR", VK_ERROR_FORMAT_NOT_SUPPORTED);
    chosen = formats[0];
    for (i = 0; i < n; i++)
        if ((formats[i].format == VK_FORMAT_B8G8R8A8_SRGB || formats[i].format == VK_FORMAT_R8G8B8A8_SRGB) &&
            formats[i].colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) {
            chosen = formats[i];
            break;
        }
    vkGetPhysicalDeviceFormatProperties(a->vk.physical_device, chosen.format, &fp);
    if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT) ||
        !(fp.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT)) {
        fprintf(stderr, "the swapchain cannot be blitted to (format %d)\n", (int)chosen.format);
        return 1;
    }
    glfwGetFramebufferSize(a->window, &fw, &fh);
    if (caps.currentExtent.width != UINT32_MAX) {
        a->swap_extent = caps.currentExtent;
    } else {
        a->swap_extent.width = (uint32_t)fw;
        a->swap_extent.height = (uint32_t)fh;
    }
    if (a->swap_extent.width < caps.minImageExtent.width) a->swap_extent.width = caps.minImageExtent.width;
    if (a->swap_extent.height < caps.minImageExtent.height) a->swap_extent.height = caps.minImageExtent.height;
    if (a->swap_extent.width > caps.maxImageExtent.width) a->swap_extent.width = caps.maxImageExtent.width;
    if (a->swap_extent.height > caps.maxImageExtent.height) a->swap_extent.height = caps.maxImageExtent.height;
    count = caps.minImageCount + 1;
    if (caps.maxImageCount && count > caps.maxImageCount) count = caps.maxImageCount;
    if (count > MAX_SWAP_IMAGES) count = MAX_SWAP_IMAGES;
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR;
    ci.surface = a->surface;
    ci.minImageCount = count;
    ci.imageFormat = chosen.format;
    ci.imageColorSpace = chosen.colorSpace;
    ci.imageExtent = a->swap_extent;
    ci.imageArrayLayers = 1;
    ci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ci.preTransform = caps.currentTransform;
    ci.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                            ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                            : (VkCompositeAlphaFlagBitsKHR)(caps.supportedCompositeAlpha & (0u - caps.supportedCompositeAlpha));
    ci.presentMode = VK_PRESENT_MODE_FIFO_KHR;
    ci.clipped = VK_TRUE;
    ci.oldSwapchain = old;
    r = vkCreateSwapchainKHR(a->vk.device, &ci, NULL, &a->swapchain);
    if (old) vkDestroySwapchainKHR(a->vk.device, old, NULL);
    if (r != VK_SUCCESS) {
        a->swapchain = VK_NULL_HANDLE;
        return vk_fail("vkCreateSwapchainKHR", r);
    }
    a->swap_format = chosen.format;
    a->swap_count = MAX_SWAP_IMAGES;
    vkGetSwapchainImagesKHR(a->vk.device, a->swapchain, &a->swap_count, a->swap_images);
    destroy_swapchain_semaphores(a);
    for (i = 0; i < a->swap_count; i++) {
        a->presented[i] = vks_semaphore(&a->vk, 0, 0);
        if (!a->presented[i]) return vk_fail("vkCreateSemaphore", VK_ERROR_UNKNOWN);
    }
    return 0;
}

static void wait_frame(App *a) {
    if (!a->fence_pending) return;
    vkWaitForFences(a->vk.device, 1, &a->fence, VK_TRUE, UINT64_MAX);
    vkResetFences(a->vk.device, 1, &a->fence);
    a->fence_pending = 0;
}

/* The window changed size: Nimbus lets go of the images before they are destroyed. */
static int recreate_for_window(App *a) {
    int fw = 0, fh = 0;
    int32_t rc;
    glfwGetFramebufferSize(a->window, &fw, &fh);
    while ((fw == 0 || fh == 0) && !glfwWindowShouldClose(a->window)) { /* minimised */
        glfwWaitEvents();
        glfwGetFramebufferSize(a->window, &fw, &fh);
    }
    wait_frame(a);
    vks_wait_idle(&a->vk);
    if (a->ctx && (rc = nimbus_context_release_vulkan_images(a->ctx)) != NIMBUS_OK)
        return fail(a, "nimbus_context_release_vulkan_images", rc);
    destroy_size_objects(a);
    if (create_swapchain(a)) return 1;
    a->resized = 0;
    printf("resized to %ux%u\n", a->swap_extent.width, a->swap_extent.height);
    return create_size_objects(a, a->swap_extent.width, a->swap_extent.height);
}

/* ---- one frame on the host's device ----------------------------------------------------- */

/* Every pixel nearer than OCCLUDED_METERS must come back exactly as uploaded. */
static void check_occluded(App *a) {
    const uint8_t *up = (const uint8_t *)a->upload.mapped, *back = (const uint8_t *)a->readback.mapped;
    uint32_t w = (uint32_t)a->width, h = (uint32_t)a->height, x, y;
    const float *p = a->projection;
    long checked = 0, bad = 0;
    int c;
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            float d = a->depth_buf[i], z, vx, vy, dist;
            float nx = ((float)x + 0.5f) / (float)w * 2.0f - 1.0f, ny = 1.0f - ((float)y + 0.5f) / (float)h * 2.0f;
            if (d >= 1.0f) continue;
            z = p[14] / (d + p[10]); /* view-space distance along the view axis */
            vx = nx * z / p[0];
            vy = ny * z / p[5];
            dist = sqrtf(vx * vx + vy * vy + z * z);
            if (dist >= OCCLUDED_METERS) continue;
            checked++;
            for (c = 0; c < 3; c++) {
                float u = vks_load_channel(a->color_format, up, i, c), b = vks_load_channel(a->color_format, back, i, c);
                float tol = a->color_format == VK_FORMAT_R16G16B16A16_SFLOAT
                                ? fabsf(u) * (1.0f / 1024.0f) + 1.0f / 16384.0f /* a half-float epsilon */
                                : 0.0f;
                int differs = a->color_format == VK_FORMAT_R16G16B16A16_SFLOAT
                                  ? fabsf(u - b) > tol
                                  : abs((int)up[i * 4 + (size_t)c] - (int)back[i * 4 + (size_t)c]) > 1; /* 1/255 */
                if (differs) {
                    if (bad < 5)
                        fprintf(stderr, "occluded pixel (%u, %u) at %.0f m changed: channel %d %.6f -> %.6f\n", x, y,
                                (double)dist, c, (double)u, (double)b);
                    bad++;
                    break;
                }
            }
        }
    a->occluded_checked += checked;
    a->occluded_failures += bad;
}

/* Draws the scene, hands it to Nimbus, and reads it back (readback) and/or presents it. */
static int vk_frame(App *a, double time, int readback, int present) {
    const LayoutPair *lp = &LAYOUTS[a->layouts];
    NimbusFrame frame;
    NimbusVulkanTargets targets;
    NimbusVulkanSemaphore wait, signal;
    VkCommandBufferBeginInfo bi;
    VkRenderPassBeginInfo rp;
    VkSemaphore waits[2], signals[1];
    uint64_t wait_values[2], signal_values[1];
    VkPipelineStageFlags wait_stages[2];
    uint32_t wait_count = 0, signal_count = 0, image_index = 0;
    double t0;
    int32_t rc;
    VkResult r;

    wait_frame(a);
    if (present) {
        if (a->resized && recreate_for_window(a)) return 1;
        r = vkAcquireNextImageKHR(a->vk.device, a->swapchain, UINT64_MAX, a->acquired, VK_NULL_HANDLE, &image_index);
        if (r == VK_ERROR_OUT_OF_DATE_KHR) {
            a->resized = 1;
            return 0; /* skipped; next frame recreates */
        }
        if (r == VK_SUBOPTIMAL_KHR) a->resized = 1;
        else if (r != VK_SUCCESS) return vk_fail("vkAcquireNextImageKHR", r);
    }

    /* The host's scene: CPU-rendered, uploaded, then its render pass (loads, draws nothing,
     * leaves both attachments in the layouts Nimbus is told). */
    build_frame(a, time, (uint32_t)a->width, (uint32_t)a->height, &frame);
    vks_write_scene(&a->upload, a->color_format, VK_FORMAT_D32_SFLOAT, (uint32_t)a->width, (uint32_t)a->height,
                    a->color_buf, a->depth_buf);
    vkResetCommandPool(a->vk.device, a->pool, 0);
    memset(&bi, 0, sizeof bi);
    bi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkBeginCommandBuffer(a->cmd_scene, &bi);
    vks_record_upload(a->cmd_scene, &a->upload, &a->color, &a->depth, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    memset(&rp, 0, sizeof rp);
    rp.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
    rp.renderPass = a->pass;
    rp.framebuffer = a->framebuffer;
    rp.renderArea.extent.width = (uint32_t)a->width;
    rp.renderArea.extent.height = (uint32_t)a->height;
    vkCmdBeginRenderPass(a->cmd_scene, &rp, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdEndRenderPass(a->cmd_scene);
    a->color.layout = lp->color_in;
    a->depth.layout = lp->depth_in;
    vkEndCommandBuffer(a->cmd_scene);
    if (a->semaphores) {
        signals[0] = a->timeline;
        signal_values[0] = a->timeline_value + 1;
        r = vks_submit(&a->vk, a->cmd_scene, 0, NULL, NULL, NULL, 1, signals, signal_values, VK_NULL_HANDLE);
    } else {
        r = vks_submit(&a->vk, a->cmd_scene, 0, NULL, NULL, NULL, 0, NULL, NULL, VK_NULL_HANDLE);
    }
    if (r != VK_SUCCESS) return vk_fail("vkQueueSubmit (scene)", r);

    /* Nimbus: clouds into the color image in place, on the host's queue. */
    memset(&targets, 0, sizeof targets);
    targets.color = vks_nimbus_image(&a->color, lp->color_out);
    targets.depth = vks_nimbus_image(&a->depth, lp->depth_out);
    if (a->semaphores) {
        memset(&wait, 0, sizeof wait);
        memset(&signal, 0, sizeof signal);
        wait.semaphore = VKS_HANDLE(a->timeline);
        wait.value = a->timeline_value + 1;
        wait.stage = 0; /* ALL_COMMANDS */
        signal.semaphore = VKS_HANDLE(a->timeline);
        signal.value = a->timeline_value + 2;
        targets.wait_count = 1;
        targets.waits = &wait;
        targets.signal_count = 1;
        targets.signals = &signal;
    }
    t0 = now_seconds();
    rc = nimbus_context_render_vulkan(a->ctx, &frame, &targets);
    t0 = now_seconds() - t0;
    if (a->handoff_calls++ == 0) a->handoff_first = t0; /* wraps the images, compiles pipelines */
    else a->handoff_seconds += t0;
    if (rc != NIMBUS_OK) return fail(a, "nimbus_context_render_vulkan", rc);
    a->color.layout = out_layout(lp->color_in, lp->color_out); /* as promised: the next barrier starts there */
    a->depth.layout = out_layout(lp->depth_in, lp->depth_out);

    /* Afterwards: the color from its final layout to TRANSFER_SRC, then read back and/or
     * blitted to the swapchain. */
    vkBeginCommandBuffer(a->cmd_after, &bi);
    if (a->color.layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)
        vks_transition(a->cmd_after, &a->color, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    if (readback) vks_record_readback(a->cmd_after, &a->color, &a->readback);
    if (present) {
        VkImageBlit blit;
        VkImage target = a->swap_images[image_index];
        vks_image_barrier(a->cmd_after, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                          VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
        memset(&blit, 0, sizeof blit);
        blit.srcSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
        blit.srcSubresource.layerCount = 1;
        blit.srcOffsets[1].x = a->width;
        blit.srcOffsets[1].y = a->height;
        blit.srcOffsets[1].z = 1;
        blit.dstSubresource = blit.srcSubresource;
        blit.dstOffsets[1].x = (int32_t)a->swap_extent.width;
        blit.dstOffsets[1].y = (int32_t)a->swap_extent.height;
        blit.dstOffsets[1].z = 1;
        vkCmdBlitImage(a->cmd_after, a->color.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
        vks_image_barrier(a->cmd_after, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                          VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
    }
    vkEndCommandBuffer(a->cmd_after);
    if (a->semaphores) {
        waits[wait_count] = a->timeline;
        wait_values[wait_count] = a->timeline_value + 2; /* Nimbus's signal */
        wait_stages[wait_count++] = VK_PIPELINE_STAGE_TRANSFER_BIT;
    }
    if (present) {
        waits[wait_count] = a->acquired;
        wait_values[wait_count] = 0; /* binary: ignored */
        wait_stages[wait_count++] = VK_PIPELINE_STAGE_TRANSFER_BIT;
        signals[signal_count] = a->presented[image_index];
        signal_values[signal_count++] = 0;
    }
    r = vks_submit(&a->vk, a->cmd_after, wait_count, waits, a->semaphores ? wait_values : NULL, wait_stages,
                   signal_count, signals, a->semaphores ? signal_values : NULL, a->fence);
    if (r != VK_SUCCESS) return vk_fail("vkQueueSubmit (after Nimbus)", r);
    a->fence_pending = 1;
    a->timeline_value += 2;

    if (present) {
        VkPresentInfoKHR pi;
        memset(&pi, 0, sizeof pi);
        pi.sType = VK_STRUCTURE_TYPE_PRESENT_INFO_KHR;
        pi.waitSemaphoreCount = 1;
        pi.pWaitSemaphores = &a->presented[image_index];
        pi.swapchainCount = 1;
        pi.pSwapchains = &a->swapchain;
        pi.pImageIndices = &image_index;
        vks_lock(&a->vk);
        r = vkQueuePresentKHR(a->vk.queue, &pi);
        vks_unlock(&a->vk);
        if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) a->resized = 1;
        else if (r != VK_SUCCESS) return vk_fail("vkQueuePresentKHR", r);
    }
    if (readback) {
        wait_frame(a);
        if (a->check_occluded) check_occluded(a);
    }
    return 0;
}

static int write_png(App *a, const char *path) {
    uint8_t *rgba = (uint8_t *)malloc((size_t)a->width * a->height * 4);
    if (!rgba) return 1;
    vks_to_srgb8(a->color_format, a->readback.mapped, (uint32_t)a->width, (uint32_t)a->height, rgba);
    if (png_write_rgba8(path, rgba, (uint32_t)a->width, (uint32_t)a->height) != 0) {
        fprintf(stderr, "cannot write %s\n", path);
        free(rgba);
        return 1;
    }
    printf("wrote %s (%dx%d)\n", path, a->width, a->height);
    free(rgba);
    return 0;
}

/* ---- window input ------------------------------------------------------------------------ */
static void set_weather(App *a, double now) {
    static const char *names[] = {"", "clear", "sparse", "cloudy", "overcast", "stormy"};
    int32_t rc = nimbus_context_set_weather(a->ctx, a->preset, a->options, now, 8.0);
    if (rc != NIMBUS_OK) fail(a, "nimbus_context_set_weather", rc);
    else printf("weather -> %s%s%s\n", names[a->preset], a->options & NIMBUS_WEATHER_CIRRUS ? " + cirrus" : "",
                a->options & NIMBUS_WEATHER_HORIZON_GRADIENT ? " + horizon gradient" : "");
}

static double app_time(const App *a) { return now_seconds() - a->start; }

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods) {
    App *a = (App *)glfwGetWindowUserPointer(w);
    (void)scancode; (void)mods;
    if (action != GLFW_PRESS) return;
    if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(w, 1);
    if (key >= GLFW_KEY_1 && key <= GLFW_KEY_5) {
        a->preset = (uint32_t)(key - GLFW_KEY_1) + NIMBUS_PRESET_CLEAR;
        set_weather(a, app_time(a));
    }
    if (key == GLFW_KEY_6) { a->options ^= NIMBUS_WEATHER_CIRRUS; set_weather(a, app_time(a)); }
    if (key == GLFW_KEY_7) { a->options ^= NIMBUS_WEATHER_HORIZON_GRADIENT; set_weather(a, app_time(a)); }
}

static void on_mouse_button(GLFWwindow *w, int button, int action, int mods) {
    App *a = (App *)glfwGetWindowUserPointer(w);
    (void)mods;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        a->looking = action == GLFW_PRESS;
        glfwGetCursorPos(w, &a->mouse_x, &a->mouse_y);
    }
}

static void on_resize(GLFWwindow *w, int width, int height) {
    App *a = (App *)glfwGetWindowUserPointer(w);
    (void)width; (void)height;
    a->resized = 1;
}

static void log_to_stderr(int32_t level, const char *message, void *user) {
    (void)user;
    fprintf(stderr, "[nimbus %s] %s\n", level <= 1 ? "error" : "warning", message);
}

/* ---- the owned path: the same frames on Nimbus's own device and NimbusTextures -------------- */
static int run_owned(App *a) {
    NimbusTextureDesc d = {0};
    NimbusTexture *scene = NULL, *depth = NULL, *out = NULL;
    NimbusTargets targets = {0};
    NimbusFrame frame;
    uint32_t w = (uint32_t)a->width, h = (uint32_t)a->height;
    size_t pixels = (size_t)w * h, bytes = 0;
    int frame_i;
    int32_t rc;
    uint8_t *rgba;

    a->desc.next = &a->settings.chain;
    if ((rc = nimbus_context_create(&a->desc, &a->ctx)) != NIMBUS_OK) return fail(NULL, "nimbus_context_create", rc);
    printf("nimbus %s on %s (owned device)\n", nimbus_version_string(), nimbus_context_adapter_name(a->ctx));
    if (alloc_cpu_buffers(a, w, h)) return 1;
    d.width = w;
    d.height = h;
    d.format = NIMBUS_FORMAT_RGBA32_FLOAT;
    if ((rc = nimbus_texture_create(a->ctx, &d, &scene)) != NIMBUS_OK) return fail(a, "nimbus_texture_create", rc);
    d.format = NIMBUS_FORMAT_R32_FLOAT;
    if ((rc = nimbus_texture_create(a->ctx, &d, &depth)) != NIMBUS_OK) return fail(a, "nimbus_texture_create", rc);
    d.format = NIMBUS_FORMAT_RGBA8_UNORM_SRGB;
    if ((rc = nimbus_texture_create(a->ctx, &d, &out)) != NIMBUS_OK) return fail(a, "nimbus_texture_create", rc);
    targets.scene_color = scene;
    targets.scene_depth = depth;
    targets.output = out;
    for (frame_i = 0; frame_i < a->frames; frame_i++) {
        auto_camera(a, 1.0f / 30.0f);
        build_frame(a, frame_i / 30.0, w, h, &frame);
        if ((rc = nimbus_texture_write(scene, a->color_buf, pixels * 4 * sizeof(float))) != NIMBUS_OK ||
            (rc = nimbus_texture_write(depth, a->depth_buf, pixels * sizeof(float))) != NIMBUS_OK)
            return fail(a, "nimbus_texture_write", rc);
        if ((rc = nimbus_context_render(a->ctx, &frame, &targets)) != NIMBUS_OK) return fail(a, "nimbus_context_render", rc);
    }
    printf("%d frames (owned)\n", a->frames);
    if (a->shot) {
        nimbus_texture_byte_size(out, &bytes);
        rgba = (uint8_t *)malloc(bytes);
        if (!rgba) return 1;
        if ((rc = nimbus_texture_read(out, rgba, bytes)) != NIMBUS_OK) return fail(a, "nimbus_texture_read", rc);
        if (png_write_rgba8(a->shot, rgba, w, h) != 0) { fprintf(stderr, "cannot write %s\n", a->shot); return 1; }
        printf("wrote %s (%ux%u)\n", a->shot, w, h);
        free(rgba);
    }
    nimbus_texture_destroy(scene);
    nimbus_texture_destroy(depth);
    nimbus_texture_destroy(out);
    nimbus_context_destroy(a->ctx);
    a->ctx = NULL;
    free(a->color_buf);
    free(a->depth_buf);
    return 0;
}

/* ---- main --------------------------------------------------------------------------------- */
static int usage(const char *argv0) {
    fprintf(stderr,
            "usage: %s [--size WxH] [--frames N] [--screenshot FILE.png] [--validation] [--layouts 0..3]\n"
            "          [--semaphores] [--recreate N] [--owned] [--lock] [--time-handoff] [--check-occluded]\n"
            "          [--format rgba16f|srgb8]\n",
            argv0);
    return 2;
}

int main(int argc, char **argv) {
    App app, *a = &app;
    VksOptions opt;
    const char *host_device_ext[1] = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
    VkCommandPoolCreateInfo pi;
    VkCommandBufferAllocateInfo ai;
    VkCommandBuffer cmds[2];
    VkFenceCreateInfo fi;
    VkBool32 can_present = VK_FALSE;
    double last, title_time, frame_ms = 0.0;
    char title[160];
    int i, frame, headless, status = 0;
    int32_t rc;

    memset(a, 0, sizeof *a);
    a->width = 960;
    a->height = 540;
    a->color_format = VK_FORMAT_R16G16B16A16_SFLOAT;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--frames") && i + 1 < argc) a->frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--screenshot") && i + 1 < argc) a->shot = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 1 < argc && sscanf(argv[i + 1], "%dx%d", &a->width, &a->height) == 2) i++;
        else if (!strcmp(argv[i], "--validation")) a->validation = 1;
        else if (!strcmp(argv[i], "--layouts") && i + 1 < argc) a->layouts = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--semaphores")) a->semaphores = 1;
        else if (!strcmp(argv[i], "--recreate") && i + 1 < argc) a->recreate = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--owned")) a->owned = 1;
        else if (!strcmp(argv[i], "--lock")) a->lock = 1;
        else if (!strcmp(argv[i], "--time-handoff")) a->time_handoff = 1;
        else if (!strcmp(argv[i], "--check-occluded")) a->check_occluded = 1;
        else if (!strcmp(argv[i], "--format") && i + 1 < argc) {
            i++;
            if (!strcmp(argv[i], "rgba16f")) a->color_format = VK_FORMAT_R16G16B16A16_SFLOAT;
            else if (!strcmp(argv[i], "srgb8")) a->color_format = VK_FORMAT_R8G8B8A8_SRGB;
            else return usage(argv[0]);
        } else return usage(argv[0]);
    }
    if (a->width <= 0 || a->height <= 0 || a->layouts < 0 || a->layouts > 3 || a->frames < 0 || a->recreate < 0)
        return usage(argv[0]);
    headless = a->shot != NULL || a->owned;
    if (headless && a->frames <= 0) a->frames = 1;

    a->eye = v3(0.0f, 60.0f, 0.0f);
    a->pitch = 0.25f;
    a->sun_elevation = 35.0f;
    a->sun_azimuth = 150.0f;
    a->preset = NIMBUS_PRESET_SPARSE;
    pthread_mutex_init(&a->queue_mutex, NULL);
    nimbus_set_log_callback(log_to_stderr, NULL, 2);

    /* Deterministic clouds (no jitter), for comparing runs and paths. */
    a->settings.chain.s_type = NIMBUS_STYPE_SETTINGS;
    a->settings.jitter = NIMBUS_JITTER_OFF;
    a->desc.abi_version = NIMBUS_ABI_VERSION;
    if (a->owned) return run_owned(a);

    /* The instance and device: the host's own needs (GLFW's surface extensions, the
     * swapchain, timeline semaphores) with Nimbus's merged in. */
    memset(&opt, 0, sizeof opt);
    opt.validation = a->validation;
    if (!headless) {
        if (!glfwInit()) { fprintf(stderr, "glfwInit failed\n"); return 1; }
        if (!glfwVulkanSupported()) { fprintf(stderr, "GLFW finds no Vulkan loader\n"); return 1; }
        opt.host_instance_extensions = glfwGetRequiredInstanceExtensions(&opt.host_instance_extension_count);
        opt.host_device_extensions = host_device_ext;
        opt.host_device_extension_count = 1;
    }
    if (a->lock) {
        opt.lock = host_lock_queue;
        opt.unlock = host_unlock_queue;
        opt.lock_user = a;
    }
    if (vks_create(&a->vk, &opt)) {
        fprintf(stderr, "Vulkan setup failed: %s\n", a->vk.error);
        return 1;
    }
    printf("Vulkan device: %s; %u instance and %u device extensions; queue family %u\n", a->vk.properties.deviceName,
           a->vk.instance_extension_count, a->vk.device_extension_count, a->vk.queue_family);
    printf("layouts %d: %s\n", a->layouts, LAYOUTS[a->layouts].name);

    memset(&pi, 0, sizeof pi);
    pi.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
    pi.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    pi.queueFamilyIndex = a->vk.queue_family;
    memset(&ai, 0, sizeof ai);
    ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 2;
    memset(&fi, 0, sizeof fi);
    fi.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
    if (vkCreateCommandPool(a->vk.device, &pi, NULL, &a->pool) != VK_SUCCESS) return vk_fail("vkCreateCommandPool", VK_ERROR_UNKNOWN);
    ai.commandPool = a->pool;
    if (vkAllocateCommandBuffers(a->vk.device, &ai, cmds) != VK_SUCCESS) return vk_fail("vkAllocateCommandBuffers", VK_ERROR_UNKNOWN);
    a->cmd_scene = cmds[0];
    a->cmd_after = cmds[1];
    if (vkCreateFence(a->vk.device, &fi, NULL, &a->fence) != VK_SUCCESS) return vk_fail("vkCreateFence", VK_ERROR_UNKNOWN);
    a->timeline = vks_semaphore(&a->vk, 1, 0);
    if (!a->timeline) return vk_fail("vkCreateSemaphore (timeline)", VK_ERROR_UNKNOWN);
    if (create_render_pass(a)) return 1;

    if (!headless) {
        VkResult r;
        printf("%s", HELP);
        glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
        a->window = glfwCreateWindow(a->width, a->height, "Nimbus (Vulkan host)", NULL, NULL);
        if (!a->window) { fprintf(stderr, "cannot open a window\n"); return 1; }
        if ((r = glfwCreateWindowSurface(a->vk.instance, a->window, NULL, &a->surface)) != VK_SUCCESS)
            return vk_fail("glfwCreateWindowSurface", r);
        vkGetPhysicalDeviceSurfaceSupportKHR(a->vk.physical_device, a->vk.queue_family, a->surface, &can_present);
        if (!can_present) { fprintf(stderr, "queue family %u cannot present to the window\n", a->vk.queue_family); return 1; }
        a->acquired = vks_semaphore(&a->vk, 0, 0);
        if (!a->acquired || create_swapchain(a)) return 1;
        a->width = (int)a->swap_extent.width;
        a->height = (int)a->swap_extent.height;
        glfwSetWindowUserPointer(a->window, a);
        glfwSetKeyCallback(a->window, on_key);
        glfwSetMouseButtonCallback(a->window, on_mouse_button);
        glfwSetFramebufferSizeCallback(a->window, on_resize);
    }
    if (create_size_objects(a, (uint32_t)a->width, (uint32_t)a->height)) return 1;

    /* The context on the host's device. */
    vks_device_ext(&a->vk, &a->device_ext);
    if (a->lock) {
        a->device_ext.lock_queue = nimbus_lock_queue;
        a->device_ext.unlock_queue = nimbus_unlock_queue;
        a->device_ext.lock_user_data = a;
    }
    a->device_ext.chain.next = &a->settings.chain;
    a->desc.next = &a->device_ext.chain;
    if ((rc = nimbus_context_create(&a->desc, &a->ctx)) != NIMBUS_OK) return fail(NULL, "nimbus_context_create", rc);
    printf("nimbus %s on %s (the host's device)\n", nimbus_version_string(), nimbus_context_adapter_name(a->ctx));

    a->start = now_seconds();
    last = title_time = a->start;
    for (frame = 0; (a->frames == 0 || frame < a->frames) && !(a->window && glfwWindowShouldClose(a->window)); frame++) {
        double wall = now_seconds(), time = a->frames ? frame / 30.0 : wall - a->start;
        int last_frame = a->frames && frame == a->frames - 1;
        if (a->window) {
            glfwPollEvents();
            update_camera(a, (float)(a->frames ? 1.0 / 30.0 : wall - last));
        } else {
            auto_camera(a, 1.0f / 30.0f);
        }
        if (vk_frame(a, time, a->check_occluded || (a->shot && last_frame), a->window != NULL)) return 1;
        frame_ms = 0.9 * frame_ms + 0.1 * (now_seconds() - wall) * 1000.0;
        last = wall;
        if (a->window && (wall - title_time > 0.5 || a->frames)) {
            snprintf(title, sizeof title, "Nimbus (Vulkan host) | %.1f ms | altitude %.0f m | sun %.0f deg", frame_ms,
                     (double)a->eye.y, (double)a->sun_elevation);
            glfwSetWindowTitle(a->window, title);
            title_time = wall;
        }
    }
    wait_frame(a);
    printf("%d frames, last frame %.1f ms\n", frame, frame_ms);
    if (a->shot && write_png(a, a->shot)) return 1;
    if (a->time_handoff && a->handoff_calls > 1)
        printf("nimbus_context_render_vulkan: %.1f us on average over %ld calls after the first (%.1f us) (CPU time)\n",
               a->handoff_seconds * 1e6 / (double)(a->handoff_calls - 1), a->handoff_calls - 1, a->handoff_first * 1e6);
    else if (a->time_handoff && a->handoff_calls == 1)
        printf("nimbus_context_render_vulkan: %.1f us (one call, CPU time)\n", a->handoff_first * 1e6);
    if (a->check_occluded) {
        printf("occluded check: %ld pixels nearer than %.0f m checked, %ld changed\n", a->occluded_checked,
               (double)OCCLUDED_METERS, a->occluded_failures);
        if (a->occluded_failures > 0 || a->occluded_checked == 0) status = 1;
    }

    /* Contexts come and go on the same device. */
    nimbus_context_destroy(a->ctx);
    a->ctx = NULL;
    for (i = 1; i <= a->recreate; i++) {
        if ((rc = nimbus_context_create(&a->desc, &a->ctx)) != NIMBUS_OK) return fail(NULL, "nimbus_context_create", rc);
        if (vk_frame(a, i / 30.0, 0, 0)) return 1;
        wait_frame(a);
        nimbus_context_destroy(a->ctx);
        a->ctx = NULL;
        printf("recreate %d/%d: RSS %.1f MiB\n", i, a->recreate, vks_rss_mib());
    }
    if (a->lock) {
        printf("queue lock calls: %ld\n", a->lock_calls);
        if (a->lock_calls <= 0 && frame > 0) status = 1;
    }

    /* Teardown: everything of the host's before the device; the validation layer reports
     * any object left on it at vkDestroyDevice. */
    vks_wait_idle(&a->vk);
    destroy_size_objects(a);
    if (a->swapchain) vkDestroySwapchainKHR(a->vk.device, a->swapchain, NULL);
    destroy_swapchain_semaphores(a);
    if (a->acquired) vkDestroySemaphore(a->vk.device, a->acquired, NULL);
    vkDestroySemaphore(a->vk.device, a->timeline, NULL);
    vkDestroyFence(a->vk.device, a->fence, NULL);
    vkDestroyCommandPool(a->vk.device, a->pool, NULL);
    vkDestroyRenderPass(a->vk.device, a->pass, NULL);
    if (a->surface) vkDestroySurfaceKHR(a->vk.instance, a->surface, NULL);
    vks_destroy(&a->vk);
    if (a->window) {
        glfwDestroyWindow(a->window);
        glfwTerminate();
    }
    free(a->color_buf);
    free(a->depth_buf);
    if (a->validation) {
        int n = vks_validation_messages();
        printf("validation messages: %d\n", n);
        if (n > 0) status = 1;
    }
    return status;
}
