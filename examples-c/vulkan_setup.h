/* Vulkan helpers for a host that brings its own device to Nimbus, shared by vulkan_host.c and
 * tests/c/vulkan_test.c: an instance and a device created with Nimbus's requirements merged
 * into the host's own (extensions, features, queue family), optionally under the Khronos
 * validation layer with synchronization validation; images, buffers, barriers, one-shot
 * submissions, the scene upload (linear float color and clip depth from scene.h) and the
 * color readback to sRGB-encoded RGBA8.
 *
 * Header-only (static inline), C99. Uses only vulkan.h and libvulkan (-lvulkan) and pthreads
 * (-pthread: the validation messenger may be called from any thread that uses the device,
 * Nimbus's included). */
#ifndef NIMBUS_VULKAN_SETUP_H
#define NIMBUS_VULKAN_SETUP_H

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <vulkan/vulkan.h>

#include "nimbus.h"

#define VKS_MAX_NAMES 64
#define VKS_VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"

/* Non-dispatchable handles (VkImage, VkSemaphore) as Nimbus's uint64_t. */
#if VK_USE_64_BIT_PTR_DEFINES == 1
#define VKS_HANDLE(h) ((uint64_t)(uintptr_t)(h))
#else
#define VKS_HANDLE(h) ((uint64_t)(h))
#endif

/* ---- validation messages: printed and counted (warnings and errors; info and verbose are
 * not requested) ------------------------------------------------------------------------- */
static pthread_mutex_t vks_message_mutex = PTHREAD_MUTEX_INITIALIZER;
static int vks_message_count = 0;

/* Resident memory of this process in MiB (Linux: /proc/self/statm), -1 when unknown. */
static inline double vks_rss_mib(void) {
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return -1.0;
    if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    fclose(f);
    return (double)resident * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0);
}

static inline int vks_validation_messages(void) {
    int n;
    pthread_mutex_lock(&vks_message_mutex);
    n = vks_message_count;
    pthread_mutex_unlock(&vks_message_mutex);
    return n;
}

static VKAPI_ATTR VkBool32 VKAPI_CALL vks_on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT types,
                                                     const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                     void *user) {
    (void)types;
    (void)user;
    if (!(severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)))
        return VK_FALSE;
    pthread_mutex_lock(&vks_message_mutex);
    vks_message_count++;
    fprintf(stderr, "[vulkan %s] %s\n", severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning",
            data && data->pMessage ? data->pMessage : "(no message)");
    pthread_mutex_unlock(&vks_message_mutex);
    return VK_FALSE;
}

static inline void vks_messenger_info(VkDebugUtilsMessengerCreateInfoEXT *info) {
    memset(info, 0, sizeof *info);
    info->sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
    info->messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    info->messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                        VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    info->pfnUserCallback = vks_on_message;
}

/* ---- instance and device ----------------------------------------------------------------- */

typedef void (*VksLockFn)(void *user);

/* What the host wants besides Nimbus's requirements, and the deliberate mistakes of the
 * bad-input tests. A zeroed struct: no validation, nothing of the host's own but its
 * timelineSemaphore bit, everything Nimbus asks for. */
typedef struct VksOptions {
    int validation;                               /* VK_LAYER_KHRONOS_validation + sync validation + messenger */
    uint32_t host_instance_extension_count;       /* the host's own, e.g. GLFW's required ones */
    const char *const *host_instance_extensions;
    uint32_t host_device_extension_count;         /* the host's own, e.g. VK_KHR_swapchain */
    const char *const *host_device_extensions;
    const char *omit_instance_extension;          /* leave this name out of the instance */
    const char *omit_device_extension;            /* leave this name out of the device */
    int omit_first_device_extension;              /* leave out the first name Nimbus lists */
    int skip_feature_merge;                       /* no nimbus_vulkan_device_requirements_merge_features */
    int no_host_timeline;                         /* the host does not set timelineSemaphore itself */
    int clear_timeline_after_merge;               /* clear timelineSemaphore after the merge */
    VksLockFn lock, unlock;                       /* the host's queue lock, taken around its own */
    void *lock_user;                              /* queue use in these helpers (optional) */
} VksOptions;

typedef struct VkSetup {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger;
    uint32_t api_version;                         /* given to vkCreateInstance */
    uint32_t instance_extension_count;            /* given to vkCreateInstance (kept alive: Nimbus reads them) */
    const char *instance_extensions[VKS_MAX_NAMES];
    VkPhysicalDevice physical_device;
    VkPhysicalDeviceProperties properties;
    VkPhysicalDeviceMemoryProperties memory;
    VkDevice device;
    VkQueue queue;
    uint32_t queue_family;
    uint32_t device_extension_count;              /* given to vkCreateDevice */
    const char *device_extensions[VKS_MAX_NAMES];
    /* The feature chain given to vkCreateDevice: the host's own structs, with Nimbus's bits
     * merged in (and any struct of Nimbus's appended after them). Do not move this struct. */
    VkPhysicalDeviceFeatures2 features2;
    VkPhysicalDeviceVulkan11Features features11;
    VkPhysicalDeviceVulkan12Features features12;
    VkPhysicalDeviceVulkan13Features features13;
    /* Destroyed right after vkCreateDevice when the merge appended nothing of its own to the
     * chain; otherwise kept until vks_destroy, since enabled_features (the chain) points into
     * it and Nimbus reads the chain at every nimbus_context_create. */
    NimbusVulkanDeviceRequirements *requirements;
    const char *omitted_instance_extension;       /* the name actually left out, if any */
    const char *omitted_device_extension;
    uint32_t dropped_instance_extensions;         /* names left out with it (they need it) */
    uint32_t dropped_device_extensions;
    int merge_set_timeline;                       /* the merge turned timelineSemaphore on */
    VkCommandPool pool;                           /* for the one-shot helpers */
    VksLockFn lock, unlock;                       /* from VksOptions */
    void *lock_user;
    int32_t nimbus_rc;                            /* the code of a Nimbus call that failed in here */
    char error[512];
} VkSetup;

static inline int vks_fail(VkSetup *s, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->error, sizeof s->error, fmt, ap);
    va_end(ap);
    return 1;
}

static inline void vks_lock(VkSetup *s) { if (s->lock) s->lock(s->lock_user); }
static inline void vks_unlock(VkSetup *s) { if (s->unlock) s->unlock(s->lock_user); }

static inline NimbusVkGetInstanceProcAddr vks_gipa(void) {
    return (NimbusVkGetInstanceProcAddr)vkGetInstanceProcAddr;
}

