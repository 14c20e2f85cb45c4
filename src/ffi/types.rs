//! The structs and integer enums of the C ABI. Released structs never change layout; new knobs
//! arrive as new chained structs. A zeroed struct means "defaults" wherever a default exists.

use std::ffi::c_void;

/// Header of every chained extension struct: put it first, set `s_type`, link with `next`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusChainedStruct {
    /// Which struct this is: a `NIMBUS_STYPE_*` value.
    pub s_type: u32,
    /// The next struct in the chain, or NULL.
    pub next: *const NimbusChainedStruct,
}

/// `s_type` of `NimbusSettingsExt` (chain it to `NimbusContextDesc.next`).
pub const NIMBUS_STYPE_SETTINGS: u32 = 1;
/// `s_type` of `NimbusQualityExt` (chain it to `NimbusContextDesc.next`). Since ABI 0.2.
pub const NIMBUS_STYPE_QUALITY: u32 = 2;

/// `s_type` of `NimbusViewportExt` (chain it to `NimbusTargets.next` or
/// `NimbusVulkanTargets.next`). Since ABI 0.3.
pub const NIMBUS_STYPE_VIEWPORT: u32 = 4;

/// Chained to a frame's targets: render only this rectangle of them (split screen, dynamic
/// resolution). The frame's projection maps onto the rectangle; pixels outside it are left
/// untouched; the scene depth is read at the same pixels. The history belongs to the frame's
/// view (`NimbusViewExt`): render each rectangle (each split-screen player) with a view of its
/// own; a change of a view's rectangle size starts its history afresh, moving it keeps it.
/// Since ABI 0.3.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusViewportExt {
    /// `s_type` = `NIMBUS_STYPE_VIEWPORT`.
    pub chain: NimbusChainedStruct,
    /// Left edge in pixels.
    pub x: u32,
    /// Top edge in pixels.
    pub y: u32,
    /// Width in pixels (at least 1; x + width within the targets).
    pub width: u32,
    /// Height in pixels (at least 1; y + height within the targets).
    pub height: u32,
}

/// The viewport a targets chain asks for, checking the chain.
pub(crate) fn viewport_of(
    next: *const NimbusChainedStruct,
) -> super::FfiResult<Option<crate::Viewport>> {
    super::context::check_chain(next, &[NIMBUS_STYPE_VIEWPORT])?;
    if next.is_null() {
        return Ok(None);
    }
    // SAFETY: the chain was checked; its first link has s_type NIMBUS_STYPE_VIEWPORT.
    let link = unsafe { &*next };
    if !link.next.is_null() {
        return Err(super::FfiError::new(
            super::NIMBUS_ERROR_UNKNOWN_STRUCT,
            "NimbusViewportExt appears more than once, or with another struct, in the targets' chain",
        ));
    }
    // SAFETY: an s_type of NIMBUS_STYPE_VIEWPORT promises a NimbusViewportExt.
    let v = unsafe { &*(next as *const NimbusViewportExt) };
    Ok(Some(crate::Viewport {
        x: v.x,
        y: v.y,
        width: v.width,
        height: v.height,
    }))
}

/// Window platforms for `NimbusWindowHandle.platform`.
pub const NIMBUS_PLATFORM_X11: u32 = 1;
/// Wayland: `display` is the `wl_display*`, `surface` the `wl_surface*`.
pub const NIMBUS_PLATFORM_WAYLAND: u32 = 2;
/// Win32: `display` is the `HINSTANCE` (may be NULL), `window` the `HWND`.
pub const NIMBUS_PLATFORM_WIN32: u32 = 3;
/// AppKit: `surface` is the `NSView*`.
pub const NIMBUS_PLATFORM_APPKIT: u32 = 4;

/// A native window to present to. The handles must outlive the context.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusWindowHandle {
    /// A `NIMBUS_PLATFORM_*` value.
    pub platform: u32,
    /// X11: the Xlib `Display*`. Wayland: the `wl_display*`. Win32: the `HINSTANCE`.
    pub display: *mut c_void,
    /// X11: the `Window` (XID). Win32: the `HWND`.
    pub window: u64,
    /// Wayland: the `wl_surface*`. AppKit: the `NSView*`.
    pub surface: *mut c_void,
}

