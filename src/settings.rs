//! Quality and look settings: plain data, `Default` gives a good-looking fair-weather sky.
//!
//! Units: meters, radians, linear RGB. Every field documents its default.
//! [`Settings::validate`] refuses anything non-finite or out of range with the field's path.

use glam::Vec3;

use crate::error::Result;
use crate::lighting::phase::PhaseModel;
use crate::validate::{color, count, finite, in_range, invalid, non_negative, positive, pow2};
use crate::weather::preset::Weather;

/// Everything that defines how the clouds look and how they are rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Planet geometry and world orientation.
    pub planet: Planet,
    /// The weather at start (a built-in preset or one loaded from a file). Change it later with
    /// `Renderer::set_weather` for a smooth transition.
    pub weather: Weather,
    /// Sizes, seed and world scale of the baked noise.
    pub noise: NoiseSettings,
    /// Phase function, multiple scattering, light march.
    pub lighting: Lighting,
    /// Ray-march budget.
    pub march: March,
    /// Aerial-perspective haze that distant clouds fade into.
    pub haze: Haze,
    /// Replaces the noise model by an analytic medium (for checking the integrator).
    pub debug_density: DebugDensity,
    /// The cloud shadow map handed to the host (off by default).
    pub shadows: CloudShadows,
    /// How many texels of a requested weather's map `Renderer::set_weather` generates per
    /// frame. A map larger than this is generated in slices of whole rows, one per
    /// `prepare`, so that no single frame pays for the whole map (a 512² map costs about
    /// 0.2 s on a 2-core software rasteriser); the transition then starts once the map is
    /// ready, at the later of its requested start and that frame's time. A map that fits
    /// (or 0 = no limit) is generated at once in the request, which the transition then
    /// starts exactly at. Default 16384: a 512² map over 16 frames, a 128² one at once (a slice
    /// then costs about 3% of a default frame at 1280×720 on software Vulkan; at 32768 the worst
    /// frame of a request was 1.12× a normal one once the default level traced a half grid).
    pub weather_map_texels_per_frame: u32,
}

/// The cloud shadow map: the clouds' optical depth toward the sun over a square around the
/// default view's camera, for the host to darken its ground and objects. See
/// docs/cloud-shadows.md for what a texel holds and how to sample it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudShadows {
    /// Make and update the map. Default false (it costs a march per texel, amortised).
    pub enabled: bool,
    /// Side of the square (m), centered on the camera, in [1 km, 1000 km]. Default 40 km.
    pub extent: f32,
    /// Texels along each side, a power of two in [16, 2048]. Default 256 (156 m texels).
    pub resolution: u32,
    /// Density samples along each texel's ray through the medium, in [4, 256]. Default 32.
    pub steps: u32,
    /// Spread the refresh over this many frames (one slice of rows per frame), in [1, 16]:
    /// the map then costs 1/slices of a full update per frame and follows the wind and
    /// weather with that many frames' lag. Texels the camera's motion brings into the
    /// square, a sun that turned by more than 0.1°, and a settings change are updated at once.
    /// Default 4.
    pub update_slices: u32,
    /// Let the march read the long part of its light path toward the sun from the map (a
    /// "Beer shadow map" light march, as three-clouds does): `local_steps` light samples
    /// over the first `local_distance` meters resolve the self-shadowing next to the sample,
    /// the map gives the optical depth from there to the sun. Samples outside the map's
    /// square march the whole way. Needs `enabled`. Default false.
    pub march_light: bool,
    /// Length (m) of the light path marched sample by sample before the map takes over, in
    /// [10, 10000]. Default 1000: the map's linear ramp through a texel's clouds (its one
    /// approximation) then only has to stand for the light's far part.
    pub local_distance: f32,
    /// Light samples over `local_distance`, in [1, 32]. Default 4.
    pub local_steps: u32,
}

impl Default for CloudShadows {
    fn default() -> Self {
        Self {
            enabled: false,
            extent: 40_000.0,
            resolution: 256,
            steps: 32,
            update_slices: 4,
            march_light: false,
            local_distance: 1_000.0,
            local_steps: 4,
        }
    }
}