/* Adds `name` to `names` unless it is there already or is the one to omit. */
static inline int vks_add_name(const char **names, uint32_t *count, const char *name, const char *omit,
                               const char **omitted) {
    uint32_t i;
    if (omit && strcmp(name, omit) == 0) {
        if (omitted) *omitted = name;
        return 0;
    }
    for (i = 0; i < *count; i++)
        if (strcmp(names[i], name) == 0) return 0;
    if (*count >= VKS_MAX_NAMES) return 1;
    names[(*count)++] = name;
    return 0;
}

/* Extensions that need another one enabled with them (instance and device): when a test
 * leaves a name out, the names needing it go too, so the setup stays valid Vulkan. */
static const char *const VKS_EXTENSION_NEEDS[][2] = {
    {"VK_KHR_xlib_surface", "VK_KHR_surface"},
    {"VK_KHR_xcb_surface", "VK_KHR_surface"},
    {"VK_KHR_wayland_surface", "VK_KHR_surface"},
    {"VK_KHR_win32_surface", "VK_KHR_surface"},
    {"VK_KHR_android_surface", "VK_KHR_surface"},
    {"VK_EXT_metal_surface", "VK_KHR_surface"},
    {"VK_EXT_headless_surface", "VK_KHR_surface"},
    {"VK_KHR_display", "VK_KHR_surface"},
    {"VK_KHR_get_surface_capabilities2", "VK_KHR_surface"},
    {"VK_KHR_surface_protected_capabilities", "VK_KHR_get_surface_capabilities2"},
    {"VK_EXT_swapchain_colorspace", "VK_KHR_surface"},
    {"VK_EXT_surface_maintenance1", "VK_KHR_surface"},
    {"VK_KHR_get_display_properties2", "VK_KHR_display"},
    {"VK_EXT_direct_mode_display", "VK_KHR_display"},
    {"VK_EXT_display_surface_counter", "VK_KHR_display"},
    {"VK_EXT_acquire_xlib_display", "VK_EXT_direct_mode_display"},
    {"VK_EXT_acquire_drm_display", "VK_EXT_direct_mode_display"},
    {"VK_KHR_swapchain_mutable_format", "VK_KHR_swapchain"},
    {"VK_EXT_swapchain_maintenance1", "VK_KHR_swapchain"},
    {"VK_KHR_present_id", "VK_KHR_swapchain"},
    {"VK_KHR_present_wait", "VK_KHR_present_id"},
    {"VK_KHR_incremental_present", "VK_KHR_swapchain"},
    {"VK_KHR_display_swapchain", "VK_KHR_swapchain"},
    {"VK_KHR_shared_presentable_image", "VK_KHR_swapchain"},
    {"VK_EXT_full_screen_exclusive", "VK_KHR_swapchain"},
    {"VK_EXT_hdr_metadata", "VK_KHR_swapchain"},
    {"VK_EXT_display_control", "VK_KHR_swapchain"},
    {"VK_GOOGLE_display_timing", "VK_KHR_swapchain"},
};

/* Drops, until none is left, every name whose needed extension is not in the list. Returns
 * how many were dropped. */
static inline uint32_t vks_drop_orphans(const char **names, uint32_t *count) {
    uint32_t dropped = 0, i, j, k;
    int changed = 1;
    while (changed) {
        changed = 0;
        for (i = 0; i < *count; i++) {
            for (k = 0; k < sizeof VKS_EXTENSION_NEEDS / sizeof VKS_EXTENSION_NEEDS[0]; k++) {
                int found = 0;
                if (strcmp(names[i], VKS_EXTENSION_NEEDS[k][0]) != 0) continue;
                for (j = 0; j < *count; j++)
                    if (strcmp(names[j], VKS_EXTENSION_NEEDS[k][1]) == 0) found = 1;
                if (found) continue;
                for (j = i; j + 1 < *count; j++) names[j] = names[j + 1];
                (*count)--;
                dropped++;
                changed = 1;
                break;
            }
            if (changed) break;
        }
    }
    return dropped;
}

static inline int vks_has_extension(const VkExtensionProperties *props, uint32_t n, const char *name) {
    uint32_t i;
    for (i = 0; i < n; i++)
        if (strcmp(props[i].extensionName, name) == 0) return 1;
    return 0;
}

/* The instance (apiVersion 1.3) with Nimbus's instance extensions merged into the host's, and
 * physical device 0. */