/// How to create a context.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusContextDesc {
    /// Chained extensions (e.g. `NimbusSettingsExt`), or NULL.
    pub next: *const NimbusChainedStruct,
    /// Must be `NIMBUS_ABI_VERSION` of the header you compiled against.
    pub abi_version: u32,
    /// Window surface size in pixels (ignored without a window).
    pub width: u32,
    /// Window surface height in pixels.
    pub height: u32,
    /// The window to present to, or NULL for a headless context.
    pub window: *const NimbusWindowHandle,
}

/// Preset ids for `nimbus_context_set_weather` and `NimbusSettingsExt.initial_preset`.
pub const NIMBUS_PRESET_CLEAR: u32 = 1;
/// Fair-weather cumulus (the default).
pub const NIMBUS_PRESET_SPARSE: u32 = 2;
/// Cumulus over a broken stratocumulus deck.
pub const NIMBUS_PRESET_CLOUDY: u32 = 3;
/// A closed low deck.
pub const NIMBUS_PRESET_OVERCAST: u32 = 4;
/// Towering cumulonimbus over a dark deck.
pub const NIMBUS_PRESET_STORMY: u32 = 5;

/// Weather option flag: add the cirrus-like high layer.
pub const NIMBUS_WEATHER_CIRRUS: u32 = 1;
/// Weather option flag: turn on the horizon gradient (big clouds far away).
pub const NIMBUS_WEATHER_HORIZON_GRADIENT: u32 = 2;

/// Jitter setting: the default (on).
pub const NIMBUS_JITTER_DEFAULT: u32 = 0;
/// Jitter setting: blue-noise jitter of the ray start, against banding.
pub const NIMBUS_JITTER_ON: u32 = 1;
/// Jitter setting: no jitter (deterministic frame to frame, but banding).
pub const NIMBUS_JITTER_OFF: u32 = 2;

/// Quality level: the default (medium).
pub const NIMBUS_QUALITY_DEFAULT: u32 = 0;
/// Quarter-resolution grid, one pixel in 16 traced per frame, 48-96 steps.
pub const NIMBUS_QUALITY_LOW: u32 = 1;
/// Half-resolution grid, one pixel in 16 traced per frame, 48-96 steps (the default).
pub const NIMBUS_QUALITY_MEDIUM: u32 = 2;
/// Full-resolution grid, one pixel in 4 traced per frame, longer marches.
pub const NIMBUS_QUALITY_HIGH: u32 = 3;
/// Every pixel every frame, long marches, no temporal reuse (the unoptimised march).
pub const NIMBUS_QUALITY_ULTRA: u32 = 4;

/// Settings extension (`s_type = NIMBUS_STYPE_SETTINGS`). Zero in any field means its default.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusSettingsExt {
    /// Chain header.
    pub chain: NimbusChainedStruct,
    /// Weather at start: a `NIMBUS_PRESET_*` id. 0: sparse.
    pub initial_preset: u32,
    /// Seed of the noise volumes. 0: 1.
    pub noise_seed: u32,
    /// Most march steps per ray (4..=1024). 0: 96.
    pub march_max_steps: u32,
    /// Fewest march steps per ray (1..=max). 0: 48.
    pub march_min_steps: u32,
    /// A `NIMBUS_JITTER_*` value.
    pub jitter: u32,
    /// Rays end this far away, meters. 0: 120 000.
    pub max_distance: f32,
    /// Planet radius, meters. 0: 6 360 000.
    pub planet_radius: f32,
}

/// Quality extension (`s_type = NIMBUS_STYPE_QUALITY`), since ABI 0.2. The level is applied
/// first; the march fields of a `NimbusSettingsExt` in the same chain refine it.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusQualityExt {
    /// Chain header.
    pub chain: NimbusChainedStruct,
    /// A `NIMBUS_QUALITY_*` level. 0: medium.
    pub quality: u32,
}

