//! `Settings::validate` and the frame checks on arbitrary numbers: never a panic, and settings
//! that validate keep every light-march step length finite and positive (the combined check).
#![no_main]

use nimbus::glam::{Mat4, Vec3};
use nimbus::{Camera, DepthConvention, FrameInputs, Quality, Settings, Sun};

/// Reads little-endian values off the input, zeros once it runs out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u32(&mut self) -> u32 {
        let mut b = [0u8; 4];
        let n = self.0.len().min(4);
        b[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        u32::from_le_bytes(b)
    }
    fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }
    /// Mostly tame numbers (so deep checks are reached), sometimes raw bits (NaN, inf, huge).
    fn num(&mut self) -> f32 {
        let tag = self.u32();
        if tag % 4 == 0 {
            self.f32()
        } else {
            (tag >> 2) as f32 / 1024.0 - 1000.0
        }
    }
    fn small(&mut self, n: u32) -> u32 {
        self.u32() % n
    }
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let mut s = Settings::default();
    [Quality::Low, Quality::Medium, Quality::High, Quality::Ultra][b.small(4) as usize]
        .apply(&mut s);
    s.planet.radius = b.num();
    s.noise.seed = b.u32();
    s.noise.base_size = 1 << b.small(10);
    s.noise.detail_scale = b.num();
    s.lighting.light_steps = b.small(200);
    s.lighting.light_step_growth = 1.0 + b.num().abs() % 4.0;
    s.lighting.light_distance = b.num();
    s.lighting.multiple_scattering.octaves = b.small(10);
    s.lighting.multiple_scattering.attenuation = b.num();
    s.march.max_steps = b.small(1100);
    s.march.min_steps = b.small(1100);
    s.march.max_distance = b.num();
    s.march.transmittance_cutoff = b.num();
    s.haze.fade_distance = b.num();
    s.weather.clouds.coverage = b.num();
    s.weather.layer.bottom_altitude = b.num();
    s.weather.layer.top_altitude = b.num();
    if s.validate().is_ok() {
        // The partition the shader computes: first step = d (r - 1) / (r^n - 1), in f32.
        let l = &s.lighting;
        let (r, n, d) = (l.light_step_growth, l.light_steps as f32, l.light_distance);
        let first = if r > 1.0001 {
            d * (r - 1.0) / (r.powf(n) - 1.0)
        } else {
            d / n
        };
        assert!(
            first.is_finite() && first > 0.0,
            "validated settings give a first light step of {first}"
        );
    }
    let mut m = [0.0f32; 16];
    let mut p = [0.0f32; 16];
    for v in m.iter_mut().chain(p.iter_mut()) {
        *v = b.num();
    }
    // Half the time a real camera with fuzzed parts, so the depth-convention checks run.
    if b.small(2) == 0 {
        m = Mat4::look_at_rh(
            Vec3::new(b.num(), b.num(), b.num()),
            Vec3::new(b.num(), 1.0, b.num()),
            Vec3::Y,
        )
        .to_cols_array();
        p = Mat4::perspective_rh(b.num(), b.num(), b.num(), b.num()).to_cols_array();
    }
    let flags = b.u32();
    let frame = FrameInputs {
        camera: Camera {
            view: Mat4::from_cols_array(&m),
            projection: Mat4::from_cols_array(&p),
            depth: DepthConvention {
                reversed_z: flags & 1 != 0,
                infinite_far: flags & 2 != 0,
                gl_clip_z: flags & 4 != 0,
            },
        },
        sun: Sun {
            direction: Vec3::new(b.num(), b.num(), b.num()),
            color: Vec3::new(b.num(), b.num(), b.num()),
            illuminance: b.num(),
        },
        time: b.num() as f64 * 1e6,
    };
    if let Err(e) = frame.check() {
        assert!(e.to_string().len() < 600, "long message: {e}");
    }
});