static inline int vks_create_instance(VkSetup *s, const VksOptions *o) {
    const char *nimbus_names[VKS_MAX_NAMES];
    uint32_t n = 0, i, avail = 0;
    VkExtensionProperties *props = NULL;
    VkApplicationInfo app;
    VkInstanceCreateInfo ci;
    VkValidationFeaturesEXT features;
    VkValidationFeatureEnableEXT enables[1] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkDebugUtilsMessengerCreateInfoEXT messenger;
    const char *layers[1] = {VKS_VALIDATION_LAYER};
    VkPhysicalDevice devices[16];
    uint32_t device_count = 16;
    VkResult r;
    int32_t rc;

    memset(s, 0, sizeof *s);
    s->lock = o->lock;
    s->unlock = o->unlock;
    s->lock_user = o->lock_user;
    rc = nimbus_vulkan_instance_extensions(vks_gipa(), &n, NULL);
    if (rc == NIMBUS_OK && n > VKS_MAX_NAMES) return vks_fail(s, "Nimbus asks for %u instance extensions", n);
    if (rc == NIMBUS_OK) rc = nimbus_vulkan_instance_extensions(vks_gipa(), &n, nimbus_names);
    if (rc != NIMBUS_OK) {
        s->nimbus_rc = rc;
        return vks_fail(s, "nimbus_vulkan_instance_extensions: %s: %s", nimbus_result_name(rc), nimbus_context_last_error(NULL));
    }
    for (i = 0; i < o->host_instance_extension_count; i++)
        if (vks_add_name(s->instance_extensions, &s->instance_extension_count, o->host_instance_extensions[i],
                         o->omit_instance_extension, &s->omitted_instance_extension))
            return vks_fail(s, "too many instance extensions");
    for (i = 0; i < n; i++)
        if (vks_add_name(s->instance_extensions, &s->instance_extension_count, nimbus_names[i],
                         o->omit_instance_extension, &s->omitted_instance_extension))
            return vks_fail(s, "too many instance extensions");

    if (s->omitted_instance_extension)
        s->dropped_instance_extensions = vks_drop_orphans(s->instance_extensions, &s->instance_extension_count);
    if (o->validation) {
        VkLayerProperties lp[64];
        uint32_t lc = 64;
        int found = 0;
        vkEnumerateInstanceLayerProperties(&lc, lp);
        for (i = 0; i < lc; i++)
            if (strcmp(lp[i].layerName, VKS_VALIDATION_LAYER) == 0) found = 1;
        if (!found) return vks_fail(s, "the validation layer %s is not installed (vulkan-validationlayers)", VKS_VALIDATION_LAYER);
        vks_add_name(s->instance_extensions, &s->instance_extension_count, VK_EXT_DEBUG_UTILS_EXTENSION_NAME, NULL, NULL);
        vks_add_name(s->instance_extensions, &s->instance_extension_count, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME, NULL, NULL);
    }

    /* Every name must be offered by the loader (or by the validation layer). */
    {
        uint32_t base = 0, layer = 0;
        vkEnumerateInstanceExtensionProperties(NULL, &base, NULL);
        if (o->validation) vkEnumerateInstanceExtensionProperties(VKS_VALIDATION_LAYER, &layer, NULL);
        props = (VkExtensionProperties *)calloc((size_t)base + layer + 1, sizeof *props);
        if (!props) return vks_fail(s, "out of memory");
        vkEnumerateInstanceExtensionProperties(NULL, &base, props);
        if (o->validation) vkEnumerateInstanceExtensionProperties(VKS_VALIDATION_LAYER, &layer, props + base);
        avail = base + layer;
        for (i = 0; i < s->instance_extension_count; i++)
            if (!vks_has_extension(props, avail, s->instance_extensions[i])) {
                vks_fail(s, "instance extension %s is not available", s->instance_extensions[i]);
                free(props);
                return 1;
            }
        free(props);
    }

    memset(&app, 0, sizeof app);
    app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
    app.pApplicationName = "nimbus vulkan host";
    app.applicationVersion = 1;
    app.apiVersion = VK_API_VERSION_1_3;
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
    ci.pApplicationInfo = &app;
    ci.enabledExtensionCount = s->instance_extension_count;
    ci.ppEnabledExtensionNames = s->instance_extensions;
    if (o->validation) {
        /* The messenger in the chain also sees vkCreateInstance and vkDestroyInstance. */
        vks_messenger_info(&messenger);
        memset(&features, 0, sizeof features);
        features.sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT;
        features.pNext = &messenger;
        features.enabledValidationFeatureCount = 1;
        features.pEnabledValidationFeatures = enables;
        ci.pNext = &features;
        ci.enabledLayerCount = 1;
        ci.ppEnabledLayerNames = layers;
    }
    r = vkCreateInstance(&ci, NULL, &s->instance);
    if (r != VK_SUCCESS) {
        s->instance = VK_NULL_HANDLE;
        return vks_fail(s, "vkCreateInstance failed (%d)", (int)r);
    }
    s->api_version = app.apiVersion;
    if (o->validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(s->instance, "vkCreateDebugUtilsMessengerEXT");
        s->destroy_messenger =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(s->instance, "vkDestroyDebugUtilsMessengerEXT");
        vks_messenger_info(&messenger);
        if (!create || !s->destroy_messenger || create(s->instance, &messenger, NULL, &s->messenger) != VK_SUCCESS)
            return vks_fail(s, "vkCreateDebugUtilsMessengerEXT failed");
    }

    r = vkEnumeratePhysicalDevices(s->instance, &device_count, devices);
    if ((r != VK_SUCCESS && r != VK_INCOMPLETE) || device_count == 0) return vks_fail(s, "no Vulkan physical device");
    s->physical_device = devices[0];
    vkGetPhysicalDeviceProperties(s->physical_device, &s->properties);
    vkGetPhysicalDeviceMemoryProperties(s->physical_device, &s->memory);
    if (s->properties.apiVersion < VK_API_VERSION_1_3)
        return vks_fail(s, "%s supports Vulkan %u.%u; this host needs 1.3", s->properties.deviceName,
                        VK_API_VERSION_MAJOR(s->properties.apiVersion), VK_API_VERSION_MINOR(s->properties.apiVersion));
    return 0;
}

/* The instance as Nimbus sees it. */
static inline void vks_nimbus_instance(const VkSetup *s, NimbusVulkanInstance *out) {
    memset(out, 0, sizeof *out);
    out->get_instance_proc_addr = vks_gipa();
    out->instance = (void *)s->instance;
    out->api_version = s->api_version;
    out->extension_count = s->instance_extension_count;
    out->extensions = s->instance_extensions;
}

/* The device: Nimbus's device extensions merged into the host's, the host's feature chain
 * (VkPhysicalDeviceFeatures2 -> Vulkan11 -> Vulkan12 -> Vulkan13, with the host's own
 * timelineSemaphore) with Nimbus's features merged in, one queue of Nimbus's family. */
