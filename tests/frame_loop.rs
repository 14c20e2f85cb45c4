//! The frame loop creates nothing: after the first frames (which build the bind groups of the
//! history ping-pong), frames make no bind groups, views, pipelines or shader modules, on a
//! moving camera with the clock running, in every composite mode. Settings, weather and size
//! changes may create objects, and only then.

use glam::{Mat4, Vec3};
use nimbus::{Camera, DepthConvention, FrameInputs, Headless, Sun, Weather};

mod common;
use common::{headless, small_noise};

/// A camera that turns and climbs every frame, on a running clock: every uniform changes.
fn moving_frame(i: u32) -> FrameInputs {
    let t = i as f32 * 0.05;
    let eye = Vec3::new(10.0 * t, 600.0 + 5.0 * t, 0.0);
    let target = eye + Vec3::new(t.sin(), 0.2, -t.cos());
    FrameInputs {
        camera: Camera {
            view: Mat4::look_at_rh(eye, target, Vec3::Y),
            projection: Mat4::perspective_rh(1.0, 16.0 / 9.0, 1.0, 400_000.0),
            depth: DepthConvention::default(),
        },
        sun: Sun::default(),
        time: i as f64 / 30.0,
    }
}

fn frames(h: &mut Headless, range: std::ops::Range<u32>) {
    for i in range {
        h.render(&moving_frame(i)).unwrap();
    }
}

fn assert_frames_create_nothing(h: &mut Headless, what: &str) {
    // Two warm-up frames: the history ping-pong binds each of its two textures once.
    frames(h, 0..2);
    let (made, live) = (h.renderer().bind_groups_created(), h.live_objects());
    frames(h, 2..24);
    assert_eq!(
        h.renderer().bind_groups_created(),
        made,
        "{what}: frames made bind groups"
    );
    assert_eq!(
        h.live_objects().counts(),
        live.counts(),
        "{what}: live objects changed over plain frames (buffers, views, bind groups, pipelines, shaders): {} then {}",
        live,
        h.live_objects()
    );
}

#[test]
fn frames_create_no_gpu_objects() {
    let mut h = headless(small_noise(3));
    assert_frames_create_nothing(&mut h, "separate output (compute composite)");
    h.set_storage_output(false).unwrap();
    assert_frames_create_nothing(&mut h, "separate output (fullscreen triangle)");
    h.set_in_place(true);
    assert_frames_create_nothing(&mut h, "in place");
    // Scene depth switches the march and composite variants: warm up, then again nothing.
    let scene = nimbus::demo::standard_views()[0].scene(common::W, common::H);
    h.upload_scene(&scene.color, Some(&scene.depth)).unwrap();
    assert_frames_create_nothing(&mut h, "with scene depth");
    // The cloud shadow map: made with the settings, then updated every frame in place.
    let mut s = small_noise(3);
    s.shadows.enabled = true;
    s.shadows.resolution = 64;
    h.renderer_mut().set_settings(s).unwrap();
    assert_frames_create_nothing(&mut h, "with the cloud shadow map");
}

#[test]
fn only_changes_create_bind_groups() {
    let mut h = headless(small_noise(4));
    frames(&mut h, 0..4);
    let made = h.renderer().bind_groups_created();
    // A weather request swaps the map slots: new bind groups, once.
    h.renderer_mut()
        .set_weather(Weather::cloudy(), 4.0 / 30.0, 1.0)
        .unwrap();
    frames(&mut h, 4..8);
    let after_weather = h.renderer().bind_groups_created();
    assert!(
        after_weather > made,
        "new weather maps need new bind groups"
    );
    frames(&mut h, 8..20);
    assert_eq!(h.renderer().bind_groups_created(), after_weather);
    // A resize: new per-size textures, new bind groups, once.
    h.resize(common::W / 2, common::H / 2).unwrap();
    frames(&mut h, 20..24);
    let after_resize = h.renderer().bind_groups_created();
    assert!(after_resize > after_weather);
    frames(&mut h, 24..40);
    assert_eq!(h.renderer().bind_groups_created(), after_resize);
}

#[test]
fn settings_change_of_a_scale_bakes_nothing_and_keeps_the_noise() {
    let mut h = headless(small_noise(5));
    frames(&mut h, 0..2);
    let before = h.read_noise(nimbus::NoiseVolume::Base, 0).unwrap();
    let made = h.renderer().bind_groups_created();
    let mut s = h.renderer().settings().clone();
    s.noise.base_scale *= 1.5;
    s.noise.weather_extent *= 0.5;
    h.renderer_mut().set_settings(s.clone()).unwrap();
    assert_eq!(h.renderer().settings().noise.base_scale, s.noise.base_scale);
    // The same volumes and maps stay bound: the next frames bind nothing new.
    frames(&mut h, 2..6);
    assert_eq!(
        h.renderer().bind_groups_created(),
        made,
        "a tile-scale change re-baked textures"
    );
    // A new seed does re-bake (new volumes, new bind groups, other contents).
    s.noise.seed = 99;
    h.renderer_mut().set_settings(s).unwrap();
    frames(&mut h, 6..8);
    assert!(h.renderer().bind_groups_created() > made);
    assert_ne!(h.read_noise(nimbus::NoiseVolume::Base, 0).unwrap(), before);
}

#[test]
fn a_lost_device_is_reported_and_a_new_one_works() {
    let mut h = headless(small_noise(6));
    frames(&mut h, 0..2);
    h.device().destroy();
    let e = h.render(&moving_frame(2)).unwrap_err();
    assert!(matches!(e, nimbus::Error::DeviceLost(_)), "{e}");
    // It stays lost, with the same error, and never panics.
    assert!(matches!(
        h.render(&moving_frame(3)),
        Err(nimbus::Error::DeviceLost(_))
    ));
    drop(h);
    let mut again = headless(small_noise(6));
    frames(&mut again, 0..2);
}