/// The planet: a sphere whose surface passes through the world origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planet {
    /// Planet radius in meters. Default 6 360 000 (Earth).
    pub radius: f32,
    /// World up direction (normalised on use). Default +Y. The planet center lies at
    /// `-up * radius`, so the world origin is on the ground at altitude 0.
    pub up: Vec3,
}

/// Sizes, seed and world scale of the baked noise (the same for every weather).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseSettings {
    /// Seed of the base and detail volumes and of the blue noise. Default 1.
    pub seed: u32,
    /// Edge of the base-shape volume (RGBA8), a power of two in [8, 256]. Default 128.
    pub base_size: u32,
    /// Edge of the detail volume (RGBA8), a power of two in [8, 128]. Default 32.
    pub detail_size: u32,
    /// Edge of the weather maps, a power of two in [16, 2048]. Default 512.
    pub weather_size: u32,
    /// Edge of the blue-noise jitter texture, a power of two in [8, 128]. Default 64.
    pub blue_noise_size: u32,
    /// Size in meters of one tile of the base-shape volume. Default 14 000.
    pub base_scale: f32,
    /// Size in meters of one tile of the detail volume. Default 900: its Worley cells (2, 4
    /// and 6 to a tile) are 450, 225 and 150 m, the size of a cumulus's turrets.
    pub detail_scale: f32,
    /// Size in meters of one (tileable) weather-map tile. Default 60 000.
    pub weather_extent: f32,
}

/// How the march estimates light scattered more than once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MultipleScatteringModel {
    /// Single scattering only (the sun's light scattered once; ambient still added).
    SingleOnly,
    /// Wrenninge 2015 octaves (the `octaves`, `attenuation`, `contribution`, `eccentricity`
    /// fields). Cheap, but cannot carry light deep into a cloud: thick media come out orders of
    /// magnitude too dark against the path tracer (docs/fidelity.md).
    Octaves,
    /// The default: a delta-Eddington diffuse field (Joseph, Wiscombe & Weinman 1976) of the
    /// local plane-parallel column (independent column approximation), from the optical depth
    /// toward the sun and the optical depth below the sample, with the forward peak of the phase
    /// folded into the direct beam. Carries light through thick clouds as the path tracer does
    /// and answers albedo; the octave fields are ignored.
    #[default]
    DeltaEddington,
}

/// Multiple scattering: the model, and Wrenninge 2015's octave parameters (octave i scatters
/// `b^i` as much light, through an optical depth scaled by `a^i`, with phase eccentricity scaled
/// by `c^i`) for [`MultipleScatteringModel::Octaves`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MultipleScattering {
    /// The model. Default [`MultipleScatteringModel::DeltaEddington`].
    pub model: MultipleScatteringModel,
    /// Number of octaves N in [1, 8]; 1 = single scattering only. Default 4.
    pub octaves: u32,
    /// Attenuation a in (0, 1]. Default 0.5.
    pub attenuation: f32,
    /// Contribution b in [0, 1]. Default 0.5.
    pub contribution: f32,
    /// Eccentricity c in [0, 1]. Default 0.5.
    pub eccentricity: f32,
}

/// Lighting model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Phase function. Default Jendersie & d'Eon HG + Draine for 10 µm droplets.
    pub phase: PhaseModel,
    /// Multiple-scattering approximation.
    pub multiple_scattering: MultipleScattering,
    /// Number of light-march samples toward the sun, in [1, 128]. Default 8.
    pub light_steps: u32,
    /// Length in meters the light march covers (clipped to the shell). Default 3 000.
    pub light_distance: f32,
    /// Each light step is this many times as long as the one before, in [1, 4] (1: uniform).
    /// Default 1.4: with 8 steps over 3 km the first is 87 m long and the last 920 m. Short
    /// first steps resolve the self-shadowing next to the sample, which dominates the look;
    /// against the converged reference 1.4 scored better than 1.6 on every benchmark scene
    /// at the same cost (docs/performance.md).
    pub light_step_growth: f32,
    /// Fewer, longer light steps far away: one step fewer per doubling of the distance beyond
    /// 5 km (at least 2), covering the same length. Default true.
    pub light_lod: bool,
}