/// `NimbusWeatherState.phase`: the transition starts later.
pub const NIMBUS_TRANSITION_SCHEDULED: u32 = 1;
/// `NimbusWeatherState.phase`: the transition is under way.
pub const NIMBUS_TRANSITION_RUNNING: u32 = 2;
/// `NimbusWeatherState.phase`: the transition has finished (or was instant, or the sky is
/// held after nimbus_context_cancel_weather).
pub const NIMBUS_TRANSITION_DONE: u32 = 3;
/// `NimbusWeatherState.phase`: the requested weather's map is still being generated, a slice
/// per frame; the transition starts once it is ready, at the later of its requested start
/// and that frame's time. `from_name` is the sky now, `to_name` the request, `start` its
/// requested start. Since ABI 0.7 (a context made with an older header reads SCHEDULED).
pub const NIMBUS_TRANSITION_PENDING: u32 = 4;

/// Largest preset (file or text) accepted, in bytes.
pub const NIMBUS_MAX_PRESET_BYTES: usize = 65536;

/// Longest weather name `NimbusWeatherState` carries, NUL included; longer names are cut.
pub const NIMBUS_WEATHER_NAME_CAPACITY: usize = 32;

/// The weather transition as seen at one time (nimbus_context_weather_state), since ABI 0.2.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusWeatherState {
    /// Chained extensions, or NULL.
    pub next: *const NimbusChainedStruct,
    /// Name of the weather the transition starts from, NUL-terminated (a frozen blend keeps
    /// the name of its nearer end).
    pub from_name: [std::ffi::c_char; NIMBUS_WEATHER_NAME_CAPACITY],
    /// Name of the weather it heads to, NUL-terminated.
    pub to_name: [std::ffi::c_char; NIMBUS_WEATHER_NAME_CAPACITY],
    /// Host time the transition starts at, seconds.
    pub start: f64,
    /// Its length in seconds (0: instant, or a held sky).
    pub duration: f64,
    /// Blend weight in [0, 1] at the queried time.
    pub progress: f32,
    /// A `NIMBUS_TRANSITION_*` value.
    pub phase: u32,
}

/// Depth flag: the projection is reversed-Z (near at depth 1).
pub const NIMBUS_DEPTH_REVERSED_Z: u32 = 1;
/// Depth flag: the projection has no far plane.
pub const NIMBUS_DEPTH_INFINITE_FAR: u32 = 2;
/// Depth flag (since ABI 0.2): the projection is OpenGL-style, clip z in [-w, w], and the
/// depth buffer holds OpenGL's window depth (z / w + 1) / 2. A matrix cannot tell the two
/// conventions apart (every OpenGL projection is also a valid [0, 1] projection with other near
/// and far planes), so without this flag an OpenGL matrix is read as a [0, 1] one and its
/// depth buffer misread: set it whenever the projection comes from an OpenGL-style helper
/// (glm::perspective without GLM_FORCE_DEPTH_ZERO_TO_ONE, glFrustum, ...).
pub const NIMBUS_DEPTH_GL_CLIP_Z: u32 = 4;

/// One frame's inputs. Matrices are column-major, right-handed, meters; clip depth in [0, 1].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusFrame {
    /// Chained extensions, or NULL.
    pub next: *const NimbusChainedStruct,
    /// World-to-view matrix (camera looks down -Z).
    pub view: [f32; 16],
    /// View-to-clip perspective projection.
    pub projection: [f32; 16],
    /// `NIMBUS_DEPTH_*` flags; they must match the projection (checked).
    pub depth_flags: u32,
    /// Direction from the scene toward the sun (normalised by Nimbus; not zero).
    pub sun_direction: [f32; 3],
    /// Linear RGB sun tint. All zero: white.
    pub sun_color: [f32; 3],
    /// Sun illuminance, lux-like linear units (0: no sun, e.g. at night).
    pub sun_illuminance: f32,
    /// Seconds on the host's clock: drives wind and weather transitions.
    pub time: f64,
}

