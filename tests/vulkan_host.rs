//! The host-Vulkan-device path from C, under the Khronos validation layer with synchronisation
//! validation (any validation message fails): builds examples-c/vulkan_host.c and
//! tests/c/vulkan_test.c, runs the host with several entry / exit layout pairs, timeline
//! semaphores, the queue lock and 24 context lifetimes on one device, compares its picture
//! with the owned-device render of the same frames (FLIP), and runs the bad-input matrix.

mod common;
use common::setup;

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn target() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
}

/// Builds the library (with the same features as tests/c_api.rs, so the two tests share one
/// build) and the two C programs, once for both tests.
fn build() -> PathBuf {
    static BUILT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    BUILT.get_or_init(build_once).clone()
}

fn build_once() -> PathBuf {
    let status = Command::new(env!("CARGO"))
        .args(["build", "--lib", "--features", "test-hooks"])
        .current_dir(root())
        .status()
        .expect("run cargo build --lib");
    assert!(status.success(), "cargo build --lib failed");
    let out = target().join("c-vulkan");
    let made = Command::new("make")
        .arg("-C")
        .arg(root().join("examples-c"))
        .arg(format!("LIBDIR={}", target().join("debug").display()))
        .arg(format!("OUT={}", out.display()))
        .arg(out.join("vulkan_host"))
        .arg(out.join("vulkan_test"))
        .output()
        .expect("run make (install make, a C compiler, libvulkan-dev and libglfw3-dev)");
    assert!(
        made.status.success(),
        "make failed:\n{}\n{}",
        String::from_utf8_lossy(&made.stdout),
        String::from_utf8_lossy(&made.stderr)
    );
    out
}

/// Runs a program; returns its stdout, failing with both streams on a non-zero exit.
///
/// glibc's malloc opens another arena whenever threads contend for one (llvmpipe's JIT and
/// worker threads do, more so while other tests load the machine), and keeps it: RSS then
/// grows by tens of MiB over context cycles with no leak (docs/soak.md measured the same for
/// owned contexts). Two arenas keep the RSS check about Nimbus's memory.
fn run(program: &Path, args: &[&str]) -> String {
    let output = Command::new(program)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .env("MALLOC_ARENA_MAX", "2")
        .output()
        .unwrap_or_else(|e| panic!("run {}: {e}", program.display()));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!(
        "$ {} {}\n{stdout}{stderr}",
        program.display(),
        args.join(" ")
    );
    assert!(
        output.status.success(),
        "{} {} failed:\n{stdout}\n{stderr}",
        program.display(),
        args.join(" ")
    );
    assert!(
        !stderr.contains("panicked at"),
        "a panic message reached stderr:\n{stderr}"
    );
    stdout
}

fn number_after(text: &str, prefix: &str) -> Option<f64> {
    text.lines().find_map(|l| {
        let rest = &l[l.find(prefix)? + prefix.len()..];
        rest.split_whitespace().next()?.parse().ok()
    })
}

fn rgb8(path: &Path) -> (Vec<u8>, (u32, u32)) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let size = img.dimensions();
    (img.into_raw(), size)
}

/// FLIP mean of two sRGB PNGs of one size.
fn flip_mean(reference: &Path, test: &Path) -> f32 {
    let (r, size) = rgb8(reference);
    let (t, size_t) = rgb8(test);
    assert_eq!(size, size_t, "the two renders differ in size");
    let r = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &r);
    let t = nv_flip::FlipImageRgb8::with_data(size.0, size.1, &t);
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean()
}

#[test]
fn vulkan_host_composites_in_place_under_the_validation_layer() {
    setup();
    let out = build();
    let host = out.join("vulkan_host");
    let shot = |name: &str| out.join(name).display().to_string();
    let common = ["--size", "320x180", "--frames", "16", "--validation"];

    // Layout pair 0 (the render pass's layouts in, the blit source out), with timeline
    // semaphores both ways, the queue lock, and the occlusion check.
    let a = shot("layouts0.png");
    let mut args = common.to_vec();
    args.extend([
        "--layouts",
        "0",
        "--semaphores",
        "--lock",
        "--check-occluded",
    ]);
    args.extend(["--time-handoff", "--screenshot", &a]);
    let text = run(&host, &args);
    assert_eq!(
        number_after(&text, "validation messages:"),
        Some(0.0),
        "{text}"
    );
    let locks = number_after(&text, "queue lock calls:").expect("lock count printed");
    assert!(
        locks >= 16.0,
        "the queue lock was taken {locks} times for 16 frames"
    );

    // Two more entry / exit pairs; the last also creates and destroys the context 20 times on
    // one device (the layer reports objects left alive at vkDestroyDevice).
    for (pair, extra) in [("1", &[][..]), ("2", &["--recreate", "20"][..])] {
        let png = shot(&format!("layouts{pair}.png"));
        let mut args = common.to_vec();
        args.extend(["--layouts", pair, "--screenshot", &png]);
        args.extend(extra);
        let text = run(&host, &args);
        assert_eq!(
            number_after(&text, "validation messages:"),
            Some(0.0),
            "{text}"
        );
        let f = flip_mean(Path::new(&a), Path::new(&png));
        println!("layouts {pair} vs layouts 0: FLIP mean {f:.5}");
        assert!(
            f <= 0.01,
            "layout pair {pair} changed the picture: FLIP {f}"
        );
    }

    // The owned-device render of the same frames (NimbusTexture path).
    let owned = shot("owned.png");
    let mut args = common[..4].to_vec();
    args.extend(["--owned", "--screenshot", &owned]);
    run(&host, &args);
    let f = flip_mean(Path::new(&owned), Path::new(&a));
    println!("host device vs owned device: FLIP mean {f:.5}");
    assert!(
        f <= 0.01,
        "the host-device render differs from the owned one: FLIP {f}"
    );
}

#[test]
fn vulkan_bad_input_matrix() {
    setup();
    let out = build();
    let text = run(&out.join("vulkan_test"), &[]);
    let cases = number_after(&text, "vulkan_test:").expect("case count printed");
    assert!(cases >= 30.0, "only {cases} cases");
    assert!(text.contains(" 0 failures"), "{text}");
}