static inline int vks_create_device(VkSetup *s, const VksOptions *o) {
    NimbusVulkanInstance instance;
    NimbusVulkanDeviceRequirements *req = NULL;
    const char *nimbus_names[VKS_MAX_NAMES];
    uint32_t n = 0, i, family_count = 0, avail = 0;
    VkQueueFamilyProperties families[32];
    VkExtensionProperties *props;
    VkDeviceQueueCreateInfo qi;
    VkDeviceCreateInfo di;
    VkCommandPoolCreateInfo pi;
    const char *omit;
    float priority = 1.0f;
    int32_t rc;
    VkResult r;
    VkBool32 before;
    const VkBaseOutStructure *it;
    int foreign = 0;

    vks_nimbus_instance(s, &instance);
    rc = nimbus_vulkan_device_requirements_create(&instance, (void *)s->physical_device, &req);
    if (rc != NIMBUS_OK) {
        s->nimbus_rc = rc;
        return vks_fail(s, "nimbus_vulkan_device_requirements_create: %s: %s", nimbus_result_name(rc),
                        nimbus_context_last_error(NULL));
    }
    s->requirements = req;
    rc = nimbus_vulkan_device_requirements_extensions(req, &n, NULL);
    if (rc == NIMBUS_OK && n > VKS_MAX_NAMES) return vks_fail(s, "Nimbus asks for %u device extensions", n);
    if (rc == NIMBUS_OK) rc = nimbus_vulkan_device_requirements_extensions(req, &n, nimbus_names);
    if (rc != NIMBUS_OK) {
        s->nimbus_rc = rc;
        return vks_fail(s, "nimbus_vulkan_device_requirements_extensions: %s: %s", nimbus_result_name(rc),
                        nimbus_context_last_error(NULL));
    }
    omit = o->omit_device_extension;
    if (o->omit_first_device_extension && n > 0) omit = nimbus_names[0];
    for (i = 0; i < o->host_device_extension_count; i++)
        if (vks_add_name(s->device_extensions, &s->device_extension_count, o->host_device_extensions[i], omit,
                         &s->omitted_device_extension))
            return vks_fail(s, "too many device extensions");
    for (i = 0; i < n; i++)
        if (vks_add_name(s->device_extensions, &s->device_extension_count, nimbus_names[i], omit,
                         &s->omitted_device_extension))
            return vks_fail(s, "too many device extensions");
    if (s->omitted_device_extension)
        s->dropped_device_extensions = vks_drop_orphans(s->device_extensions, &s->device_extension_count);
    vkEnumerateDeviceExtensionProperties(s->physical_device, NULL, &avail, NULL);
    props = (VkExtensionProperties *)calloc((size_t)avail + 1, sizeof *props);
    if (!props) return vks_fail(s, "out of memory");
    vkEnumerateDeviceExtensionProperties(s->physical_device, NULL, &avail, props);
    for (i = 0; i < s->device_extension_count; i++)
        if (!vks_has_extension(props, avail, s->device_extensions[i])) {
            vks_fail(s, "device extension %s is not available on %s", s->device_extensions[i], s->properties.deviceName);
            free(props);
            return 1;
        }
    free(props);

    /* The host's own feature chain, core structs included, before Nimbus merges into it. */
    memset(&s->features2, 0, sizeof s->features2);
    memset(&s->features11, 0, sizeof s->features11);
    memset(&s->features12, 0, sizeof s->features12);
    memset(&s->features13, 0, sizeof s->features13);
    s->features2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
    s->features11.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES;
    s->features12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
    s->features13.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES;
    s->features2.pNext = &s->features11;
    s->features11.pNext = &s->features12;
    s->features12.pNext = &s->features13;
    s->features13.pNext = NULL;
    if (!o->no_host_timeline) s->features12.timelineSemaphore = VK_TRUE; /* the host's own use */
    before = s->features12.timelineSemaphore;
    if (!o->skip_feature_merge) {
        rc = nimbus_vulkan_device_requirements_merge_features(req, &s->features2);
        if (rc != NIMBUS_OK) {
            s->nimbus_rc = rc;
            return vks_fail(s, "nimbus_vulkan_device_requirements_merge_features: %s: %s", nimbus_result_name(rc),
                            nimbus_context_last_error(NULL));
        }
    }
    s->merge_set_timeline = !before && s->features12.timelineSemaphore;
    if (o->clear_timeline_after_merge) s->features12.timelineSemaphore = VK_FALSE;

    rc = nimbus_vulkan_device_requirements_queue_family(req, &s->queue_family);
    if (rc != NIMBUS_OK) {
        s->nimbus_rc = rc;
        return vks_fail(s, "nimbus_vulkan_device_requirements_queue_family: %s: %s", nimbus_result_name(rc),
                        nimbus_context_last_error(NULL));
    }
    family_count = 32;
    vkGetPhysicalDeviceQueueFamilyProperties(s->physical_device, &family_count, families);
    if (s->queue_family >= family_count ||
        (families[s->queue_family].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) !=
            (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))
        return vks_fail(s, "queue family %u (from Nimbus) is not a graphics+compute family", s->queue_family);

    memset(&qi, 0, sizeof qi);
    qi.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
    qi.queueFamilyIndex = s->queue_family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    memset(&di, 0, sizeof di);
    di.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
    di.pNext = &s->features2;
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.enabledExtensionCount = s->device_extension_count;
    di.ppEnabledExtensionNames = s->device_extensions;
    di.pEnabledFeatures = NULL; /* the features are in the chain */
    r = vkCreateDevice(s->physical_device, &di, NULL, &s->device);
    if (r != VK_SUCCESS) {
        s->device = VK_NULL_HANDLE;
        return vks_fail(s, "vkCreateDevice failed (%d)", (int)r);
    }
    /* The requirements must outlive vkCreateDevice; after it they are needed only while the
     * chain holds structs of theirs. */
    for (it = (const VkBaseOutStructure *)s->features2.pNext; it; it = it->pNext)
        if ((const void *)it != (const void *)&s->features11 && (const void *)it != (const void *)&s->features12 &&
            (const void *)it != (const void *)&s->features13)
            foreign = 1;
    if (!foreign) {
        nimbus_vulkan_device_requirements_destroy(req);
        s->requirements = NULL;
    }
    vkGetDeviceQueue(s->device, s->queue_family, 0, &s->queue);

    memset(&pi, 0, sizeof pi);
    pi.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = s->queue_family;
    if (vkCreateCommandPool(s->device, &pi, NULL, &s->pool) != VK_SUCCESS) return vks_fail(s, "vkCreateCommandPool failed");
    return 0;
}

static inline int vks_create(VkSetup *s, const VksOptions *o) {
    return vks_create_instance(s, o) || vks_create_device(s, o);
}

/* Fills the struct chained to NimbusContextDesc.next. Everything it points to lives in `s`. */
static inline void vks_device_ext(const VkSetup *s, NimbusVulkanDeviceExt *ext) {
    memset(ext, 0, sizeof *ext);
    ext->chain.s_type = NIMBUS_STYPE_VULKAN_DEVICE;
    vks_nimbus_instance(s, &ext->instance);
    ext->physical_device = (void *)s->physical_device;
    ext->device = (void *)s->device;
    ext->extension_count = s->device_extension_count;
    ext->extensions = s->device_extensions;
    ext->enabled_features = &s->features2;
    ext->queue = (void *)s->queue;
    ext->queue_family_index = s->queue_family;
    ext->queue_index = 0;
}

static inline void vks_wait_idle(VkSetup *s) {
    if (!s->device) return;
    vks_lock(s);
    vkDeviceWaitIdle(s->device);
    vks_unlock(s);
}

/* Destroys the device (everything made on it must be gone: the validation layer reports
 * leftovers here), the requirements, the messenger and the instance. */
static inline void vks_destroy(VkSetup *s) {
    if (s->device) {
        vks_wait_idle(s);
        if (s->pool) vkDestroyCommandPool(s->device, s->pool, NULL);
        vkDestroyDevice(s->device, NULL);
    }
    nimbus_vulkan_device_requirements_destroy(s->requirements);
    if (s->messenger) s->destroy_messenger(s->instance, s->messenger, NULL);
    if (s->instance) vkDestroyInstance(s->instance, NULL);
    s->device = VK_NULL_HANDLE;
    s->pool = VK_NULL_HANDLE;
    s->requirements = NULL;
    s->messenger = VK_NULL_HANDLE;
    s->instance = VK_NULL_HANDLE;
}