/// Ray-march budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct March {
    /// Steps for the longest segment, in [4, 1024]. Default 96.
    pub max_steps: u32,
    /// Steps for the shortest segment, in [1, max_steps]. Default 48.
    pub min_steps: u32,
    /// Rays end this far from the camera, in meters (> 0). Default 120 000.
    pub max_distance: f32,
    /// The march stops once transmittance falls below this, in [0, 1). Default 0.003. What the
    /// rest of the ray would add is estimated as the last sample's medium continued without
    /// end (T S / σt), so stopping early costs little light; but seen from below, a thick
    /// cloud's source grows toward its sunlit top, and at 0.01 the estimate left the stormy
    /// deck's FLIP at 0.052 against the benchmark's converged reference (0.047-0.049 at 0.003,
    /// for 2-5 ms more a frame on llvmpipe at 1280x720; docs/performance.md).
    pub transmittance_cutoff: f32,
    /// Blue-noise jitter of the ray start (against banding). Default true.
    pub jitter: bool,
    /// Resolution the clouds are traced at; the composite upsamples depth-aware.
    /// Default half (one ray per 2×2 output pixels): on software Vulkan a third of the full
    /// grid's frame for +0.001-0.005 FLIP against the converged reference (docs/performance.md).
    pub resolution: TraceResolution,
    /// Temporal reprojection: trace a subset of pixels each frame and accumulate the rest
    /// from reprojected history. Default on, one pixel in 16.
    pub temporal: Temporal,
    /// Coarse-then-fine stepping: long steps with the cheap (base-shape) density until a
    /// cloud is found, then a step back and fine steps until the ray has left it. Default true.
    pub coarse_then_fine: bool,
    /// Steps grow with distance on long (horizon) paths; off, steps are uniform along the
    /// path. Default true.
    pub distance_steps: bool,
    /// Noise mip level chosen by the ray's pixel footprint (and the light step's length), so
    /// distant clouds read prefiltered noise. Default true.
    pub noise_lod: bool,
}

/// Temporal reprojection and accumulation of the cloud image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Temporal {
    /// Accumulate over frames through the previous view-projection and the cloud depth.
    /// Default true. Off, `pattern` must be [`TracePattern::Every`].
    pub enabled: bool,
    /// Which pixels of the trace grid get a new ray each frame. Default one in 16.
    pub pattern: TracePattern,
    /// Most samples a pixel's history averages, in [1, 64]: more is smoother, fewer follows
    /// changes (moving sun, weather) faster. Default 4.
    pub max_samples: u32,
}

/// Which pixels of the trace grid are traced in a frame. The order is a Bayer matrix, so
/// consecutive frames fill the block evenly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TracePattern {
    /// Every pixel, every frame.
    Every,
    /// One pixel of each 2×2 block per frame (all of them in 4 frames).
    OneIn4,
    /// One pixel of each 4×4 block per frame (all of them in 16 frames).
    #[default]
    OneIn16,
}

impl TracePattern {
    /// Edge of the block one traced pixel stands for (1, 2 or 4).
    pub fn block(self) -> u32 {
        match self {
            TracePattern::Every => 1,
            TracePattern::OneIn4 => 2,
            TracePattern::OneIn16 => 4,
        }
    }

    /// Position inside the block traced at `frame` (Bayer order).
    pub fn offset(self, frame: u32) -> (u32, u32) {
        const BAYER2: [(u32, u32); 4] = [(0, 0), (1, 1), (1, 0), (0, 1)];
        const BAYER4: [(u32, u32); 16] = [
            (0, 0),
            (2, 2),
            (2, 0),
            (0, 2),
            (1, 1),
            (3, 3),
            (3, 1),
            (1, 3),
            (1, 0),
            (3, 2),
            (3, 0),
            (1, 2),
            (0, 1),
            (2, 3),
            (2, 1),
            (0, 3),
        ];
        match self {
            TracePattern::Every => (0, 0),
            TracePattern::OneIn4 => BAYER2[(frame % 4) as usize],
            TracePattern::OneIn16 => BAYER4[(frame % 16) as usize],
        }
    }
}

