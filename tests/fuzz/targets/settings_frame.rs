//! `Settings::validate` and the frame checks on arbitrary numbers: never a panic, and settings
//! that validate keep every light-march step length finite and positive (the combined check).
#![no_main]

use nimbus::glam::{Mat4, Vec3};
use nimbus::{Camera, DepthConvention, FrameInputs, Quality, Settings, Sun};

#[path = "bytes.rs"]
mod bytes;
use bytes::Bytes;

/// Mostly tame numbers (so deep checks are reached), sometimes raw bits (NaN, inf, huge).
fn num(b: &mut Bytes) -> f32 {
    let tag = b.u32();
    if tag % 4 == 0 {
        f32::from_bits(b.u32())
    } else {
        (tag >> 2) as f32 / 1024.0 - 1000.0
    }
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let mut s = Settings::default();
    [Quality::Low, Quality::Medium, Quality::High, Quality::Ultra][b.small(4) as usize]
        .apply(&mut s);
    s.planet.radius = num(&mut b);
    s.noise.seed = b.u32();
    s.noise.base_size = 1 << b.small(10);
    s.noise.detail_scale = num(&mut b);
    s.lighting.light_steps = b.small(200);
    s.lighting.light_step_growth = 1.0 + num(&mut b).abs() % 4.0;
    s.lighting.light_distance = num(&mut b);
    s.lighting.multiple_scattering.octaves = b.small(10);
    s.lighting.multiple_scattering.attenuation = num(&mut b);
    s.march.max_steps = b.small(1100);
    s.march.min_steps = b.small(1100);
    s.march.max_distance = num(&mut b);
    s.march.transmittance_cutoff = num(&mut b);
    s.haze.fade_distance = num(&mut b);
    s.weather.clouds.coverage = num(&mut b);
    s.weather.layer.bottom_altitude = num(&mut b);
    s.weather.layer.top_altitude = num(&mut b);
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
        *v = num(&mut b);
    }
    // Half the time a real camera with fuzzed parts, so the depth-convention checks run.
    if b.small(2) == 0 {
        m = Mat4::look_at_rh(
            Vec3::new(num(&mut b), num(&mut b), num(&mut b)),
            Vec3::new(num(&mut b), 1.0, num(&mut b)),
            Vec3::Y,
        )
        .to_cols_array();
        p = Mat4::perspective_rh(num(&mut b), num(&mut b), num(&mut b), num(&mut b))
            .to_cols_array();
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
            direction: Vec3::new(num(&mut b), num(&mut b), num(&mut b)),
            color: Vec3::new(num(&mut b), num(&mut b), num(&mut b)),
            illuminance: num(&mut b),
        },
        time: num(&mut b) as f64 * 1e6,
    };
    if let Err(e) = frame.check() {
        assert!(e.to_string().len() < 600, "long message: {e}");
    }
});
