//! The C API from C: builds the shared library, compiles the C programs with
//! `-std=c99 -Wall -Wextra -Werror -pedantic` (the API test under AddressSanitizer and UBSan),
//! runs them, and compares the headless C program's PNG with a Rust render of the same view.

mod common;
use common::{f16, quiet, setup};

use std::path::PathBuf;
use std::process::Command;

use nimbus::demo::standard_views;
use nimbus::{Headless, Settings};

fn srgb_byte(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

#[test]
fn c_programs_pass_and_match_the_rust_render() {
    setup();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    // `cargo test` builds no cdylib: build it (cargo releases its lock while tests run).
    // With the test hooks (panic, device loss), which the release library never exports.
    let status = Command::new(env!("CARGO"))
        .args(["build", "--lib", "--features", "test-hooks"])
        .current_dir(&root)
        .status()
        .expect("run cargo build --lib");
    assert!(status.success(), "cargo build --lib failed");
    let out_dir = target.join("c");
    let output = Command::new("make")
        .arg("-C")
        .arg(root.join("examples-c"))
        .arg(format!("LIBDIR={}", target.join("debug").display()))
        .arg(format!("OUT={}", out_dir.display()))
        .arg("check")
        .env("RUST_BACKTRACE", "0")
        // `cargo test --release` puts target/release (a library without the test hooks) on
        // LD_LIBRARY_PATH, which the loader searches before the programs' RUNPATH.
        .env_remove("LD_LIBRARY_PATH")
        .output()
        .expect("run make (install make and a C compiler)");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stdout}");
    assert!(
        output.status.success(),
        "make check failed:\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains(" passed, 0 failed"),
        "C API test summary missing:\n{stdout}"
    );
    let cases: usize = stdout
        .lines()
        .find_map(|l| l.strip_prefix("bad-input cases: "))
        .and_then(|n| n.trim().parse().ok())
        .expect("the C test reports its bad-input case count");
    assert!(cases >= 60, "only {cases} bad-input cases");
    // Caught panics go to the log callback, never to the host's stderr.
    assert!(
        !stderr.contains("panicked at"),
        "a panic message reached stderr:\n{stderr}"
    );

    // The same view in Rust: jitter off, plain sky color, no depth, sRGB output.
    let (w, h) = (160u32, 90u32);
    let c_png = image::open(out_dir.join("headless.png"))
        .expect("headless.png")
        .to_rgba8();
    assert_eq!(c_png.dimensions(), (w, h));
    // The C host keeps the default level's trace grid (it renders 16 frames of one pixel in 16,
    // jitter off: every grid pixel traced once, as one frame with temporal reuse off).
    let mut settings = quiet(Settings::default());
    settings.march.resolution = Settings::default().march.resolution;
    let mut r = Headless::new(settings).unwrap();
    r.resize(w, h).unwrap();
    r.upload_scene(&vec![[0.2, 0.35, 0.7, 1.0]; (w * h) as usize], None)
        .unwrap();
    r.render(&standard_views()[0].frame(w, h, 0.0)).unwrap();
    let rust = r.read_output().unwrap();
    let (mut worst, mut sum) = (0i32, 0i64);
    for (p, c) in rust.iter().zip(c_png.pixels()) {
        for (linear, encoded) in p.iter().zip(c.0).take(3) {
            let d = (srgb_byte(f16(*linear)) as i32 - encoded as i32).abs();
            worst = worst.max(d);
            sum += d as i64;
        }
    }
    let mean = sum as f64 / (w * h * 3) as f64;
    println!("C vs Rust render: max difference {worst}/255, mean {mean:.3}/255");
    assert!(
        worst <= 3 && mean < 0.5,
        "C render differs: max {worst}, mean {mean}"
    );
}
