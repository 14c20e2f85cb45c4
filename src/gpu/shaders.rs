//! WGSL sources. WGSL has no imports, so each pass is the concatenation of shared modules and
//! its own file; `PASSES` is the one list of what goes into what.

/// A scene-depth binding variant of the march pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum DepthKind {
    /// A depth-format texture (`texture_depth_2d`), or no depth at all (a dummy is bound).
    Depth,
    /// An `R32Float` color texture holding depth values.
    R32Float,
}

macro_rules! shader {
    ($name:literal) => {
        ($name, include_str!(concat!("../../shaders/", $name)))
    };
}

pub(crate) const COMMON: (&str, &str) = shader!("common.wgsl");
pub(crate) const DEPTH: (&str, &str) = shader!("depth.wgsl");
pub(crate) const NOISE: (&str, &str) = shader!("noise.wgsl");
pub(crate) const ATMOSPHERE: (&str, &str) = shader!("atmosphere.wgsl");
pub(crate) const PHASE: (&str, &str) = shader!("phase.wgsl");
pub(crate) const DENSITY: (&str, &str) = shader!("density.wgsl");
pub(crate) const NOISE_BAKE: (&str, &str) = shader!("noise_bake.wgsl");
pub(crate) const WEATHER_BAKE: (&str, &str) = shader!("weather_bake.wgsl");
pub(crate) const WEATHER_BLEND: (&str, &str) = shader!("weather_blend.wgsl");
pub(crate) const MIP_DOWNSAMPLE: (&str, &str) = shader!("mip_downsample.wgsl");
pub(crate) const MEDIUM: (&str, &str) = shader!("medium.wgsl");
pub(crate) const DIFFUSION: (&str, &str) = shader!("diffusion.wgsl");
pub(crate) const MARCH_RAY: (&str, &str) = shader!("march_ray.wgsl");
pub(crate) const MARCH: (&str, &str) = shader!("march.wgsl");
pub(crate) const AMBIENT: (&str, &str) = shader!("ambient.wgsl");
pub(crate) const SHADOW: (&str, &str) = shader!("shadow.wgsl");
pub(crate) const DENSITY_PROBE: (&str, &str) = shader!("density_probe.wgsl");
pub(crate) const PATH_TRACE: (&str, &str) = shader!("path_trace.wgsl");
pub(crate) const TEMPORAL: (&str, &str) = shader!("temporal.wgsl");
pub(crate) const COMPOSITE: (&str, &str) = shader!("composite.wgsl");
pub(crate) const COMPOSITE_SEPARATE: (&str, &str) = shader!("composite_separate.wgsl");
pub(crate) const COMPOSITE_COMPUTE: (&str, &str) = shader!("composite_compute.wgsl");

/// The noise bake's modules: also what a noise cache's bake id hashes (`crate::noise_cache`).
pub(crate) const NOISE_BAKE_MODULES: &[(&str, &str)] = &[COMMON, NOISE, NOISE_BAKE];

/// The passes and the modules each is built from, in order.
pub(crate) const PASSES: &[(&str, &[(&str, &str)])] = &[
    ("noise_bake", NOISE_BAKE_MODULES),
    ("weather_bake", &[COMMON, NOISE, WEATHER_BAKE]),
    ("weather_blend", &[WEATHER_BLEND]),
    ("mip_downsample", &[MIP_DOWNSAMPLE]),
    (
        "march",
        &[
            COMMON, DEPTH, ATMOSPHERE, PHASE, DENSITY, MEDIUM, DIFFUSION, MARCH_RAY, MARCH,
        ],
    ),
    (
        "ambient",
        &[
            COMMON, ATMOSPHERE, PHASE, DENSITY, MEDIUM, DIFFUSION, MARCH_RAY, AMBIENT,
        ],
    ),
    ("shadow", &[COMMON, ATMOSPHERE, DENSITY, MEDIUM, SHADOW]),
    (
        "density_probe",
        &[COMMON, ATMOSPHERE, DENSITY, MEDIUM, DENSITY_PROBE],
    ),
    (
        "path_trace",
        &[
            COMMON, DEPTH, ATMOSPHERE, PHASE, DENSITY, MEDIUM, PATH_TRACE,
        ],
    ),
    ("temporal", &[DEPTH, TEMPORAL]),
    ("composite_in_place", &[DEPTH, COMPOSITE]),
    (
        "composite_separate",
        &[DEPTH, COMPOSITE, COMPOSITE_SEPARATE],
    ),
    ("composite_compute", &[DEPTH, COMPOSITE, COMPOSITE_COMPUTE]),
];