/* ---- memory, images, buffers -------------------------------------------------------------- */

static inline int vks_memory_type(const VkSetup *s, uint32_t bits, VkMemoryPropertyFlags want) {
    uint32_t i;
    for (i = 0; i < s->memory.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (s->memory.memoryTypes[i].propertyFlags & want) == want) return (int)i;
    return -1;
}

static inline VkImageAspectFlags vks_format_aspect(VkFormat format) {
    switch (format) {
    case VK_FORMAT_D16_UNORM:
    case VK_FORMAT_D32_SFLOAT:
    case VK_FORMAT_X8_D24_UNORM_PACK32: return VK_IMAGE_ASPECT_DEPTH_BIT;
    case VK_FORMAT_S8_UINT: return VK_IMAGE_ASPECT_STENCIL_BIT;
    case VK_FORMAT_D16_UNORM_S8_UINT:
    case VK_FORMAT_D24_UNORM_S8_UINT:
    case VK_FORMAT_D32_SFLOAT_S8_UINT: return VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
    default: return VK_IMAGE_ASPECT_COLOR_BIT;
    }
}

typedef struct VksImage {
    VkImage image;
    VkDeviceMemory memory;
    VkFormat format;
    VkImageUsageFlags usage;
    uint32_t width, height;
    VkImageAspectFlags aspect;
    VkImageLayout layout; /* where the host's command stream has left it */
} VksImage;

/* A 2D image with `mips` levels and `layers` layers (optimal tiling) in device-local memory,
 * layout UNDEFINED. */
static inline int vks_image_create_levels(VkSetup *s, VksImage *img, VkFormat format, VkImageUsageFlags usage,
                                          uint32_t width, uint32_t height, uint32_t mips, uint32_t layers) {
    VkImageCreateInfo ci;
    VkMemoryRequirements mr;
    VkMemoryAllocateInfo ai;
    int type;
    memset(img, 0, sizeof *img);
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
    ci.imageType = VK_IMAGE_TYPE_2D;
    ci.format = format;
    ci.extent.width = width;
    ci.extent.height = height;
    ci.extent.depth = 1;
    ci.mipLevels = mips;
    ci.arrayLayers = layers;
    ci.samples = VK_SAMPLE_COUNT_1_BIT;
    ci.tiling = VK_IMAGE_TILING_OPTIMAL;
    ci.usage = usage;
    ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ci.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    if (vkCreateImage(s->device, &ci, NULL, &img->image) != VK_SUCCESS)
        return vks_fail(s, "vkCreateImage (format %d, usage 0x%x, %ux%u) failed", (int)format, usage, width, height);
    vkGetImageMemoryRequirements(s->device, img->image, &mr);
    type = vks_memory_type(s, mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type < 0) type = vks_memory_type(s, mr.memoryTypeBits, 0);
    memset(&ai, 0, sizeof ai);
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    ai.allocationSize = mr.size;
    ai.memoryTypeIndex = (uint32_t)type;
    if (type < 0 || vkAllocateMemory(s->device, &ai, NULL, &img->memory) != VK_SUCCESS ||
        vkBindImageMemory(s->device, img->image, img->memory, 0) != VK_SUCCESS) {
        vkDestroyImage(s->device, img->image, NULL);
        if (img->memory) vkFreeMemory(s->device, img->memory, NULL);
        memset(img, 0, sizeof *img);
        return vks_fail(s, "cannot allocate image memory");
    }
    img->format = format;
    img->usage = usage;
    img->width = width;
    img->height = height;
    img->aspect = vks_format_aspect(format);
    img->layout = VK_IMAGE_LAYOUT_UNDEFINED;
    return 0;
}

/* A 2D image (1 mip, 1 layer, optimal tiling) in device-local memory, layout UNDEFINED. */
static inline int vks_image_create(VkSetup *s, VksImage *img, VkFormat format, VkImageUsageFlags usage,
                                   uint32_t width, uint32_t height) {
    return vks_image_create_levels(s, img, format, usage, width, height, 1, 1);
}

static inline void vks_image_destroy(VkSetup *s, VksImage *img) {
    if (img->image) vkDestroyImage(s->device, img->image, NULL);
    if (img->memory) vkFreeMemory(s->device, img->memory, NULL);
    memset(img, 0, sizeof *img);
}

static inline VkImageView vks_image_view(VkSetup *s, const VksImage *img) {
    VkImageViewCreateInfo ci;
    VkImageView view = VK_NULL_HANDLE;
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
    ci.image = img->image;
    ci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    ci.format = img->format;
    ci.subresourceRange.aspectMask = img->aspect;
    ci.subresourceRange.levelCount = 1;
    ci.subresourceRange.layerCount = 1;
    if (vkCreateImageView(s->device, &ci, NULL, &view) != VK_SUCCESS) return VK_NULL_HANDLE;
    return view;
}

/* The image as Nimbus sees it: in img->layout when Nimbus's work runs, left in `final_layout`
 * (VK_IMAGE_LAYOUT_UNDEFINED: the same). */
static inline NimbusVulkanImage vks_nimbus_image(const VksImage *img, VkImageLayout final_layout) {
    NimbusVulkanImage out;
    memset(&out, 0, sizeof out);
    out.image = VKS_HANDLE(img->image);
    out.format = (uint32_t)img->format;
    out.width = img->width;
    out.height = img->height;
    out.mip_levels = 1;
    out.array_layers = 1;
    out.usage = (uint32_t)img->usage;
    out.layout = (uint32_t)img->layout;
    out.final_layout = (uint32_t)final_layout;
    return out;
}

typedef struct VksBuffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    void *mapped; /* host-visible, coherent, mapped for its whole life */
} VksBuffer;

