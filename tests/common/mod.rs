//! Helpers shared by the GPU test files.
#![allow(dead_code)]

use nimbus::settings::{NoiseSettings, TraceResolution};
use nimbus::{Headless, Settings, Temporal};

pub const W: u32 = 160;
pub const H: u32 = 90;

/// A private runtime dir keeps Mesa from probing the session's.
pub fn setup() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join(format!("nimbus-xdg-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        std::env::set_var("XDG_RUNTIME_DIR", dir);
    }
}

pub fn headless(settings: Settings) -> Headless {
    setup();
    let mut h = Headless::new(settings).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
    h.resize(W, H).unwrap();
    h
}

/// The fidelity program's debug sphere (radius 1000 m, σt 0.02, albedo 0.999) at `center`,
/// with no ambient and no haze: all its light is the sun's.
pub fn debug_sphere(center: glam::Vec3) -> Settings {
    let mut s = small_noise(1);
    s.debug_density = nimbus::DebugDensity::Sphere {
        center,
        radius: 1_000.0,
        density: 1.0,
    };
    s.weather.clouds.extinction = 0.02;
    s.weather.clouds.albedo = 0.999;
    s.weather.ambient_top = glam::Vec3::ZERO;
    s.weather.ambient_bottom = glam::Vec3::ZERO;
    s.haze.fade_distance = f32::INFINITY;
    s
}

/// Small noise volumes keep the tests quick on software Vulkan.
pub fn small_noise(seed: u32) -> Settings {
    Settings {
        noise: NoiseSettings {
            seed,
            base_size: 32,
            detail_size: 16,
            weather_size: 128,
            blue_noise_size: 16,
            ..NoiseSettings::default()
        },
        ..Settings::default()
    }
}

/// The cumulus the reconstruction and approximation budgets were measured on: the eroded
/// edge's ramp unsharpened (`edge_sharpness` 1) and eroded 0.7 deep (the default shape until
/// 2026-12-07). Those tests judge the machinery (reduced grids, reprojection, the optimised
/// march, the shadow map's light) on a scene that stays put when the presets' look is retuned:
/// sharper outlines hold more detail than a half grid or a long step can carry, which moves
/// every such error without anything in the machinery changing (measured at sharpness 4 and
/// depth 1: the half grid's upsample 0.046 against 0.028 here, its bilinear resampling alone
/// 0.046; a sharper filter does not recover it, Catmull-Rom 0.047). The shipped look's errors
/// are the benchmark's (docs/performance.md).
pub fn measured_shape(mut s: Settings) -> Settings {
    s.weather.clouds.edge_sharpness = 1.0;
    s.weather.clouds.detail_strength = 0.7;
    s
}

/// Settings for comparing single frames: the blue-noise jitter rotates every frame, so it is
/// off, and every pixel is traced every frame (no temporal reprojection) on the full-resolution
/// grid (the default level traces a half grid), so a pixel of `read_clouds` is one ray.
pub fn quiet(mut s: Settings) -> Settings {
    s.march.jitter = false;
    s.march.temporal = Temporal::OFF;
    s.march.resolution = TraceResolution::Full;
    s
}

/// Linear value as stored in an RGBA16F target.
pub fn f16(v: f32) -> f32 {
    half::f16::from_f32(v).to_f32()
}

/// The mean of an image's RGB channels over all pixels: the level a machinery test's budget
/// scales with, since the loss of a reduced grid or a reprojection grows with the clouds'
/// brightness and contrast.
pub fn mean_level(pixels: &[[f32; 4]]) -> f64 {
    pixels
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0)
        .sum::<f64>()
        / pixels.len() as f64
}

/// Pixels as RGBA16F bytes (for uploads).
pub fn halfs(pixels: &[[f32; 4]]) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| p.map(|c| half::f16::from_f32(c).to_bits()))
        .flat_map(u16::to_le_bytes)
        .collect()
}

/// RGBA16F bytes (a readback) as pixels.
pub fn rgba(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytes
        .chunks_exact(8)
        .map(|c| {
            let h = |i: usize| half::f16::from_le_bytes([c[i], c[i + 1]]).to_f32();
            [h(0), h(2), h(4), h(6)]
        })
        .collect()
}

/// Writes `bytes` (`bpp` bytes a texel, rows packed) into the whole of mip 0 of `texture`.
pub fn upload(queue: &wgpu::Queue, texture: &wgpu::Texture, bytes: &[u8], bpp: u32) {
    queue.write_texture(
        texture.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(texture.width() * bpp),
            rows_per_image: Some(texture.height()),
        },
        texture.size(),
    );
}
