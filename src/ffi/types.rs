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

/// `s_type` of [`NimbusSettingsExt`] (chain it to `NimbusContextDesc::next`).
pub const NIMBUS_STYPE_SETTINGS: u32 = 1;

/// Window platforms for [`NimbusWindowHandle::platform`].
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
    /// Chained extensions (e.g. [`NimbusSettingsExt`]), or NULL.
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

/// Preset ids for `nimbus_context_set_weather` and `NimbusSettingsExt::initial_preset`.
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
/// Half-resolution grid, one pixel in 16 traced per frame, short marches.
pub const NIMBUS_QUALITY_LOW: u32 = 1;
/// Full-resolution grid, one pixel in 16 traced per frame (the default).
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
    /// A `NIMBUS_QUALITY_*` level, applied before the march fields above refine it.
    /// 0: medium.
    pub quality: u32,
}

/// Depth flag: the projection is reversed-Z (near at depth 1).
pub const NIMBUS_DEPTH_REVERSED_Z: u32 = 1;
/// Depth flag: the projection has no far plane.
pub const NIMBUS_DEPTH_INFINITE_FAR: u32 = 2;

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

/// Texture formats for [`NimbusTextureDesc::format`].
pub const NIMBUS_FORMAT_RGBA8_UNORM: u32 = 1;
/// 8-bit sRGB-encoded color (stored encoded, read and written as linear by Nimbus).
pub const NIMBUS_FORMAT_RGBA8_UNORM_SRGB: u32 = 2;
/// Half-float linear HDR color.
pub const NIMBUS_FORMAT_RGBA16_FLOAT: u32 = 3;
/// Float linear HDR color (separate output only: not blendable in place).
pub const NIMBUS_FORMAT_RGBA32_FLOAT: u32 = 4;
/// One float per pixel: scene depth in the camera's clip-space convention.
pub const NIMBUS_FORMAT_R32_FLOAT: u32 = 5;

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
    }
}