static inline int vks_buffer_create(VkSetup *s, VksBuffer *b, VkDeviceSize size, VkBufferUsageFlags usage) {
    VkBufferCreateInfo ci;
    VkMemoryRequirements mr;
    VkMemoryAllocateInfo ai;
    int type;
    memset(b, 0, sizeof *b);
    memset(&ci, 0, sizeof ci);
    ci.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
    ci.size = size;
    ci.usage = usage;
    ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (vkCreateBuffer(s->device, &ci, NULL, &b->buffer) != VK_SUCCESS) return vks_fail(s, "vkCreateBuffer failed");
    vkGetBufferMemoryRequirements(s->device, b->buffer, &mr);
    type = vks_memory_type(s, mr.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    memset(&ai, 0, sizeof ai);
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    ai.allocationSize = mr.size;
    ai.memoryTypeIndex = (uint32_t)type;
    if (type < 0 || vkAllocateMemory(s->device, &ai, NULL, &b->memory) != VK_SUCCESS ||
        vkBindBufferMemory(s->device, b->buffer, b->memory, 0) != VK_SUCCESS ||
        vkMapMemory(s->device, b->memory, 0, VK_WHOLE_SIZE, 0, &b->mapped) != VK_SUCCESS) {
        vkDestroyBuffer(s->device, b->buffer, NULL);
        if (b->memory) vkFreeMemory(s->device, b->memory, NULL);
        memset(b, 0, sizeof *b);
        return vks_fail(s, "cannot allocate host-visible buffer memory");
    }
    b->size = size;
    return 0;
}

static inline void vks_buffer_destroy(VkSetup *s, VksBuffer *b) {
    if (b->buffer) vkDestroyBuffer(s->device, b->buffer, NULL);
    if (b->memory) vkFreeMemory(s->device, b->memory, NULL); /* unmaps */
    memset(b, 0, sizeof *b);
}

/* ---- barriers ------------------------------------------------------------------------------ */

/* The stages and accesses of an image's use in `layout`: as the source of a barrier (the use
 * before it: only its writes need making available) or as its destination. */
static inline void vks_layout_scope(VkImageLayout layout, int as_source, VkPipelineStageFlags *stage,
                                    VkAccessFlags *access) {
    VkAccessFlags reads = 0, writes = 0;
    switch (layout) {
    case VK_IMAGE_LAYOUT_UNDEFINED:
        *stage = as_source ? VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT : VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
        break;
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
        writes = VK_ACCESS_TRANSFER_WRITE_BIT;
        break;
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
        reads = VK_ACCESS_TRANSFER_READ_BIT;
        break;
    case VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        reads = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
        writes = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        break;
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
        reads = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
        writes = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        break;
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT |
                 VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
        reads = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
        break;
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL:
        *stage = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
        reads = VK_ACCESS_SHADER_READ_BIT;
        break;
    case VK_IMAGE_LAYOUT_PRESENT_SRC_KHR:
        *stage = as_source ? VK_PIPELINE_STAGE_TRANSFER_BIT /* the acquire semaphore's wait stage */
                           : VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT;
        break;
    default:
        *stage = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
        reads = VK_ACCESS_MEMORY_READ_BIT;
        writes = VK_ACCESS_MEMORY_WRITE_BIT;
        break;
    }
    *access = as_source ? writes : (reads | writes);
}

/* A layout barrier over mips [mip, mip + mips) and layers [layer, layer + layers). */
static inline void vks_image_barrier_range(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect,
                                           uint32_t mip, uint32_t mips, uint32_t layer, uint32_t layers,
                                           VkImageLayout from, VkImageLayout to) {
    VkImageMemoryBarrier b;
    VkPipelineStageFlags src, dst;
    memset(&b, 0, sizeof b);
    b.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
    vks_layout_scope(from, 1, &src, &b.srcAccessMask);
    vks_layout_scope(to, 0, &dst, &b.dstAccessMask);
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange.aspectMask = aspect;
    b.subresourceRange.baseMipLevel = mip;
    b.subresourceRange.levelCount = mips;
    b.subresourceRange.baseArrayLayer = layer;
    b.subresourceRange.layerCount = layers;
    vkCmdPipelineBarrier(cmd, src, dst, 0, 0, NULL, 0, NULL, 1, &b);
}

static inline void vks_image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                                     VkImageLayout to) {
    vks_image_barrier_range(cmd, image, aspect, 0, 1, 0, 1, from, to);
}

/* Moves `img` from the layout the host's command stream left it in to `to` (a barrier even
 * when the layout stays: it orders the earlier use before the next). */
static inline void vks_transition(VkCommandBuffer cmd, VksImage *img, VkImageLayout to) {
    vks_image_barrier(cmd, img->image, img->aspect, img->layout, to);
    img->layout = to;
}

/* ---- submissions ---------------------------------------------------------------------------- */

/* vkQueueSubmit of one command buffer with optional waits and signals (timeline values when
 * the value arrays are given; ignored for binary semaphores) and fence, under the host's lock. */
static inline VkResult vks_submit(VkSetup *s, VkCommandBuffer cmd, uint32_t wait_count, const VkSemaphore *waits,
                                  const uint64_t *wait_values, const VkPipelineStageFlags *wait_stages,
                                  uint32_t signal_count, const VkSemaphore *signals, const uint64_t *signal_values,
                                  VkFence fence) {
    VkSubmitInfo si;
    VkTimelineSemaphoreSubmitInfo ti;
    VkResult r;
    memset(&si, 0, sizeof si);
    memset(&ti, 0, sizeof ti);
    si.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
    si.waitSemaphoreCount = wait_count;
    si.pWaitSemaphores = waits;
    si.pWaitDstStageMask = wait_stages;
    si.commandBufferCount = cmd ? 1 : 0;
    si.pCommandBuffers = cmd ? &cmd : NULL;
    si.signalSemaphoreCount = signal_count;
    si.pSignalSemaphores = signals;
    if (wait_values || signal_values) {
        ti.sType = VK_STRUCTURE_TYPE_TIMELINE_SEMAPHORE_SUBMIT_INFO;
        ti.waitSemaphoreValueCount = wait_values ? wait_count : 0;
        ti.pWaitSemaphoreValues = wait_values;
        ti.signalSemaphoreValueCount = signal_values ? signal_count : 0;
        ti.pSignalSemaphoreValues = signal_values;
        si.pNext = &ti;
    }
    vks_lock(s);
    r = vkQueueSubmit(s->queue, 1, &si, fence);
    vks_unlock(s);
    return r;
}

static inline VkCommandBuffer vks_begin_once(VkSetup *s) {
    VkCommandBufferAllocateInfo ai;
    VkCommandBufferBeginInfo bi;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    memset(&ai, 0, sizeof ai);
    ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    ai.commandPool = s->pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    if (vkAllocateCommandBuffers(s->device, &ai, &cmd) != VK_SUCCESS) return VK_NULL_HANDLE;
    memset(&bi, 0, sizeof bi);
    bi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    vkBeginCommandBuffer(cmd, &bi);
    return cmd;
}