impl Default for Temporal {
    fn default() -> Self {
        Self {
            enabled: true,
            pattern: TracePattern::OneIn16,
            max_samples: 4,
        }
    }
}

impl Temporal {
    /// No reprojection: every pixel traced every frame, nothing kept between frames.
    pub const OFF: Temporal = Temporal {
        enabled: false,
        pattern: TracePattern::Every,
        max_samples: 1,
    };
}

/// Resolution of the cloud march relative to the output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TraceResolution {
    /// One ray per output pixel.
    #[default]
    Full,
    /// One ray per 2×2 output pixels.
    Half,
    /// One ray per 4×4 output pixels.
    Quarter,
}

impl TraceResolution {
    /// Output pixels per traced pixel along each axis.
    pub fn divisor(self) -> u32 {
        match self {
            TraceResolution::Full => 1,
            TraceResolution::Half => 2,
            TraceResolution::Quarter => 4,
        }
    }
}

/// Quality levels: what each trades is written next to it; `docs/performance.md` has their
/// measured cost and error. `Settings::default()` is [`Quality::Medium`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// Quarter-resolution grid (one ray per 4×4 output pixels), one pixel in 16 traced per
    /// frame, 48-96 march steps, 8 light steps (growth 1.4); every optimisation on. The
    /// default's march on a coarser grid: on software Vulkan half its frame for +0.003 to
    /// +0.005 FLIP on most scenes (docs/performance.md).
    Low,
    /// Half-resolution grid, one pixel in 16 traced per frame, 48-96 march steps, 8 light
    /// steps (growth 1.4); every optimisation on. The default.
    Medium,
    /// Full-resolution grid, one pixel in 4 traced per frame, 64-128 march steps, 10 light
    /// steps (growth 1.5); every optimisation on.
    High,
    /// The unoptimised march: every pixel every frame at full resolution, 64-128 steps
    /// uniform along the path, 12 light steps (growth 1.4), no temporal reuse, no coarse
    /// stepping, no LOD, no early exit at low transmittance (the others stop at 0.003).
    Ultra,
}

impl Quality {
    /// All levels, cheapest first.
    pub const ALL: [Quality; 4] = [Quality::Low, Quality::Medium, Quality::High, Quality::Ultra];

    /// Sets the march budget, light steps, trace resolution, temporal pattern and the
    /// optimisation switches of `settings`.
    pub fn apply(self, settings: &mut Settings) {
        use TracePattern as P;
        use TraceResolution as R;
        let (resolution, pattern, min, max, light, growth) = match self {
            Quality::Low => (R::Quarter, P::OneIn16, 48, 96, 8, 1.4),
            Quality::Medium => (R::Half, P::OneIn16, 48, 96, 8, 1.4),
            Quality::High => (R::Full, P::OneIn4, 64, 128, 10, 1.5),
            Quality::Ultra => (R::Full, P::Every, 64, 128, 12, 1.4),
        };
        let optimised = self != Quality::Ultra;
        let m = &mut settings.march;
        m.resolution = resolution;
        m.min_steps = min;
        m.max_steps = max;
        m.temporal = if optimised {
            Temporal {
                enabled: true,
                pattern,
                ..Temporal::default()
            }
        } else {
            Temporal::OFF
        };
        m.coarse_then_fine = optimised;
        m.distance_steps = optimised;
        m.noise_lod = optimised;
        // The unoptimised march goes on to the end of the medium: stopping at T = 0.01 with no
        // estimate of what lies beyond dropped two thirds of a thick slab's single scattering
        // (its deep, sunward part is the brightest). The other levels keep the early exit, at
        // T = 0.003 (see `March::transmittance_cutoff`).
        m.transmittance_cutoff = if optimised { 0.003 } else { 0.0 };
        settings.lighting.light_steps = light;
        settings.lighting.light_step_growth = growth;
        settings.lighting.light_lod = optimised;
    }
}