/// Texture formats for `NimbusTextureDesc.format`.
pub const NIMBUS_FORMAT_RGBA8_UNORM: u32 = 1;
/// 8-bit sRGB-encoded color (stored encoded, read and written as linear by Nimbus).
pub const NIMBUS_FORMAT_RGBA8_UNORM_SRGB: u32 = 2;
/// Half-float linear HDR color.
pub const NIMBUS_FORMAT_RGBA16_FLOAT: u32 = 3;
/// Float linear HDR color (separate output only: not blendable in place).
pub const NIMBUS_FORMAT_RGBA32_FLOAT: u32 = 4;
/// One float per pixel: scene depth in the camera's clip-space convention.
pub const NIMBUS_FORMAT_R32_FLOAT: u32 = 5;
/// 8-bit color in B, G, R, A order (since ABI 0.3).
pub const NIMBUS_FORMAT_BGRA8_UNORM: u32 = 6;
/// 8-bit sRGB-encoded color in B, G, R, A order (since ABI 0.3).
pub const NIMBUS_FORMAT_BGRA8_UNORM_SRGB: u32 = 7;
/// 10-bit color with 2-bit alpha, one little-endian 32-bit word per pixel, R in the low bits
/// (Vulkan's `A2B10G10R10_UNORM_PACK32`; since ABI 0.3).
pub const NIMBUS_FORMAT_RGB10A2_UNORM: u32 = 8;
/// Packed unsigned float HDR color, one 32-bit word per pixel, R in the low 11 bits
/// (Vulkan's `B10G11R11_UFLOAT_PACK32`; since ABI 0.3). Only where the device can render to
/// it (`nimbus_texture_create` says so otherwise).
pub const NIMBUS_FORMAT_RG11B10_UFLOAT: u32 = 9;
/// A real 16-bit depth buffer (`D16_UNORM`), in the camera's depth convention, written as
/// 16-bit unsigned integers (since ABI 0.3). The other depth formats cannot be written from
/// the CPU (WebGPU's copy rules): hand a real D32 / D24S8 depth buffer in through the host
/// Vulkan device path, or write clip depth to `NIMBUS_FORMAT_R32_FLOAT`.
pub const NIMBUS_FORMAT_DEPTH16_UNORM: u32 = 10;

/// How to create a texture.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusTextureDesc {
    /// Chained extensions, or NULL.
    pub next: *const NimbusChainedStruct,
    /// Width in pixels, 1..=8192.
    pub width: u32,
    /// Height in pixels, 1..=8192.
    pub height: u32,
    /// A `NIMBUS_FORMAT_*` value.
    pub format: u32,
}

/// The textures of one frame, all the same size.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NimbusTargets {
    /// Chained extensions, or NULL.
    pub next: *const NimbusChainedStruct,
    /// The rendered scene (color format). Required.
    pub scene_color: *const super::NimbusTexture,
    /// Scene depth (`NIMBUS_FORMAT_R32_FLOAT`), or NULL when nothing occludes the clouds.
    pub scene_depth: *const super::NimbusTexture,
    /// Where `scene * T + L` goes: another color texture, `scene_color` itself (in place), or
    /// NULL to present to the context's window.
    pub output: *const super::NimbusTexture,
}

#[cfg(all(test, target_pointer_width = "64"))]
mod tests {
    use super::*;
    use std::mem::size_of;

    /// The C test (tests/c/api_test.c) asserts the same sizes from the header's side.
    #[test]
    fn released_struct_sizes_are_pinned() {
        assert_eq!(size_of::<NimbusChainedStruct>(), 16);
        assert_eq!(size_of::<NimbusWindowHandle>(), 32);
        assert_eq!(size_of::<NimbusContextDesc>(), 32);
        assert_eq!(size_of::<NimbusSettingsExt>(), 48);
        assert_eq!(size_of::<NimbusFrame>(), 176);
        assert_eq!(size_of::<NimbusTextureDesc>(), 24);
        assert_eq!(size_of::<NimbusTargets>(), 32);
        assert_eq!(size_of::<NimbusQualityExt>(), 24);
        assert_eq!(size_of::<NimbusWeatherState>(), 96);
    }

    #[test]
    fn preset_limit_matches_the_rust_one() {
        assert_eq!(
            NIMBUS_MAX_PRESET_BYTES,
            crate::weather::preset::MAX_PRESET_BYTES
        );
    }

