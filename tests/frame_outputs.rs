//! The per-frame outputs (contract version 1): the cloud image's front depth against the
//! closed-form entry into a debug sphere, its transmittance, with and without the temporal
//! resolve.

mod common;

use common::{headless, quiet, small_noise, H, W};
use glam::{Mat4, Vec3, Vec4};
use nimbus::{
    Camera, DebugDensity, DepthConvention, FrameInputs, Settings, Sun, ViewId,
    FRAME_OUTPUTS_VERSION,
};

const CENTER: Vec3 = Vec3::new(0.0, 3_000.0, -4_000.0);
const RADIUS: f32 = 800.0;
const SIGMA_T: f32 = 0.002;

fn sphere(mut s: Settings) -> Settings {
    s.weather.clouds.extinction = SIGMA_T;
    s.debug_density = DebugDensity::Sphere {
        center: CENTER,
        radius: RADIUS,
        density: 1.0,
    };
    s
}

fn frame() -> (FrameInputs, Mat4) {
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let view = Mat4::look_at_rh(eye, CENTER, Vec3::Y);
    let projection = Mat4::perspective_rh(40f32.to_radians(), W as f32 / H as f32, 1.0, 1e5);
    let f = FrameInputs {
        camera: Camera {
            view,
            projection,
            depth: DepthConvention::default(),
        },
        sun: Sun::default(),
        time: 0.0,
    };
    (f, (projection * view).inverse())
}

/// The entry distance and chord of the ray through the center of trace-grid pixel (x, y) (a grid
/// of `grid` pixels over the view) into the sphere.
fn entry(inv: Mat4, x: u32, y: u32, grid: (u32, u32)) -> Option<(f32, f32)> {
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let ndc = Vec4::new(
        (x as f32 + 0.5) / grid.0 as f32 * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / grid.1 as f32 * 2.0,
        0.0,
        1.0,
    );
    let p = inv * ndc;
    let d = (p.truncate() / p.w - eye).normalize();
    let oc = eye - CENTER;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - RADIUS * RADIUS);
    (disc > 0.0).then(|| (-b - disc.sqrt(), 2.0 * disc.sqrt()))
}

fn check(pixels: &[[f32; 4]], grid: (u32, u32), inv: Mat4, what: &str) {
    assert_eq!(
        pixels.len(),
        (grid.0 * grid.1) as usize,
        "{what}: one texel per grid pixel"
    );
    let (mut worst, mut hits) = (0.0f32, 0);
    for y in 0..grid.1 {
        for x in 0..grid.0 {
            let [t, front, depth, _] = pixels[(y * grid.0 + x) as usize];
            match entry(inv, x, y, grid) {
                // Away from the rim (where a step may miss the thin cap): the front depth is
                // the entry to within a march step (the chord over at least 48 steps).
                Some((t0, chord)) if chord > 200.0 => {
                    hits += 1;
                    worst = worst.max((front - t0).abs());
                    assert!(
                        depth >= front - 1.0 && depth <= t0 + chord,
                        "{what} ({x}, {y}): depth {depth} outside [{front}, {}]",
                        t0 + chord
                    );
                    let want = (-SIGMA_T * chord).exp();
                    assert!(
                        (t - want).abs() < 0.01,
                        "{what} ({x}, {y}): T {t}, closed form {want}"
                    );
                }
                None => {
                    assert_eq!((front, depth), (0.0, 0.0), "{what} ({x}, {y}) has no cloud");
                    assert!(t > 0.999, "{what} ({x}, {y}): T {t} off the sphere");
                }
                _ => {}
            }
        }
    }
    println!("{what}: {hits} pixels on the sphere, worst |front - entry| {worst:.1} m");
    // The sphere covers about 9% of the view.
    let min_hits = grid.0 * grid.1 / 15;
    assert!(
        hits > min_hits,
        "{what}: the sphere covers only {hits} pixels"
    );
    assert!(worst < 40.0, "{what}: front depth off by {worst} m");
}

#[test]
fn the_front_depth_is_the_entry_into_a_debug_sphere() {
    let (f, inv) = frame();
    // Every pixel traced in the one frame.
    let mut h = headless(sphere(quiet(small_noise(1))));
    h.render(&f).unwrap();
    let out = h.renderer().frame_outputs(ViewId::DEFAULT).unwrap();
    assert_eq!(out.version, FRAME_OUTPUTS_VERSION);
    assert_eq!(out.grid, (W, H));
    assert!(out.shadows.is_none());
    check(&h.read_frame_outputs().unwrap(), (W, H), inv, "one frame");

    // The default level: a half-resolution grid, one pixel in 16 a frame, the rest from the
    // resolve's history. Jitter on: the front depth is the start of the step, not the
    // jittered sample.
    let mut h = headless(sphere(small_noise(1)));
    assert!(h.renderer().frame_outputs(ViewId::DEFAULT).is_err());
    for _ in 0..16 {
        h.render(&f).unwrap();
    }
    let grid = h.renderer().frame_outputs(ViewId::DEFAULT).unwrap().grid;
    assert_eq!(grid, (W / 2, H / 2));
    check(
        &h.read_frame_outputs().unwrap(),
        grid,
        inv,
        "temporal, 16 frames",
    );
    let other = h.renderer_mut().create_view().unwrap();
    assert!(h.renderer().frame_outputs(other).is_err());
}