/// Distant clouds fade into a haze color (aerial perspective).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Haze {
    /// Radiance of the haze (linear RGB). Default a pale sky blue.
    pub color: Vec3,
    /// Distance in meters at which the fade starts (>= 0). Default 15 000.
    pub start_distance: f32,
    /// e-folding distance of the fade beyond the start, meters; `f32::INFINITY` disables
    /// the haze. Default 40 000.
    pub fade_distance: f32,
}

/// Analytic media replacing the noise model, so the integrator can be checked against
/// closed-form or path-traced references. Densities multiply `clouds.extinction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DebugDensity {
    /// Normal rendering with the procedural noise model.
    Off,
    /// A homogeneous spherical slab between two altitudes.
    Slab {
        /// Bottom altitude in meters.
        bottom_altitude: f32,
        /// Top altitude in meters.
        top_altitude: f32,
        /// Density (σt = density × extinction).
        density: f32,
    },
    /// A homogeneous sphere.
    Sphere {
        /// World-space center in meters.
        center: Vec3,
        /// Radius in meters.
        radius: f32,
        /// Density (σt = density × extinction).
        density: f32,
    },
}

impl Default for Planet {
    fn default() -> Self {
        Self {
            radius: 6_360_000.0,
            up: Vec3::Y,
        }
    }
}

impl Default for NoiseSettings {
    fn default() -> Self {
        Self {
            seed: 1,
            base_size: 128,
            detail_size: 32,
            weather_size: 512,
            blue_noise_size: 64,
            base_scale: 14_000.0,
            detail_scale: 900.0,
            weather_extent: 60_000.0,
        }
    }
}

impl Default for MultipleScattering {
    fn default() -> Self {
        Self {
            model: MultipleScatteringModel::default(),
            octaves: 4,
            attenuation: 0.5,
            contribution: 0.5,
            eccentricity: 0.5,
        }
    }
}

impl Default for Lighting {
    fn default() -> Self {
        Self {
            phase: PhaseModel::default(),
            multiple_scattering: MultipleScattering::default(),
            light_steps: 8,
            light_distance: 3_000.0,
            light_step_growth: 1.4,
            light_lod: true,
        }
    }
}

impl Default for March {
    fn default() -> Self {
        Self {
            max_steps: 96,
            min_steps: 48,
            max_distance: 120_000.0,
            transmittance_cutoff: 0.003,
            jitter: true,
            resolution: TraceResolution::Half,
            temporal: Temporal::default(),
            coarse_then_fine: true,
            distance_steps: true,
            noise_lod: true,
        }
    }
}

impl Default for Haze {
    fn default() -> Self {
        Self {
            color: Vec3::new(0.62, 0.72, 0.88) * 0.5,
            start_distance: 15_000.0,
            fade_distance: 40_000.0,
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            planet: Planet::default(),
            weather: Weather::default(),
            noise: NoiseSettings::default(),
            lighting: Lighting::default(),
            march: March::default(),
            haze: Haze::default(),
            debug_density: DebugDensity::Off,
            shadows: CloudShadows::default(),
            weather_map_texels_per_frame: 16_384,
        }
    }
}

/// Shortest first light step accepted (m): below it the first sample sees no self-shadowing.
const MIN_FIRST_LIGHT_STEP: f32 = 0.01;

/// The light march's geometric partition, checked in f32 as the shader computes it: n steps
/// growing by `growth` sum to `distance`, so the first is distance (r - 1) / (r^n - 1). Each
/// field can be in range while the pair is not: 128 steps growing by 2 overflow r^n, the first
/// step becomes 0 m and the clouds render fully sunlit.
fn light_partition(steps: u32, growth: f32, distance: f32) -> Result<()> {
    // The shader's rule: uniform steps up to a growth of 1.0001 (found by fuzzing: a tiny
    // light distance made even those 0 m long).
    let (total, first) = if growth <= 1.0001 {
        (1.0, distance / steps as f32)
    } else {
        let total = growth.powf(steps as f32);
        (total, distance * (growth - 1.0) / (total - 1.0))
    };
    if total.is_finite() && first >= MIN_FIRST_LIGHT_STEP {
        return Ok(());
    }
    Err(invalid(
        "lighting.light_step_growth",
        format!(
            "{} with lighting.light_steps {steps} over lighting.light_distance {} m makes the \
             first light step {} m (at least {MIN_FIRST_LIGHT_STEP} m is needed{}): change the \
             growth, the step count or the distance",
            crate::validate::num(growth),
            crate::validate::num(distance),
            if total.is_finite() {
                crate::validate::num(first)
            } else {
                "0".into()
            },
            if total.is_finite() {
                ""
            } else {
                "; growth^steps overflows f32"
            }
        ),
    ))
}