/* Ends, submits (with optional semaphore waits/signals), waits for the queue to idle, frees. */
static inline int vks_end_once_sync(VkSetup *s, VkCommandBuffer cmd, uint32_t wait_count, const VkSemaphore *waits,
                                    const uint64_t *wait_values, const VkPipelineStageFlags *wait_stages,
                                    uint32_t signal_count, const VkSemaphore *signals, const uint64_t *signal_values) {
    VkResult r = vkEndCommandBuffer(cmd);
    if (r == VK_SUCCESS)
        r = vks_submit(s, cmd, wait_count, waits, wait_values, wait_stages, signal_count, signals, signal_values,
                       VK_NULL_HANDLE);
    if (r == VK_SUCCESS) {
        vks_lock(s);
        r = vkQueueWaitIdle(s->queue);
        vks_unlock(s);
    }
    vkFreeCommandBuffers(s->device, s->pool, 1, &cmd);
    return r == VK_SUCCESS ? 0 : vks_fail(s, "one-shot submission failed (%d)", (int)r);
}

static inline int vks_end_once(VkSetup *s, VkCommandBuffer cmd) {
    return vks_end_once_sync(s, cmd, 0, NULL, NULL, NULL, 0, NULL, NULL);
}

static inline VkSemaphore vks_semaphore(VkSetup *s, int timeline, uint64_t initial) {
    VkSemaphoreCreateInfo ci;
    VkSemaphoreTypeCreateInfo ti;
    VkSemaphore sem = VK_NULL_HANDLE;
    memset(&ci, 0, sizeof ci);
    memset(&ti, 0, sizeof ti);
    ci.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
    if (timeline) {
        ti.sType = VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO;
        ti.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
        ti.initialValue = initial;
        ci.pNext = &ti;
    }
    if (vkCreateSemaphore(s->device, &ci, NULL, &sem) != VK_SUCCESS) return VK_NULL_HANDLE;
    return sem;
}

/* ---- pixels: half floats, sRGB, the scene upload and the color readback --------------------- */

static inline uint16_t vks_float_to_half(float f) {
    uint32_t x, sign, mant, half, rem;
    int32_t e;
    memcpy(&x, &f, sizeof x);
    sign = (x >> 16) & 0x8000u;
    mant = x & 0x7fffffu;
    if (((x >> 23) & 0xffu) == 0xffu) return (uint16_t)(sign | 0x7c00u | (mant ? 0x200u : 0u)); /* inf, NaN */
    e = (int32_t)((x >> 23) & 0xffu) - 127 + 15;
    if (e >= 31) return (uint16_t)(sign | 0x7c00u); /* overflow: infinity */
    if (e <= 0) {                                   /* a half subnormal, or zero */
        uint32_t shift, halfway;
        if (e < -10) return (uint16_t)sign;
        mant |= 0x800000u;
        shift = (uint32_t)(14 - e);
        half = mant >> shift;
        rem = mant & ((1u << shift) - 1u);
        halfway = 1u << (shift - 1u);
        if (rem > halfway || (rem == halfway && (half & 1u))) half++;
        return (uint16_t)(sign | half);
    }
    half = sign | ((uint32_t)e << 10) | (mant >> 13);
    rem = mant & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (half & 1u))) half++; /* round to nearest even; may carry */
    return (uint16_t)half;
}

static inline float vks_half_to_float(uint16_t h) {
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, mant = h & 0x3ffu, x;
    float f;
    if (e == 0) {
        f = ldexpf((float)mant, -24);
        return sign ? -f : f;
    }
    if (e == 31) x = sign | 0x7f800000u | (mant << 13);
    else x = sign | ((e + 112u) << 23) | (mant << 13);
    memcpy(&f, &x, sizeof f);
    return f;
}

static inline uint8_t vks_srgb_encode(float c) {
    float v;
    if (!(c > 0.0f)) return 0; /* also NaN */
    if (c >= 1.0f) return 255;
    v = c <= 0.0031308f ? 12.92f * c : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
    return (uint8_t)(v * 255.0f + 0.5f);
}

static inline uint8_t vks_unorm8(float c) {
    if (!(c > 0.0f)) return 0;
    if (c >= 1.0f) return 255;
    return (uint8_t)(c * 255.0f + 0.5f);
}

/* Bytes per pixel of the color formats these helpers convert (0: not one of them). */
static inline uint32_t vks_color_bytes(VkFormat format) {
    switch (format) {
    case VK_FORMAT_R16G16B16A16_SFLOAT: return 8;
    case VK_FORMAT_R8G8B8A8_SRGB:
    case VK_FORMAT_R8G8B8A8_UNORM:
    case VK_FORMAT_B8G8R8A8_SRGB:
    case VK_FORMAT_B8G8R8A8_UNORM: return 4;
    default: return 0;
    }
}

static inline uint32_t vks_depth_bytes(VkFormat format) {
    return format == VK_FORMAT_D32_SFLOAT ? 4u : format == VK_FORMAT_D16_UNORM ? 2u : 0u;
}

/* The staging buffer of a scene upload: color (as stored in `color_format`), then depth. */
static inline VkDeviceSize vks_depth_offset(VkFormat color_format, uint32_t w, uint32_t h) {
    VkDeviceSize color = (VkDeviceSize)w * h * vks_color_bytes(color_format);
    return (color + 15u) & ~(VkDeviceSize)15u;
}

static inline VkDeviceSize vks_staging_size(VkFormat color_format, VkFormat depth_format, uint32_t w, uint32_t h) {
    return vks_depth_offset(color_format, w, h) + (VkDeviceSize)w * h * vks_depth_bytes(depth_format);
}

/* One linear RGBA float pixel as stored in `format` (sRGB formats encode on the CPU). */
static inline void vks_store_color(VkFormat format, const float *rgba, uint8_t *dst) {
    int srgb = format == VK_FORMAT_R8G8B8A8_SRGB || format == VK_FORMAT_B8G8R8A8_SRGB;
    int bgr = format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_B8G8R8A8_UNORM;
    int c;
    if (format == VK_FORMAT_R16G16B16A16_SFLOAT) {
        uint16_t h[4];
        for (c = 0; c < 4; c++) h[c] = vks_float_to_half(rgba[c]);
        memcpy(dst, h, sizeof h);
        return;
    }
    for (c = 0; c < 3; c++) dst[bgr ? 2 - c : c] = srgb ? vks_srgb_encode(rgba[c]) : vks_unorm8(rgba[c]);
    dst[3] = vks_unorm8(rgba[3]);
}

/* Writes the CPU scene (linear RGBA floats, clip depth) into the staging buffer. */
static inline void vks_write_scene(const VksBuffer *staging, VkFormat color_format, VkFormat depth_format, uint32_t w,
                                   uint32_t h, const float *rgba, const float *depth) {
    uint8_t *p = (uint8_t *)staging->mapped, *d = p + vks_depth_offset(color_format, w, h);
    size_t i, n = (size_t)w * h, bpp = vks_color_bytes(color_format);
    for (i = 0; i < n; i++) vks_store_color(color_format, rgba + i * 4, p + i * bpp);
    if (depth_format == VK_FORMAT_D32_SFLOAT) {
        memcpy(d, depth, n * sizeof(float));
    } else {
        for (i = 0; i < n; i++) {
            float z = depth[i] < 0.0f ? 0.0f : depth[i] > 1.0f ? 1.0f : depth[i];
            uint16_t v = (uint16_t)(z * 65535.0f + 0.5f);
            memcpy(d + i * 2, &v, sizeof v);
        }
    }
}