const DEPTH_PLACEHOLDER: &str = "//!SCENE_DEPTH_BINDING(";
const OUTPUT_PLACEHOLDER: &str = "//!OUTPUT_STORAGE_BINDING(";

/// The scene-depth binding (at `binding`) and its loader for a depth kind.
fn depth_binding(kind: DepthKind, binding: &str) -> String {
    match kind {
        DepthKind::Depth => format!(
            "@group(0) @binding({binding}) var scene_depth: texture_depth_2d;\n\
             fn load_scene_depth(c: vec2u) -> f32 {{ return textureLoad(scene_depth, c + vec2u(scene_viewport().xy), 0); }}"
        ),
        DepthKind::R32Float => format!(
            "@group(0) @binding({binding}) var scene_depth: texture_2d<f32>;\n\
             fn load_scene_depth(c: vec2u) -> f32 {{ return textureLoad(scene_depth, c + vec2u(scene_viewport().xy), 0).r; }}"
        ),
    }
}

/// Output formats a compute pass can write (`texture_storage_2d` with write access in every
/// wgpu backend), with their WGSL names.
pub(crate) const STORAGE_OUTPUT_FORMATS: [(wgpu::TextureFormat, &str); 3] = [
    (wgpu::TextureFormat::Rgba8Unorm, "rgba8unorm"),
    (wgpu::TextureFormat::Rgba16Float, "rgba16float"),
    (wgpu::TextureFormat::Rgba32Float, "rgba32float"),
];

/// The modules `pass` is built from, in order (its entry in `PASSES`).
pub(crate) fn pass_modules(pass: &str) -> &'static [(&'static str, &'static str)] {
    PASSES
        .iter()
        .find(|(name, _)| *name == pass)
        .map(|(_, m)| *m)
        .unwrap_or_else(|| unreachable!("unknown pass {pass}"))
}

/// The full source of a pass, its scene-depth placeholder (`//!SCENE_DEPTH_BINDING(n)`)
/// replaced by the binding variant for `depth`.
pub(crate) fn pass_source(pass: &str, depth: DepthKind) -> String {
    let modules = pass_modules(pass);
    let mut src = String::new();
    for (name, text) in modules {
        src.push_str(&format!("// ---- {name}\n"));
        src.push_str(text);
        src.push('\n');
    }
    replace_placeholders(&mut src, DEPTH_PLACEHOLDER, |binding| {
        depth_binding(depth, binding)
    });
    src
}

/// The source of a pass that writes a storage texture (`//!OUTPUT_STORAGE_BINDING(n)`), its
/// output declared in `storage_format` (a WGSL texel format such as `rgba16float`).
pub(crate) fn pass_source_with_output(
    pass: &str,
    depth: DepthKind,
    storage_format: &str,
) -> String {
    let mut src = pass_source(pass, depth);
    replace_placeholders(&mut src, OUTPUT_PLACEHOLDER, |binding| {
        format!(
            "@group(0) @binding({binding}) var output: texture_storage_2d<{storage_format}, write>;"
        )
    });
    src
}

/// Replaces each `placeholder` + `n)` in `src` by `declare(n)`.
fn replace_placeholders(src: &mut String, placeholder: &str, declare: impl Fn(&str) -> String) {
    while let Some(at) = src.find(placeholder) {
        let rest = &src[at + placeholder.len()..];
        let close = rest
            .find(')')
            .unwrap_or_else(|| unreachable!("placeholder without `)`"));
        let binding = rest[..close].to_string();
        let end = at + placeholder.len() + close + 1;
        src.replace_range(at..end, &declare(&binding));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn validate(label: &str, src: &str) {
        let module = naga::front::wgsl::parse_str(src)
            .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(src)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(src)));
    }

    #[test]
    fn every_pass_parses_and_validates() {
        for (pass, _) in PASSES {
            for kind in [DepthKind::Depth, DepthKind::R32Float] {
                for format in STORAGE_OUTPUT_FORMATS.map(|(_, name)| name) {
                    validate(pass, &pass_source_with_output(pass, kind, format));
                }
            }
        }
    }

    #[test]
    fn every_wgsl_file_belongs_to_a_validated_pass() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders");
        for entry in std::fs::read_dir(dir).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if !name.ends_with(".wgsl") {
                continue;
            }
            let used = PASSES
                .iter()
                .any(|(_, modules)| modules.iter().any(|(m, _)| *m == name));
            assert!(
                used,
                "{name} is in shaders/ but in no pass, so nothing validates it"
            );
        }
    }

    #[test]
    fn self_contained_modules_validate_alone() {
        for (name, src) in [COMMON, DEPTH, MIP_DOWNSAMPLE, WEATHER_BLEND] {
            validate(name, src);
        }
    }
}