/// The largest planet radius the shaders represent: their ray-sphere roots square terms of
/// the order of the radius in f32 (which overflows near 1.8e19 m, rendering nothing), and
/// the cloud shell's altitudes must stay resolved. Tested at this value (tests/gpu.rs).
pub const MAX_PLANET_RADIUS: f32 = 1.0e12;

impl Settings {
    /// Checks every field and the combinations that interact (the light-step partition);
    /// the error names the first offending field.
    pub fn validate(&self) -> Result<()> {
        positive("planet.radius", self.planet.radius)?;
        if self.planet.radius > MAX_PLANET_RADIUS {
            return Err(invalid(
                "planet.radius",
                format!(
                    "{} m is beyond what the shaders' f32 shell geometry represents (at most \
                     {MAX_PLANET_RADIUS:e} m; a larger world is flat to within a millimetre \
                     over 100 km)",
                    crate::validate::num(self.planet.radius)
                ),
            ));
        }
        if !self.planet.up.is_finite() || self.planet.up.length() < 1e-6 {
            return Err(invalid(
                "planet.up",
                format!("must be a finite non-zero vector, got {}", self.planet.up),
            ));
        }
        self.weather.validate().map_err(|e| match e {
            crate::Error::InvalidSettings { field, reason } => {
                invalid(format!("weather.{field}"), reason)
            }
            other => other,
        })?;
        let n = &self.noise;
        pow2("noise.base_size", n.base_size, 8, 256)?;
        pow2("noise.detail_size", n.detail_size, 8, 128)?;
        pow2("noise.weather_size", n.weather_size, 16, 2048)?;
        pow2("noise.blue_noise_size", n.blue_noise_size, 8, 128)?;
        positive("noise.base_scale", n.base_scale)?;
        positive("noise.detail_scale", n.detail_scale)?;
        positive("noise.weather_extent", n.weather_extent)?;
        let l = &self.lighting;
        l.phase.validate()?;
        let ms = &l.multiple_scattering;
        count("lighting.multiple_scattering.octaves", ms.octaves, 1, 8)?;
        in_range(
            "lighting.multiple_scattering.attenuation",
            ms.attenuation,
            1e-3,
            1.0,
        )?;
        in_range(
            "lighting.multiple_scattering.contribution",
            ms.contribution,
            0.0,
            1.0,
        )?;
        in_range(
            "lighting.multiple_scattering.eccentricity",
            ms.eccentricity,
            0.0,
            1.0,
        )?;
        count("lighting.light_steps", l.light_steps, 1, 128)?;
        positive("lighting.light_distance", l.light_distance)?;
        in_range("lighting.light_step_growth", l.light_step_growth, 1.0, 4.0)?;
        light_partition(l.light_steps, l.light_step_growth, l.light_distance)?;
        let m = &self.march;
        count("march.max_steps", m.max_steps, 4, 1024)?;
        count("march.min_steps", m.min_steps, 1, m.max_steps)?;
        positive("march.max_distance", m.max_distance)?;
        in_range(
            "march.transmittance_cutoff",
            m.transmittance_cutoff,
            0.0,
            0.999,
        )?;
        count("march.temporal.max_samples", m.temporal.max_samples, 1, 64)?;
        if !m.temporal.enabled && m.temporal.pattern != TracePattern::Every {
            return Err(invalid(
                "march.temporal.pattern",
                "traces a subset of pixels, which needs march.temporal.enabled",
            ));
        }
        let h = &self.haze;
        color("haze.color", h.color)?;
        non_negative("haze.start_distance", h.start_distance)?;
        if h.fade_distance.is_nan() || h.fade_distance <= 0.0 {
            return Err(invalid(
                "haze.fade_distance",
                format!("must be > 0 (or infinity), got {}", h.fade_distance),
            ));
        }
        match self.debug_density {
            DebugDensity::Off => {}
            DebugDensity::Slab {
                bottom_altitude,
                top_altitude,
                density,
            } => {
                finite("debug_density.bottom_altitude", bottom_altitude)?;
                finite("debug_density.top_altitude", top_altitude)?;
                if bottom_altitude >= top_altitude {
                    return Err(invalid(
                        "debug_density.bottom_altitude",
                        "must be below debug_density.top_altitude",
                    ));
                }
                non_negative("debug_density.density", density)?;
            }
            DebugDensity::Sphere {
                center,
                radius,
                density,
            } => {
                if !center.is_finite() {
                    return Err(invalid("debug_density.center", "must be finite"));
                }
                positive("debug_density.radius", radius)?;
                non_negative("debug_density.density", density)?;
            }
        }
        let sh = &self.shadows;
        in_range("shadows.extent", sh.extent, 1_000.0, 1_000_000.0)?;
        pow2("shadows.resolution", sh.resolution, 16, 2048)?;
        count("shadows.steps", sh.steps, 4, 256)?;
        count("shadows.update_slices", sh.update_slices, 1, 16)?;
        in_range("shadows.local_distance", sh.local_distance, 10.0, 10_000.0)?;
        count("shadows.local_steps", sh.local_steps, 1, 32)?;
        if sh.march_light && !sh.enabled {
            return Err(invalid(
                "shadows.march_light",
                "needs shadows.enabled: the march reads its light from the map",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn refused(s: &Settings) -> String {
        match s.validate() {
            Err(Error::InvalidSettings { field, .. }) => field,
            other => panic!("expected InvalidSettings, got {other:?}"),
        }
    }

    #[test]
    fn defaults_are_valid() {
        Settings::default().validate().unwrap();
    }

    #[test]
    fn shadow_map_ranges_are_checked() {
        type Break = fn(&mut CloudShadows);
        let cases: [(&str, Break); 8] = [
            ("shadows.extent", |c| c.extent = f32::NAN),
            ("shadows.extent", |c| c.extent = 10.0),
            ("shadows.resolution", |c| c.resolution = 300),
            ("shadows.steps", |c| c.steps = 0),
            ("shadows.update_slices", |c| c.update_slices = 17),
            ("shadows.local_distance", |c| c.local_distance = 5.0),
            ("shadows.local_steps", |c| c.local_steps = 0),
            ("shadows.march_light", |c| {
                c.enabled = false;
                c.march_light = true
            }),
        ];
        for (field, break_it) in cases {
            let mut s = Settings::default();
            s.shadows.enabled = true;
            break_it(&mut s.shadows);
            assert_eq!(refused(&s), field);
        }
    }

    #[test]
    fn bottom_above_top_is_refused() {
        let mut s = Settings::default();
        s.weather.layer.bottom_altitude = 5_000.0;
        assert_eq!(refused(&s), "weather.layer.bottom_altitude");
        let msg = s.validate().unwrap_err().to_string();
        assert!(msg.contains("top_altitude"), "{msg}");
    }

    #[test]
    fn negative_and_nan_values_are_refused() {
        let mut s = Settings::default();
        s.planet.radius = -1.0;
        assert_eq!(refused(&s), "planet.radius");
        s.planet.radius = f32::NAN;
        assert_eq!(refused(&s), "planet.radius");
        s.planet.radius = 2.0e19;
        assert_eq!(refused(&s), "planet.radius");
        s.planet.radius = MAX_PLANET_RADIUS * 1.01;
        assert_eq!(refused(&s), "planet.radius");
        s.planet.radius = MAX_PLANET_RADIUS;
        assert!(s.validate().is_ok());
        let mut s = Settings::default();
        s.weather.clouds.density = -0.5;
        assert_eq!(refused(&s), "weather.clouds.density");
        s.weather.clouds.density = f32::NAN;
        assert_eq!(refused(&s), "weather.clouds.density");
        let mut s = Settings::default();
        s.weather.clouds.extinction = f32::INFINITY;
        assert_eq!(refused(&s), "weather.clouds.extinction");
        let s = Settings {
            debug_density: DebugDensity::Sphere {
                center: Vec3::ZERO,
                radius: f32::NAN,
                density: 1.0,
            },
            ..Settings::default()
        };
        assert_eq!(refused(&s), "debug_density.radius");
    }

    #[test]
    fn default_is_the_medium_level() {
        let mut s = Settings::default();
        Quality::Medium.apply(&mut s);
        assert_eq!(s, Settings::default());
    }

    #[test]
    fn trace_patterns_visit_every_pixel_of_a_block_once() {
        for p in [
            TracePattern::Every,
            TracePattern::OneIn4,
            TracePattern::OneIn16,
        ] {
            let b = p.block();
            let mut seen = vec![0; (b * b) as usize];
            for f in 0..b * b {
                let (x, y) = p.offset(f);
                seen[(y * b + x) as usize] += 1;
                assert_eq!(p.offset(f + b * b), (x, y), "period is the block size");
            }
            assert!(seen.iter().all(|&n| n == 1), "{p:?}: {seen:?}");
        }
    }

    #[test]
    fn sparse_tracing_needs_temporal() {
        let mut s = Settings::default();
        s.march.temporal.enabled = false;
        assert_eq!(refused(&s), "march.temporal.pattern");
        s.march.temporal = Temporal::OFF;
        s.validate().unwrap();
        s.march.temporal.max_samples = 0;
        assert_eq!(refused(&s), "march.temporal.max_samples");
    }

    #[test]
    fn light_step_growth_is_range_checked() {
        for bad in [0.5, 4.5, f32::NAN] {
            let mut s = Settings::default();
            s.lighting.light_step_growth = bad;
            assert_eq!(refused(&s), "lighting.light_step_growth");
        }
        let mut s = Settings::default();
        s.lighting.light_step_growth = 1.0; // uniform steps are allowed
        s.validate().unwrap();
        s.lighting.light_steps = 129;
        assert_eq!(refused(&s), "lighting.light_steps");
    }

    #[test]
    fn light_steps_and_growth_are_checked_together() {
        // Each in range, the pair not: 2^128 overflows f32 and the first step becomes 0 m.
        let mut s = Settings::default();
        s.lighting.light_steps = 128;
        s.lighting.light_step_growth = 2.0;
        assert_eq!(refused(&s), "lighting.light_step_growth");
        let message = s.validate().unwrap_err().to_string();
        assert!(message.contains("overflows"), "{message}");
        // Finite but uselessly short first steps are refused too.
        s.lighting.light_steps = 40;
        assert_eq!(refused(&s), "lighting.light_step_growth");
        // Uniform steps too: a light distance this short leaves no step worth the name
        // (the fuzzer's find: 1e-30 m over 8 steps was 0 m per step in f32).
        let mut tiny = Settings::default();
        tiny.lighting.light_step_growth = 1.0;
        tiny.lighting.light_distance = 1e-30;
        assert_eq!(refused(&tiny), "lighting.light_step_growth");
        // Every quality level's own light march passes.
        for q in [Quality::Low, Quality::Medium, Quality::High, Quality::Ultra] {
            let mut s = Settings::default();
            q.apply(&mut s);
            s.validate().unwrap();
        }
        s.lighting.light_steps = 16;
        s.validate().unwrap();
    }

    #[test]
    fn sizes_must_be_powers_of_two() {
        let mut s = Settings::default();
        s.noise.base_size = 100;
        assert_eq!(refused(&s), "noise.base_size");
        let mut s = Settings::default();
        s.march.min_steps = 200;
        assert_eq!(refused(&s), "march.min_steps");
    }
}