    /// Every field's offset, as released; the C test pins the same from the header's side.
    #[test]
    fn released_field_offsets_are_pinned() {
        use std::mem::offset_of;
        let pins: &[(&str, usize, usize)] = &[
            ("chain.s_type", offset_of!(NimbusChainedStruct, s_type), 0),
            ("chain.next", offset_of!(NimbusChainedStruct, next), 8),
            (
                "window.platform",
                offset_of!(NimbusWindowHandle, platform),
                0,
            ),
            ("window.display", offset_of!(NimbusWindowHandle, display), 8),
            ("window.window", offset_of!(NimbusWindowHandle, window), 16),
            (
                "window.surface",
                offset_of!(NimbusWindowHandle, surface),
                24,
            ),
            ("desc.next", offset_of!(NimbusContextDesc, next), 0),
            (
                "desc.abi_version",
                offset_of!(NimbusContextDesc, abi_version),
                8,
            ),
            ("desc.width", offset_of!(NimbusContextDesc, width), 12),
            ("desc.height", offset_of!(NimbusContextDesc, height), 16),
            ("desc.window", offset_of!(NimbusContextDesc, window), 24),
            ("settings.chain", offset_of!(NimbusSettingsExt, chain), 0),
            (
                "settings.initial_preset",
                offset_of!(NimbusSettingsExt, initial_preset),
                16,
            ),
            (
                "settings.noise_seed",
                offset_of!(NimbusSettingsExt, noise_seed),
                20,
            ),
            (
                "settings.march_max_steps",
                offset_of!(NimbusSettingsExt, march_max_steps),
                24,
            ),
            (
                "settings.march_min_steps",
                offset_of!(NimbusSettingsExt, march_min_steps),
                28,
            ),
            ("settings.jitter", offset_of!(NimbusSettingsExt, jitter), 32),
            (
                "settings.max_distance",
                offset_of!(NimbusSettingsExt, max_distance),
                36,
            ),
            (
                "settings.planet_radius",
                offset_of!(NimbusSettingsExt, planet_radius),
                40,
            ),
            ("quality.chain", offset_of!(NimbusQualityExt, chain), 0),
            ("quality.quality", offset_of!(NimbusQualityExt, quality), 16),
            ("frame.next", offset_of!(NimbusFrame, next), 0),
            ("frame.view", offset_of!(NimbusFrame, view), 8),
            ("frame.projection", offset_of!(NimbusFrame, projection), 72),
            (
                "frame.depth_flags",
                offset_of!(NimbusFrame, depth_flags),
                136,
            ),
            (
                "frame.sun_direction",
                offset_of!(NimbusFrame, sun_direction),
                140,
            ),
            ("frame.sun_color", offset_of!(NimbusFrame, sun_color), 152),
            (
                "frame.sun_illuminance",
                offset_of!(NimbusFrame, sun_illuminance),
                164,
            ),
            ("frame.time", offset_of!(NimbusFrame, time), 168),
            ("texture_desc.next", offset_of!(NimbusTextureDesc, next), 0),
            (
                "texture_desc.width",
                offset_of!(NimbusTextureDesc, width),
                8,
            ),
            (
                "texture_desc.height",
                offset_of!(NimbusTextureDesc, height),
                12,
            ),
            (
                "texture_desc.format",
                offset_of!(NimbusTextureDesc, format),
                16,
            ),
            ("targets.next", offset_of!(NimbusTargets, next), 0),
            (
                "targets.scene_color",
                offset_of!(NimbusTargets, scene_color),
                8,
            ),
            (
                "targets.scene_depth",
                offset_of!(NimbusTargets, scene_depth),
                16,
            ),
            ("targets.output", offset_of!(NimbusTargets, output), 24),
            ("state.next", offset_of!(NimbusWeatherState, next), 0),
            (
                "state.from_name",
                offset_of!(NimbusWeatherState, from_name),
                8,
            ),
            ("state.to_name", offset_of!(NimbusWeatherState, to_name), 40),
            ("state.start", offset_of!(NimbusWeatherState, start), 72),
            (
                "state.duration",
                offset_of!(NimbusWeatherState, duration),
                80,
            ),
            (
                "state.progress",
                offset_of!(NimbusWeatherState, progress),
                88,
            ),
            ("state.phase", offset_of!(NimbusWeatherState, phase), 92),
        ];
        for (name, got, want) in pins {
            assert_eq!(got, want, "offset of {name}");
        }
    }
}