static inline void vks_copy_to_image(VkCommandBuffer cmd, VkBuffer buffer, VkDeviceSize offset, const VksImage *img,
                                     VkImageAspectFlags aspect) {
    VkBufferImageCopy region;
    memset(&region, 0, sizeof region);
    region.bufferOffset = offset;
    region.imageSubresource.aspectMask = aspect;
    region.imageSubresource.layerCount = 1;
    region.imageExtent.width = img->width;
    region.imageExtent.height = img->height;
    region.imageExtent.depth = 1;
    vkCmdCopyBufferToImage(cmd, buffer, img->image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
}

/* Records the upload of a staging buffer written by vks_write_scene into `color` and `depth`
 * (depth may be NULL), from the layouts they are in, leaving them in `color_layout` and
 * `depth_layout` (as if the host's render pass had left them there). */
static inline void vks_record_upload(VkCommandBuffer cmd, const VksBuffer *staging, VksImage *color, VksImage *depth,
                                     VkImageLayout color_layout, VkImageLayout depth_layout) {
    vks_transition(cmd, color, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    if (depth) vks_transition(cmd, depth, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    vks_copy_to_image(cmd, staging->buffer, 0, color, VK_IMAGE_ASPECT_COLOR_BIT);
    if (depth)
        vks_copy_to_image(cmd, staging->buffer, vks_depth_offset(color->format, color->width, color->height), depth,
                          VK_IMAGE_ASPECT_DEPTH_BIT);
    if (color_layout != VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL) vks_transition(cmd, color, color_layout);
    if (depth && depth_layout != VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL) vks_transition(cmd, depth, depth_layout);
}

/* Records the copy of `color` (moved to TRANSFER_SRC_OPTIMAL from the layout it is in) into
 * `buffer`, made visible to the host. */
static inline void vks_record_readback(VkCommandBuffer cmd, VksImage *color, const VksBuffer *buffer) {
    VkBufferImageCopy region;
    VkBufferMemoryBarrier b;
    if (color->layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL) vks_transition(cmd, color, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    memset(&region, 0, sizeof region);
    region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
    region.imageSubresource.layerCount = 1;
    region.imageExtent.width = color->width;
    region.imageExtent.height = color->height;
    region.imageExtent.depth = 1;
    vkCmdCopyImageToBuffer(cmd, color->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer->buffer, 1, &region);
    memset(&b, 0, sizeof b);
    b.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER;
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.buffer = buffer->buffer;
    b.size = VK_WHOLE_SIZE;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, NULL, 1, &b, 0, NULL);
}

/* The linear value of channel c (0..3) of pixel i of read-back `format` data. */
static inline float vks_load_channel(VkFormat format, const void *data, size_t i, int c) {
    const uint8_t *p = (const uint8_t *)data;
    int bgr = format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_B8G8R8A8_UNORM;
    uint8_t v;
    if (format == VK_FORMAT_R16G16B16A16_SFLOAT) {
        uint16_t h;
        memcpy(&h, p + i * 8 + (size_t)c * 2, sizeof h);
        return vks_half_to_float(h);
    }
    v = p[i * 4 + (size_t)(bgr && c < 3 ? 2 - c : c)];
    if (c < 3 && (format == VK_FORMAT_R8G8B8A8_SRGB || format == VK_FORMAT_B8G8R8A8_SRGB)) {
        float s = (float)v / 255.0f;
        return s <= 0.04045f ? s / 12.92f : powf((s + 0.055f) / 1.055f, 2.4f);
    }
    return (float)v / 255.0f;
}

/* Read-back color data to sRGB-encoded RGBA8 rows (for PNG): sRGB formats are copied as
 * stored (already encoded), linear ones are encoded on the CPU. */
static inline void vks_to_srgb8(VkFormat format, const void *data, uint32_t w, uint32_t h, uint8_t *rgba8) {
    const uint8_t *p = (const uint8_t *)data;
    size_t i, n = (size_t)w * h;
    int c;
    for (i = 0; i < n; i++) {
        switch (format) {
        case VK_FORMAT_R8G8B8A8_SRGB: memcpy(rgba8 + i * 4, p + i * 4, 4); break;
        case VK_FORMAT_B8G8R8A8_SRGB:
            rgba8[i * 4 + 0] = p[i * 4 + 2]; rgba8[i * 4 + 1] = p[i * 4 + 1];
            rgba8[i * 4 + 2] = p[i * 4 + 0]; rgba8[i * 4 + 3] = p[i * 4 + 3];
            break;
        default:
            for (c = 0; c < 3; c++) rgba8[i * 4 + c] = vks_srgb_encode(vks_load_channel(format, data, i, c));
            rgba8[i * 4 + 3] = vks_unorm8(vks_load_channel(format, data, i, 3));
            break;
        }
    }
}

/* One-shot: the scene upload, leaving the images in the given layouts; waits. */
static inline int vks_upload_scene(VkSetup *s, const VksBuffer *staging, VksImage *color, VksImage *depth,
                                   VkImageLayout color_layout, VkImageLayout depth_layout) {
    VkCommandBuffer cmd = vks_begin_once(s);
    if (!cmd) return vks_fail(s, "vkAllocateCommandBuffers failed");
    vks_record_upload(cmd, staging, color, depth, color_layout, depth_layout);
    return vks_end_once(s, cmd);
}

/* One-shot: reads `color` back from the layout it is in (color->layout: e.g. the final layout
 * promised to Nimbus) into `readback` and converts it to sRGB-encoded RGBA8 (`rgba8` may be
 * NULL: the raw data stays in readback->mapped). Leaves it in TRANSFER_SRC_OPTIMAL. */
static inline int vks_read_color(VkSetup *s, VksImage *color, const VksBuffer *readback, uint8_t *rgba8) {
    VkCommandBuffer cmd = vks_begin_once(s);
    if (!cmd) return vks_fail(s, "vkAllocateCommandBuffers failed");
    vks_record_readback(cmd, color, readback);
    if (vks_end_once(s, cmd)) return 1;
    if (rgba8) vks_to_srgb8(color->format, readback->mapped, color->width, color->height, rgba8);
    return 0;
}

#endif
