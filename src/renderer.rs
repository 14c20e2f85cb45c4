//! [`Renderer`]: the one entry point for Rust hosts that own a wgpu device.
//!
//! `new` bakes the noise and builds the march pipelines; `prepare` validates and stores the
//! frame inputs; `encode` validates the targets and records the march and composite passes into
//! the host's encoder, submitting nothing (the glyphon / vello shape).

use wgpu::TextureFormat as F;

use crate::device::gpu_scope;
use crate::error::{invalid_target, Error, Result};
use crate::frame::FrameInputs;
use crate::gpu::ambient::AmbientPipeline;
use crate::gpu::composite::{CompositeCache, CompositeInputs, CompositeUniforms};
use crate::gpu::march::{MarchPipeline, MarchUniforms, MarchVariant};
use crate::gpu::noise::{NoiseTextures, NoiseVolume};
use crate::gpu::shaders::DepthKind;
use crate::gpu::shadow::{NoShadow, ShadowFrame, ShadowPass};
use crate::gpu::temporal::{ResolveFrame, TemporalPipeline, TemporalUniforms};
use crate::gpu::timing::{GpuTimer, PassTimes};
use crate::gpu::weather::WeatherMaps;
use crate::noise_cache::volumes_for;
use crate::settings::Settings;
use crate::view::{Pending, ViewId, ViewState, Views};
use crate::weather::{Timeline, Weather, WeatherSample};

/// Output formats the composite can render to (blendable ones also work in place).
pub const OUTPUT_FORMATS: &[wgpu::TextureFormat] = &[
    F::Rgba8Unorm,
    F::Rgba8UnormSrgb,
    F::Bgra8Unorm,
    F::Bgra8UnormSrgb,
    F::Rgb10a2Unorm,
    F::Rg11b10Ufloat,
    F::Rgba16Float,
    F::Rgba32Float,
];
const OUTPUT_NAMES: &str =
    "Rgba8Unorm(Srgb), Bgra8Unorm(Srgb), Rgb10a2Unorm, Rg11b10Ufloat (needs Features::RG11B10UFLOAT_RENDERABLE), Rgba16Float, Rgba32Float (not in place)";

/// Scene-depth formats: depth formats, or `R32Float` holding clip-space depth.
pub const DEPTH_FORMATS: &[wgpu::TextureFormat] = &[
    F::Depth32Float,
    F::Depth24Plus,
    F::Depth24PlusStencil8,
    F::Depth16Unorm,
    F::Depth32FloatStencil8,
    F::R32Float,
];
const DEPTH_NAMES: &str =
    "Depth32Float, Depth24Plus, Depth24PlusStencil8 (depth-only view), Depth16Unorm, Depth32FloatStencil8, R32Float";

/// Where the scene color comes from and where the result goes.
#[derive(Clone, Copy, Debug)]
pub enum ColorTargets<'a> {
    /// Composite onto the scene color itself: it needs `RENDER_ATTACHMENT` usage and a
    /// blendable format.
    InPlace(&'a wgpu::TextureView),
    /// Read the scene color (`TEXTURE_BINDING`) and write `out = scene * T + L` to a separate
    /// output of the same size: `RENDER_ATTACHMENT` (a fullscreen triangle), or
    /// `STORAGE_BINDING` in `Rgba8Unorm`, `Rgba16Float` or `Rgba32Float` (a compute pass,
    /// chosen whenever the output allows it: much faster on compute-oriented GPUs). An output
    /// texture with `STORAGE_BINDING` must be viewed in its own format (a storage binding
    /// cannot reinterpret it, e.g. as sRGB; wgpu's refusal comes back as `Error::Gpu`).
    Separate {
        /// The host's rendered scene.
        scene: &'a wgpu::TextureView,
        /// Where the composited image goes.
        output: &'a wgpu::TextureView,
    },
}

/// The textures of one frame. Views must cover mip 0 of a 2D texture; all must have one size.
#[derive(Clone, Copy, Debug)]
pub struct Targets<'a> {
    /// Scene color and output.
    pub color: ColorTargets<'a>,
    /// Scene depth (`TEXTURE_BINDING`), in the camera's [`crate::DepthConvention`]. `None`
    /// means nothing occludes the clouds.
    pub depth: Option<&'a wgpu::TextureView>,
    /// The rectangle of the targets to render (split screen, dynamic resolution); `None`: all
    /// of them. The camera's projection maps onto this rectangle, and pixels outside it are
    /// left untouched. A change of its size starts the history afresh; moving it keeps it.
    pub viewport: Option<Viewport>,
}

/// A rectangle of the targets, in pixels from their top-left corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Width (at least 1).
    pub width: u32,
    /// Height (at least 1).
    pub height: u32,
}

pub(crate) use crate::view::TraceLayout;

/// Renders volumetric clouds with the host's wgpu device.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    settings: Settings,
    noise: NoiseTextures,
    weather_maps: WeatherMaps,
    timeline: Timeline,
    last_time: f64,
    passes: ComputePasses,
    composite: CompositeCache,
    no_depth: wgpu::TextureView,
    /// Per-camera state; the default view always exists.
    views: Views,
    /// The view `encode_view` recorded last (for the pass times and readback helpers).
    last_view: ViewId,
    timer: Option<GpuTimer>,
    /// The cloud shadow map, when `settings.shadows.enabled`.
    shadow: Option<ShadowPass>,
    /// What the march binds in its place otherwise.
    no_shadow: NoShadow,
    /// The read-back textures CPU queries use, until the next weather or settings change.
    query_data: Option<std::sync::Arc<crate::query::QueryData>>,
    /// Whether the noise volumes in use came from a noise cache (not baked).
    noise_from_cache: bool,
    /// Weather requests waiting for their maps, in request order (see `set_weather`); the
    /// first one's map is being generated.
    pending_weather: PendingWeather,
}

/// A weather request waiting for its map: it enters the timeline once the map is ready.
struct WeatherRequest {
    weather: Weather,
    start: f64,
    duration: f64,
}

/// The requests waiting for their maps and the generation of the first one's.
#[derive(Default)]
struct PendingWeather {
    requests: std::collections::VecDeque<WeatherRequest>,
    /// The first request's map in the making (made when it became first).
    generation: Option<crate::gpu::weather::Generation>,
}

/// Most weather requests that may wait for their maps at once.
const MAX_PENDING_WEATHER: usize = 64;

/// Where a new renderer's noise volumes come from (see [`crate::noise_cache`]).
#[derive(Clone, Copy, Debug, Default)]
pub enum NoiseStart<'a> {
    /// Bake them on the GPU (what [`Renderer::new`] does).
    #[default]
    Bake,
    /// Upload them from a noise cache exported by [`Renderer::export_noise_cache`]. A cache
    /// that is damaged, from another noise algorithm (another library version) or for another
    /// seed or size is an [`Error::NoiseCache`].
    Cache(&'a [u8]),
    /// Upload them from the cache when it is usable for these settings, bake them otherwise
    /// (logging why, as a warning): what a host that ships or persists a cache wants.
    /// [`Renderer::noise_from_cache`] says which happened.
    CacheOrBake(&'a [u8]),
}

/// The cloud shadow map as the last frame of the default view left it: the texture, its
/// world → map matrix and what it was built for. See docs/cloud-shadows.md.
#[derive(Clone, Copy, Debug)]
pub struct CloudShadowMap<'a> {
    /// `resolution`² texels of `Rgba16Float`: r front depth (m), g mean extinction (1/m),
    /// b total optical depth, a exp(−b). The texture is toroidal: sample with repeat
    /// addressing (bilinear filtering is fine).
    pub texture: &'a wgpu::Texture,
    /// A view of `texture` for binding.
    pub view: &'a wgpu::TextureView,
    /// World position → (x, y texture coordinates, z depth along the light in meters, 1). A
    /// point at depth z under a texel t sees the sun through exp(−min(t.g · max(z − t.r, 0),
    /// t.b)); see [`crate::shadow_optical_depth`].
    pub world_to_map: glam::Mat4,
    /// The sun direction the map was built for (it follows the frame's sun to within 0.1°).
    pub sun: glam::Vec3,
    /// The map coordinates of the square's first texel corner: a world point lies inside the
    /// square (where the map is valid) iff `world_to_map`'s x and y minus these are both in
    /// [0, 1). Outside, the repeat addressing returns texels of the square's other side.
    pub window_origin: glam::Vec2,
    /// Texels along a side.
    pub resolution: u32,
    /// Side of the square (m).
    pub extent: f32,
}

/// Version of the per-frame output contract ([`FrameOutputs`], C `NimbusFrameOutputs`). A
/// change of any field's meaning or layout takes a new version; new fields alone do not.
pub const FRAME_OUTPUTS_VERSION: u32 = 1;

/// What a view's last frame leaves for the host besides the composited picture: the cloud
/// image on the trace grid (for depth-aware transparents, fog and the host's own compositing)
/// and the cloud shadow map. Contract version [`FRAME_OUTPUTS_VERSION`]; see
/// docs/frame-outputs.md.
#[derive(Clone, Copy, Debug)]
pub struct FrameOutputs<'a> {
    /// [`FRAME_OUTPUTS_VERSION`].
    pub version: u32,
    /// Size of the two cloud textures: the viewport divided by the trace resolution's divisor
    /// (grid pixel (x, y) covers viewport pixels (x, y) × divisor, same projection).
    pub grid: (u32, u32),
    /// `Rgba16Float`: rgb the clouds' in-scattered radiance L (linear, the sun's units), a their
    /// transmittance T; the composite is `scene × T + L`.
    pub clouds: &'a wgpu::TextureView,
    /// `Rgba32Float`: r the clouds' representative depth (m along the ray from the camera,
    /// weighted by where their light comes from), g the scene distance the ray stopped at,
    /// b reserved, a the front depth (m: where the ray first met cloud). r and a are 0 where
    /// the ray met no cloud.
    pub depth: &'a wgpu::TextureView,
    /// The cloud shadow map, when on ([`Renderer::cloud_shadows`]).
    pub shadows: Option<CloudShadowMap<'a>>,
    /// The light at the camera from above and below, on the GPU (`STORAGE | COPY_SRC`, 32
    /// bytes): two `vec4<f32>`, above then below, each rgb the clouds' irradiance and a the sky
    /// visibility ([`crate::HemisphereLight`]). Bind it as a read-only storage buffer in passes
    /// recorded after the view's encode; [`Renderer::read_ambient_light`] reads it on the CPU.
    pub ambient: &'a wgpu::Buffer,
}

/// Which subresource of each target the views show, for callers that make their own views
/// (the host Vulkan path: any mip, one layer of an array image). The public path is mip 0 of
/// a single-layer texture: wgpu does not tell a view's mip.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TargetMips {
    pub color: u32,
    pub depth: u32,
    /// The textures may have several layers (the views show one).
    pub layered: bool,
}

fn check_2d(
    target: &'static str,
    view: &wgpu::TextureView,
    mip: u32,
    layered: bool,
) -> Result<(u32, u32)> {
    let t = view.texture();
    if t.dimension() != wgpu::TextureDimension::D2 || (!layered && t.depth_or_array_layers() != 1) {
        return Err(invalid_target(target, "must be a single-layer 2D texture"));
    }
    if t.sample_count() != 1 {
        return Err(invalid_target(
            target,
            "must not be multisampled (resolve it first)",
        ));
    }
    if mip >= t.mip_level_count() {
        return Err(invalid_target(
            target,
            format!("has no mip {mip} ({} levels)", t.mip_level_count()),
        ));
    }
    let size = t.size().mip_level_size(mip, wgpu::TextureDimension::D2);
    Ok((size.width, size.height))
}

fn check_usage(
    target: &'static str,
    view: &wgpu::TextureView,
    usage: wgpu::TextureUsages,
) -> Result<()> {
    if view.texture().usage().contains(usage) {
        Ok(())
    } else {
        Err(invalid_target(target, format!("needs {usage:?} usage")))
    }
}

fn check_format(
    target: &'static str,
    view: &wgpu::TextureView,
    allowed: &[wgpu::TextureFormat],
    names: &'static str,
) -> Result<wgpu::TextureFormat> {
    let format = view.texture().format();
    if allowed.contains(&format) {
        Ok(format)
    } else {
        Err(Error::UnsupportedFormat {
            target,
            format,
            supported: names,
        })
    }
}

fn check_size(target: &'static str, got: (u32, u32), want: (u32, u32)) -> Result<()> {
    if got == want {
        Ok(())
    } else {
        Err(invalid_target(
            target,
            format!(
                "is {}x{} but the output is {}x{}",
                got.0, got.1, want.0, want.1
            ),
        ))
    }
}

/// Validated targets: output size, formats and which march variant to use.
struct CheckedTargets {
    /// The rendered rectangle: x, y, width, height.
    rect: [u32; 4],
    size: (u32, u32),
    output_format: wgpu::TextureFormat,
    depth_kind: DepthKind,
}

fn check_targets(t: &Targets, mips: TargetMips) -> Result<CheckedTargets> {
    let use_render = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let use_sample = wgpu::TextureUsages::TEXTURE_BINDING;
    let (size, output_format) = match t.color {
        ColorTargets::InPlace(view) => {
            let size = check_2d("output", view, mips.color, mips.layered)?;
            let format = check_format("output", view, OUTPUT_FORMATS, OUTPUT_NAMES)?;
            if format == F::Rgba32Float {
                return Err(Error::UnsupportedFormat {
                    target: "output",
                    format,
                    supported: "a blendable format for in-place compositing (Rgba32Float is not blendable; use ColorTargets::Separate)",
                });
            }
            check_usage("output", view, use_render)?;
            (size, format)
        }
        ColorTargets::Separate { scene, output } => {
            let size = check_2d("output", output, mips.color, mips.layered)?;
            let format = check_format("output", output, OUTPUT_FORMATS, OUTPUT_NAMES)?;
            // A storage-writable output is composited by a compute pass (src/gpu/composite.rs).
            if !crate::gpu::composite::storage_writable(output) {
                check_usage("output", output, use_render).map_err(|_| {
                    invalid_target(
                        "output",
                        "needs RENDER_ATTACHMENT usage, or STORAGE_BINDING with Rgba8Unorm, Rgba16Float or Rgba32Float",
                    )
                })?;
            }
            check_size(
                "scene_color",
                check_2d("scene_color", scene, mips.color, mips.layered)?,
                size,
            )?;
            check_format("scene_color", scene, OUTPUT_FORMATS, OUTPUT_NAMES)?;
            check_usage("scene_color", scene, use_sample)?;
            if scene.texture() == output.texture() {
                return Err(invalid_target(
                    "output",
                    "is the scene color texture: use ColorTargets::InPlace",
                ));
            }
            (size, format)
        }
    };
    if size.0 == 0 || size.1 == 0 {
        return Err(invalid_target("output", "has a zero size"));
    }
    let depth_kind = match t.depth {
        None => DepthKind::Depth,
        Some(view) => {
            check_size(
                "scene_depth",
                check_2d("scene_depth", view, mips.depth, mips.layered)?,
                size,
            )?;
            let format = check_format("scene_depth", view, DEPTH_FORMATS, DEPTH_NAMES)?;
            check_usage("scene_depth", view, use_sample)?;
            if format == F::R32Float {
                DepthKind::R32Float
            } else {
                DepthKind::Depth
            }
        }
    };
    let rect = match t.viewport {
        None => [0, 0, size.0, size.1],
        Some(v) => {
            let inside = v.x.checked_add(v.width).is_some_and(|r| r <= size.0)
                && v.y.checked_add(v.height).is_some_and(|b| b <= size.1);
            if v.width == 0 || v.height == 0 || !inside {
                return Err(invalid_target(
                    "viewport",
                    format!(
                        "({}, {}) {}x{} must be non-empty and inside the {}x{} targets",
                        v.x, v.y, v.width, v.height, size.0, size.1
                    ),
                ));
            }
            [v.x, v.y, v.width, v.height]
        }
    };
    Ok(CheckedTargets {
        rect,
        size: (rect[2], rect[3]),
        output_format,
        depth_kind,
    })
}

impl Renderer {
    /// Validates `settings`, bakes the noise volumes and weather map (submitting that work
    /// on `queue`) and builds the march pipelines.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, settings: Settings) -> Result<Self> {
        Self::with_noise(device, queue, settings, NoiseStart::Bake)
    }

    /// As [`Renderer::new`], with the noise volumes from `noise` (a cache skips the bake,
    /// which is most of a creation on software Vulkan: see docs/performance.md).
    pub fn with_noise(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: Settings,
        noise: NoiseStart<'_>,
    ) -> Result<Self> {
        settings.validate()?;
        let cache = match noise {
            NoiseStart::Bake => None,
            NoiseStart::Cache(bytes) => Some(volumes_for(bytes, &settings.noise)?),
            NoiseStart::CacheOrBake(bytes) => match volumes_for(bytes, &settings.noise) {
                Ok(c) => Some(c),
                Err(e) => {
                    log::warn!("{e}; baking the noise volumes instead");
                    None
                }
            },
        };
        gpu_scope(device, || {
            let noise = match cache {
                Some(texels) => NoiseTextures::from_texels(device, queue, &settings.noise, texels),
                None => NoiseTextures::new(device, queue, &settings.noise),
            };
            let weather_maps = WeatherMaps::new(
                device,
                queue,
                settings.noise.weather_size,
                &settings.weather,
            );
            let no_depth = crate::gpu::texture_2d(
                device,
                "nimbus no scene depth",
                (1, 1),
                F::Depth32Float,
                wgpu::TextureUsages::TEXTURE_BINDING,
            )
            .create_view(&Default::default());
            let shadow = settings
                .shadows
                .enabled
                .then(|| ShadowPass::new(device, settings.shadows));
            Self {
                device: device.clone(),
                queue: queue.clone(),
                passes: ComputePasses::new(device),
                composite: CompositeCache::default(),
                timeline: Timeline::new(settings.weather.clone(), 0.0),
                last_time: 0.0,
                weather_maps,
                settings,
                noise,
                no_depth,
                views: Views::new(device),
                last_view: ViewId::DEFAULT,
                timer: None,
                shadow,
                no_shadow: NoShadow::new(device),
                query_data: None,
                noise_from_cache: cache.is_some(),
                pending_weather: PendingWeather::default(),
            }
        })
    }

    /// Whether this renderer's noise volumes came from a noise cache rather than a bake
    /// (false again after a settings change re-baked them).
    pub fn noise_from_cache(&self) -> bool {
        self.noise_from_cache
    }

    /// The noise volumes in use as a noise cache ([`crate::noise_cache`]): about 8.5 MB for
    /// the default sizes. Waits for the GPU (it reads them back): call it once, at a loading
    /// screen or on exit, and store the bytes for [`NoiseStart::Cache`].
    pub fn export_noise_cache(&self) -> Result<Vec<u8>> {
        let read = |which| {
            crate::device::read_texture(&self.device, &self.queue, self.noise.volume(which), 0)
        };
        let (base, detail) = (read(NoiseVolume::Base)?, read(NoiseVolume::Detail)?);
        Ok(crate::noise_cache::encode(
            &self.settings.noise,
            &base,
            &detail,
        ))
    }

    /// The settings in use.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replaces the settings. Re-bakes the noise volumes and blue noise only when their seed
    /// or sizes changed (tile scales are uniforms and cost nothing), and regenerates the
    /// weather maps only when `settings.weather` or the map size changed. A different
    /// `settings.weather` takes effect at once (no transition; the wind carries on from where
    /// it is): use [`Renderer::set_weather`] for a smooth change. The new textures are built
    /// beside the old ones and swapped in only once the GPU has accepted the work: on error
    /// nothing changes. A frame prepared before the change must be prepared again: `encode`
    /// refuses it with [`Error::NotPrepared`] (its parameters came from the old settings).
    pub fn set_settings(&mut self, settings: Settings) -> Result<()> {
        settings.validate()?;
        let (device, queue) = (self.device.clone(), self.queue.clone());
        let (old, new) = (&self.settings.noise, &settings.noise);
        let bake_changed = (
            old.seed,
            old.base_size,
            old.detail_size,
            old.blue_noise_size,
        ) != (
            new.seed,
            new.base_size,
            new.detail_size,
            new.blue_noise_size,
        );
        let map_changed =
            settings.weather != self.settings.weather || new.weather_size != old.weather_size;
        let shadow_settings = settings.shadows;
        let new_shadow = shadow_settings.enabled
            && !self
                .shadow
                .as_ref()
                .is_some_and(|p| p.fits(&shadow_settings));
        let (noise, maps, shadow) = gpu_scope(&device, || {
            let noise = bake_changed.then(|| NoiseTextures::new(&device, &queue, new));
            let maps = map_changed.then(|| {
                self.weather_maps
                    .rebuilt(&device, &queue, new.weather_size, &settings.weather)
            });
            let shadow = new_shadow.then(|| ShadowPass::new(&device, shadow_settings));
            (noise, maps, shadow)
        })?;
        if !shadow_settings.enabled {
            self.shadow = None;
        } else if let Some(pass) = shadow {
            self.shadow = Some(pass);
        } else if let Some(pass) = &mut self.shadow {
            // Any setting may change what the map holds (the medium, the steps).
            pass.retune(shadow_settings);
        }
        if let Some(noise) = noise {
            self.noise = noise;
            self.noise_from_cache = false;
        }
        if let Some(maps) = maps {
            self.weather_maps = maps;
            self.timeline
                .replace(settings.weather.clone(), self.last_time);
        }
        // Pending requests survive a settings change: the first one's map starts again, on
        // the new maps and budget, in the next prepare.
        self.pending_weather.generation = None;
        if bake_changed || map_changed {
            // Cached bind groups hold the replaced textures' views.
            self.clear_bind_groups();
        }
        self.settings = settings;
        self.query_data = None;
        // Accumulated history was rendered with the old settings, and a prepared frame's
        // parameters were made from them: it must be prepared again.
        self.reset_history();
        for v in self.views.iter_mut() {
            v.pending = None;
        }
        Ok(())
    }

    /// Drops the accumulated cloud history: the next frame starts afresh, with no
    /// reprojection. Call it on camera cuts (teleports, switching to another camera); fast
    /// motion is handled without it. Settings changes and resizes reset it themselves.
    /// Resets every view's history (see [`Renderer::reset_view_history`] for one view).
    pub fn reset_history(&mut self) {
        for v in self.views.iter_mut() {
            v.history.view_proj = None;
        }
    }

    /// Drops one view's accumulated cloud history (a camera cut in that view).
    pub fn reset_view_history(&mut self, view: ViewId) -> Result<()> {
        self.views.get_mut(view)?.history.view_proj = None;
        Ok(())
    }

    /// Makes a new view: its own camera history and trace-grid textures (made at its first
    /// `encode_view`, sized to its viewport), sharing this renderer's noise, weather and
    /// pipelines. Use one view per camera that renders every frame: split-screen players, the
    /// two eyes of a stereo pair, the faces of a reflection probe. At most
    /// [`crate::view::MAX_VIEWS`] at once.
    pub fn create_view(&mut self) -> Result<ViewId> {
        self.views.create(&self.device)
    }

    /// Destroys a view made by [`Renderer::create_view`], freeing its textures (once the GPU
    /// work that uses them has finished). Its id is refused from then on; the default view
    /// cannot be destroyed.
    pub fn destroy_view(&mut self, view: ViewId) -> Result<()> {
        let state = self.views.destroy(view)?;
        self.forget_view_binds(&state);
        Ok(())
    }

    /// How many views exist (the default one included).
    pub fn view_count(&self) -> usize {
        self.views.len()
    }

    /// Starts a transition to `weather`, beginning at host time `start` (seconds, the clock of
    /// [`FrameInputs::time`]) and lasting `duration` seconds (0 = at once: the views' accumulated
    /// history, which shows the old weather, is dropped when it enters). If a transition is
    /// running, its current blend is baked into a texture and becomes the starting point, so
    /// the sky never jumps. Requests must come in time order. On error nothing changes.
    ///
    /// The new weather's map is generated on the GPU. When it has more texels than
    /// [`Settings::weather_map_texels_per_frame`] (the default 512² map does), it is generated
    /// a slice per [`Renderer::prepare`] (16 frames by default), so that no frame pays for the
    /// whole map, and the request enters the timeline once the map is ready: the transition
    /// starts at the later of `start` and that frame's time, and until then
    /// [`Renderer::weather_state`] says [`TransitionPhase::Pending`](crate::weather::TransitionPhase::Pending).
    /// Requests made while others wait queue behind them, in order (at most 64); one whose
    /// successor's start has already come when its turn arrives is skipped. Otherwise the map
    /// is generated here at once (its own small submission) and the transition starts
    /// exactly at `start`.
    pub fn set_weather(&mut self, weather: Weather, start: f64, duration: f64) -> Result<()> {
        weather.validate()?;
        // The request must be valid now (time order included, against a pending one too),
        // whenever it enters the timeline.
        let mut timeline = self.timeline.clone();
        let action = timeline.request(weather.clone(), start, duration)?;
        if let Some(last) = self.pending_weather.requests.back() {
            if start < last.start {
                return Err(Error::InvalidWeather(format!(
                    "request at t={start} is earlier than the pending request's start t={}; \
                     requests must come in time order",
                    last.start
                )));
            }
        }
        let (device, queue) = (self.device.clone(), self.queue.clone());
        let budget = self.settings.weather_map_texels_per_frame;
        // Behind a pending request a request waits its turn, whatever its map's size.
        if self.weather_maps.needs_slices(budget) || !self.pending_weather.requests.is_empty() {
            if self.pending_weather.requests.len() == MAX_PENDING_WEATHER {
                return Err(Error::InvalidWeather(format!(
                    "{MAX_PENDING_WEATHER} weather requests already wait for their maps"
                )));
            }
            self.pending_weather.requests.push_back(WeatherRequest {
                weather,
                start,
                duration,
            });
            return Ok(());
        }
        let slots = gpu_scope(&device, || {
            self.weather_maps.apply(&device, &queue, action, &weather)
        })?;
        // Only now, with the GPU work accepted, do the maps and the timeline move together.
        self.enter_weather(slots, timeline, duration);
        Ok(())
    }

    /// Makes `slots` the weather maps and `timeline` the timeline, after a request's map
    /// work was accepted.
    fn enter_weather(&mut self, slots: (usize, usize), timeline: Timeline, duration: f64) {
        self.weather_maps.commit(slots);
        self.timeline = timeline;
        self.query_data = None;
        if duration == 0.0 {
            // An instant change: neither the shadow map nor the views' accumulated history may
            // show the old weather for a few frames.
            if let Some(pass) = &mut self.shadow {
                pass.plan.invalidate();
            }
            self.reset_history();
        }
    }

    /// Generates the next slice of the first pending request's map (one submission); once
    /// the map is complete the request enters the timeline at max(its start, `now`). A
    /// request whose successor's start has come (`now` ≥ it) is skipped if its map is not
    /// begun: it would show for a few frames at most, and the successor moves on from the
    /// sky as it is. So requests made every frame never pile up (at most the one being made
    /// and the latest wait), and the one being made always finishes.
    fn advance_weather(&mut self, now: f64) -> Result<()> {
        let pending = &mut self.pending_weather;
        loop {
            let r = &pending.requests;
            if r.len() >= 3 && r[2].start <= now {
                // Waiting behind the first, and overtaken: never shown.
                pending.requests.remove(1);
            } else if r.len() >= 2 && pending.generation.is_none() && r[1].start <= now {
                // First, its map not begun, and overtaken.
                pending.requests.pop_front();
            } else {
                break;
            }
        }
        let Some(request) = pending.requests.front() else {
            return Ok(());
        };
        let (device, queue) = (self.device.clone(), self.queue.clone());
        let budget = match self.settings.weather_map_texels_per_frame {
            b if self.weather_maps.needs_slices(b) => b,
            _ => u32::MAX,
        };
        let maps = &self.weather_maps;
        let timeline = &self.timeline;
        let generation = &mut pending.generation;
        let entered = gpu_scope(&device, || {
            let g = generation
                .get_or_insert_with(|| maps.begin_generation(&device, &request.weather, budget));
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("nimbus weather slice"),
            });
            maps.record_slice(&mut encoder, g);
            let mut entered = None;
            if g.done() {
                // The timeline cannot refuse it: the request was checked when made, and a
                // later start (the map's readiness, or a settings change's reset since)
                // keeps the time order.
                let start = request.start.max(now).max(timeline.state(now).start);
                let mut timeline = timeline.clone();
                let action = timeline
                    .request(request.weather.clone(), start, request.duration)
                    .unwrap_or_else(|e| unreachable!("a checked request was refused: {e}"));
                entered = Some((
                    maps.settle_generated(&device, &mut encoder, action, g),
                    timeline,
                ));
            }
            queue.submit([encoder.finish()]);
            entered
        });
        let entered = match entered {
            Ok(e) => e,
            Err(e) => {
                // The request is dropped with the error; the ones behind it go on.
                self.pending_weather.requests.pop_front();
                self.pending_weather.generation = None;
                return Err(e);
            }
        };
        if let Some((slots, timeline)) = entered {
            let request = self
                .pending_weather
                .requests
                .pop_front()
                .unwrap_or_else(|| unreachable!("the request entered was first"));
            self.pending_weather.generation = None;
            self.enter_weather(slots, timeline, request.duration);
        }
        Ok(())
    }

    /// Stops the weather where it is at host time `now`: a running transition freezes at its
    /// current blend (baked on the GPU), a scheduled or pending one is dropped, and the sky
    /// holds until the next [`Renderer::set_weather`]. Submits its own small GPU work. On
    /// error nothing changes.
    pub fn cancel_weather(&mut self, now: f64) -> Result<()> {
        let mut timeline = self.timeline.clone();
        let action = timeline.hold(now)?;
        let (device, queue) = (self.device.clone(), self.queue.clone());
        let slots = gpu_scope(&device, || self.weather_maps.hold(&device, &queue, action))?;
        self.weather_maps.commit(slots);
        self.timeline = timeline;
        self.query_data = None;
        self.pending_weather = PendingWeather::default();
        Ok(())
    }

    /// The transition as seen at host time `time`: from and to, progress and phase. While a
    /// request's map is being generated: phase `Pending`, `from` the sky as it is, `to`,
    /// `start` and `duration` the request's, progress 0.
    pub fn weather_state(&self, time: f64) -> crate::weather::TransitionState {
        let state = self.timeline.state(time);
        match self.pending_weather.requests.front() {
            None => state,
            Some(p) => crate::weather::TransitionState {
                from: if state.progress < 0.5 {
                    state.from
                } else {
                    state.to
                },
                to: p.weather.name.clone(),
                start: p.start,
                duration: p.duration,
                progress: 0.0,
                phase: crate::weather::TransitionPhase::Pending,
            },
        }
    }

    /// The share of the first pending request's map generated so far, in [0, 1); `None`
    /// when no request is waiting for its map.
    pub fn pending_weather_progress(&self) -> Option<f32> {
        let p = &self.pending_weather;
        p.requests.front()?;
        Some(p.generation.as_ref().map_or(0.0, |g| g.progress()))
    }

    /// How many weather requests wait for their maps (see [`Renderer::set_weather`]).
    pub fn pending_weather_count(&self) -> usize {
        self.pending_weather.requests.len()
    }

    /// The weather at host time `time`: blended scalars, map weight and wind displacement.
    pub fn weather_at(&self, time: f64) -> WeatherSample {
        self.timeline.sample(time)
    }

    /// Validates the frame inputs and computes this frame's uniforms, for the default view.
    /// On error the previous frame's state is dropped, so `encode` refuses to draw stale
    /// inputs.
    pub fn prepare(&mut self, frame: &FrameInputs) -> Result<()> {
        self.prepare_view(ViewId::DEFAULT, frame)
    }

    /// [`Renderer::prepare`] for one view.
    pub fn prepare_view(&mut self, view: ViewId, frame: &FrameInputs) -> Result<()> {
        self.views.get_mut(view)?.pending = None;
        let (camera, sun_dir) = frame.validate()?;
        // A pending weather request's next map slice (and its entry once the map is ready).
        self.advance_weather(frame.time)?;
        let state = self.views.get_mut(view)?;
        let sample = self.timeline.sample(frame.time);
        self.last_time = frame.time;
        let march = MarchUniforms::new(&self.settings, &sample, frame, &camera, sun_dir, false);
        let composite = CompositeUniforms::new(
            camera.inv_view_proj_rel,
            frame.camera.depth.far_value(),
            false,
        );
        state.pending = Some(Pending {
            march,
            composite,
            view_proj: camera.view_proj,
            inv_view_proj_rel: camera.inv_view_proj_rel,
            camera: camera.position,
            near_value: frame.camera.depth.near_value(),
            far_value: frame.camera.depth.far_value(),
        });
        Ok(())
    }

    /// Records the march, the temporal resolve (when on) and the composite into `encoder`,
    /// for the default view. Submits nothing: the host submits the encoder. One `encode` per
    /// `prepare`. The history belongs to one camera: give each other camera its own view
    /// ([`Renderer::create_view`]).
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, targets: &Targets) -> Result<()> {
        self.encode_view(ViewId::DEFAULT, encoder, targets)
    }

    /// [`Renderer::encode`] for one view, after [`Renderer::prepare_view`] for it. Several
    /// views may be encoded into one encoder (each has its own uniform buffers).
    pub fn encode_view(
        &mut self,
        view: ViewId,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
    ) -> Result<()> {
        self.encode_view_at(view, encoder, targets, TargetMips::default())
    }

    /// [`Renderer::encode_view`] on views of the given mips (and layers).
    pub(crate) fn encode_view_at(
        &mut self,
        view: ViewId,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        mips: TargetMips,
    ) -> Result<()> {
        let pending = self.views.get(view)?.pending.ok_or(Error::NotPrepared)?;
        let (mut uniforms, mut composite) = (pending.march, pending.composite);
        let checked = check_targets(targets, mips)?;
        let has_depth = targets.depth.is_some();
        uniforms.set_has_depth(has_depth);
        composite.set_has_depth(has_depth);
        uniforms.set_viewport(checked.rect);
        composite.set_viewport(checked.rect);
        // The trace grid, its resolve and the composite's pipeline follow the settings now.
        let divisor = self.settings.march.resolution.divisor();
        composite.set_divisor(divisor);
        let temporal = self.settings.march.temporal;
        let pattern = temporal.pattern;
        let block = pattern.block();
        let device = self.device.clone();
        let layout = gpu_scope(&device, || {
            let state = self
                .views
                .get_mut(view)
                .expect("the view was checked above");
            if state.ensure_size(&device, &self.settings, checked.size) {
                // Cached bind groups hold the old textures' views: drop them with the textures.
                let buffers = state.buffers().map(Clone::clone);
                forget_binds(&mut self.passes, &mut self.composite, &buffers);
            }
            let state = self.views.get(view).expect("the view was checked above");
            let offset = pattern.offset(state.frame_index);
            let sized = state
                .sized
                .as_ref()
                .expect("sized textures exist after ensure_size");
            let grid = sized.grid;
            uniforms.set_grid(grid, block, offset, state.frame_index / (block * block));
            self.queue
                .write_buffer(&state.uniforms, 0, bytemuck::bytes_of(&uniforms));
            self.queue
                .write_buffer(&state.composite_uniforms, 0, bytemuck::bytes_of(&composite));
            if view == ViewId::DEFAULT {
                if let Some(pass) = &mut self.shadow {
                    let frame = ShadowFrame {
                        camera: pending.camera,
                        sun: uniforms.sun_dir(),
                        medium_top: uniforms.medium_top(),
                    };
                    pass.record(
                        &device,
                        &self.queue,
                        encoder,
                        &state.uniforms,
                        &self.noise,
                        self.weather_maps.views(),
                        &frame,
                        self.timer.as_ref(),
                    );
                }
            }
            let shadow = match &self.shadow {
                Some(p) => (&p.view, &p.sampling),
                None => (&self.no_shadow.view, &self.no_shadow.sampling),
            };
            // The whole probe where the view has no history (first frame, camera cut, resize,
            // settings change), else one of its twelve subsets in turn.
            let no_history = state.history.view_proj.is_none();
            state
                .ambient
                .write_params(&self.queue, state.frame_index, no_history);
            self.passes.ambient.record(
                &device,
                encoder,
                &state.uniforms,
                &self.noise,
                self.weather_maps.views(),
                shadow,
                &state.ambient,
                if no_history {
                    crate::gpu::ambient::AMBIENT_SUBSETS
                } else {
                    1
                },
                self.timer.as_ref(),
            );
            let (march, resolve) = self.passes.for_depth(checked.depth_kind);
            let scene_depth = targets.depth.unwrap_or(&self.no_depth);
            let fresh = &sized.fresh;
            march.record(
                &device,
                encoder,
                &state.uniforms,
                &self.noise,
                self.weather_maps.views(),
                scene_depth,
                &fresh.clouds.view,
                &fresh.depth.view,
                &sized.fresh_stats.view,
                shadow,
                (fresh.clouds.texture.width(), fresh.clouds.texture.height()),
                MarchVariant::of(&uniforms),
                self.timer.as_ref(),
            );
            let resolved = if temporal.enabled {
                let previous = &sized.history[state.history.current];
                let next = &sized.history[1 - state.history.current];
                let frame = ResolveFrame {
                    inv_view_proj_rel: pending.inv_view_proj_rel,
                    prev_view_proj: state.history.view_proj,
                    camera: pending.camera,
                    near_value: pending.near_value,
                    far_value: pending.far_value,
                    grid,
                    block,
                    offset,
                    divisor,
                    max_samples: temporal.max_samples,
                    has_depth,
                    max_distance: self.settings.march.max_distance,
                    viewport: checked.rect,
                };
                self.queue.write_buffer(
                    &state.temporal_uniforms,
                    0,
                    bytemuck::bytes_of(&TemporalUniforms::new(&frame)),
                );
                resolve.record(
                    &device,
                    encoder,
                    &state.temporal_uniforms,
                    fresh,
                    previous,
                    scene_depth,
                    next,
                    grid,
                    self.timer.as_ref(),
                );
                next
            } else {
                fresh
            };
            let (scene, output) = match targets.color {
                ColorTargets::InPlace(v) => (None, v),
                ColorTargets::Separate { scene, output } => (Some(scene), output),
            };
            let inputs = CompositeInputs {
                clouds: &resolved.clouds.view,
                cloud_depth: &resolved.depth.view,
                scene_depth,
                depth_kind: checked.depth_kind,
                uniforms: &state.composite_uniforms,
                timer: self.timer.as_ref(),
                viewport: checked.rect,
                divisor,
            };
            self.composite.record(
                &device,
                encoder,
                &inputs,
                scene,
                output,
                checked.output_format,
            );
            if let Some(timer) = &self.timer {
                timer.resolve(encoder);
            }
            TraceLayout {
                grid,
                block,
                offset,
            }
        })?;
        // Only once the work is recorded does the history move on.
        let state = self.views.get_mut(view)?;
        if temporal.enabled {
            state.history.current = 1 - state.history.current;
            state.history.view_proj = Some(pending.view_proj);
        }
        state.history.resolved = temporal.enabled;
        state.history.layout = Some(layout);
        state.frame_index = state.frame_index.wrapping_add(1);
        self.last_view = view;
        Ok(())
    }

    /// Records GPU timestamps around the march and composite passes from now on (for
    /// benchmarks). Returns false when the device lacks `TIMESTAMP_QUERY` (request it when
    /// creating the device; `Headless` does).
    pub fn enable_gpu_timing(&mut self) -> bool {
        if self.timer.is_none() {
            self.timer = GpuTimer::new(&self.device, &self.queue);
        }
        self.timer.is_some()
    }

    /// The GPU time of each pass in the last submitted frame, once timing is enabled. Waits
    /// for the GPU.
    pub fn last_pass_times(&self) -> Result<Option<PassTimes>> {
        let times = self
            .timer
            .as_ref()
            .map(|t| t.read(&self.device))
            .transpose()?;
        let resolved = self
            .views
            .get(self.last_view)
            .is_ok_and(|v| v.history.resolved);
        // The resolve's queries keep an older frame's values when it did not run.
        Ok(times.map(|mut t| {
            if !resolved {
                t.resolve_ms = 0.0;
            }
            t
        }))
    }

    /// Bytes of GPU memory Nimbus has allocated for textures and buffers (noise volumes with
    /// their mips, weather maps, blue noise, and every view's trace-grid textures and
    /// uniforms).
    pub fn gpu_memory_bytes(&self) -> u64 {
        self.shared_memory_bytes()
            + self
                .views
                .iter()
                .map(|v| v.memory_bytes(texture_bytes))
                .sum::<u64>()
    }

    /// Bytes of GPU memory one view holds (its trace-grid textures and uniforms); the rest
    /// of [`Renderer::gpu_memory_bytes`] is shared by all views.
    pub fn view_memory_bytes(&self, view: ViewId) -> Result<u64> {
        Ok(self.views.get(view)?.memory_bytes(texture_bytes))
    }

    /// Bytes of GPU memory all views share (noise volumes, weather maps, blue noise, the
    /// cloud shadow map).
    pub fn shared_memory_bytes(&self) -> u64 {
        self.noise.memory_bytes(texture_bytes)
            + self.weather_maps.memory_bytes(texture_bytes)
            + self
                .shadow
                .as_ref()
                .map_or(0, |p| texture_bytes(&p.texture))
    }

    /// CPU queries (density, transmittance, coverage) that answer as this renderer renders:
    /// see [`CloudQuery`](crate::CloudQuery). The first call after creation, a weather request
    /// or a settings change reads the noise volumes and weather maps back (waits for the GPU:
    /// 9 MB at the default sizes); later ones share that copy and cost nothing. A query made
    /// before a weather request keeps answering for the weather as it was: make a new one.
    pub fn cloud_query(&mut self) -> Result<crate::CloudQuery> {
        use crate::query::{QueryData, TexelValues, Texels};
        let camera = self
            .views
            .get(ViewId::DEFAULT)
            .ok()
            .and_then(|v| v.pending)
            .map_or(glam::Vec3::ZERO, |p| p.camera);
        if let Some(data) = &self.query_data {
            return Ok(crate::CloudQuery::new(data.clone(), camera));
        }
        let read = |t: &wgpu::Texture| -> Result<Texels> {
            Ok(Texels {
                size: t.width(),
                depth: t.depth_or_array_layers(),
                values: TexelValues::read(&self.device, &self.queue, t)?,
            })
        };
        let (from, to) = self.weather_maps.textures();
        let data = std::sync::Arc::new(QueryData {
            settings: self.settings.clone(),
            timeline: self.timeline.clone(),
            base: read(self.noise.volume(NoiseVolume::Base))?,
            detail: read(self.noise.volume(NoiseVolume::Detail))?,
            maps: (read(from)?, read(to)?),
        });
        self.query_data = Some(data.clone());
        Ok(crate::CloudQuery::new(data, camera))
    }

    /// The per-frame outputs of `view`'s last encoded frame (the cloud image, its depths and
    /// the shadow map); an error for an unknown view or before its first frame. Valid for
    /// passes recorded after that `encode_view`, until the next one.
    pub fn frame_outputs(&self, view: ViewId) -> Result<FrameOutputs<'_>> {
        let (clouds, depth, grid) = self
            .cloud_image(view)
            .ok_or_else(|| invalid_target("output", "this view has not rendered a frame yet"))?;
        Ok(FrameOutputs {
            version: FRAME_OUTPUTS_VERSION,
            grid,
            clouds: &clouds.view,
            depth: &depth.view,
            shadows: self.cloud_shadows(),
            ambient: &self.views.get(view)?.ambient.out,
        })
    }

    /// The light at `view`'s camera from above and below that its last submitted frame found
    /// ([`AmbientLight`](crate::AmbientLight)); an error for an unknown view or before its first
    /// frame. Waits for the GPU (a 32-byte copy after everything submitted so far): a host that
    /// lights with it every frame binds [`FrameOutputs::ambient`] instead, or reads every few
    /// frames.
    pub fn read_ambient_light(&self, view: ViewId) -> Result<crate::AmbientLight> {
        let state = self.views.get(view)?;
        if state.history.layout.is_none() {
            return Err(invalid_target(
                "output",
                "this view has not rendered a frame yet",
            ));
        }
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&state.ambient.out, 0, &state.ambient_readback, 0, None);
        self.queue.submit([encoder.finish()]);
        let bytes = crate::gpu::readback::map_read(&self.device, &state.ambient_readback)?;
        Ok(crate::AmbientLight::from_bytes(&bytes))
    }

    /// A view's resolved (or, with temporal reprojection off, fresh) cloud image.
    fn cloud_image(
        &self,
        view: ViewId,
    ) -> Option<(
        &crate::gpu::temporal::Target,
        &crate::gpu::temporal::Target,
        (u32, u32),
    )> {
        let v = self.views.get(view).ok()?;
        v.history.layout?;
        let s = v.sized.as_ref()?;
        let image = if v.history.resolved {
            &s.history[v.history.current]
        } else {
            &s.fresh
        };
        Some((&image.clouds, &image.depth, s.grid))
    }

    /// The cloud shadow map, once a frame of the default view has been encoded with
    /// `settings.shadows.enabled`; `None` otherwise. The map follows the default view's
    /// camera and is updated in that view's `encode` (before the march, in the same encoder):
    /// bind it in passes recorded after that encode.
    pub fn cloud_shadows(&self) -> Option<CloudShadowMap<'_>> {
        let pass = self.shadow.as_ref()?;
        Some(CloudShadowMap {
            texture: &pass.texture,
            view: &pass.view,
            world_to_map: pass.world_to_map?,
            sun: pass.sun,
            window_origin: pass.window_origin,
            resolution: self.settings.shadows.resolution,
            extent: self.settings.shadows.extent,
        })
    }

    /// Number of pipelines built on demand so far: composite pipelines (one per output format
    /// and mode) and march specialisations (one per scene-depth kind, medium and shadow-map
    /// light setting used; the noise model's without the shadow-map light are built at
    /// creation). Settings and new target formats add pipelines; frames never do.
    pub fn cached_pipeline_count(&self) -> usize {
        self.composite.len() + self.passes.march_variant_count()
    }

    /// Bind groups the per-frame passes have made so far. They are made when the bound
    /// textures change (first frame of a view, resize, settings or weather change, other host
    /// views), never per frame: a frame loop that keeps its views keeps this number still.
    pub fn bind_groups_created(&self) -> u64 {
        self.passes.bind_groups_created()
            + self.composite.bind_groups_created()
            + self.shadow.as_ref().map_or(0, |p| p.bind_groups_created())
    }

    /// Drops the cached bind groups that hold the host's target views (scene depth, scene
    /// color). Call it before destroying textures whose views were passed to `encode`, so no
    /// cached bind group keeps them alive; the next frame makes new ones.
    pub fn forget_target_views(&mut self) {
        self.clear_bind_groups();
    }

    fn clear_bind_groups(&mut self) {
        self.passes.clear_bind_groups();
        self.composite.clear_bind_groups();
        if let Some(pass) = &mut self.shadow {
            pass.clear_bind_groups();
        }
    }

    fn forget_view_binds(&mut self, state: &ViewState) {
        let buffers = state.buffers().map(Clone::clone);
        forget_binds(&mut self.passes, &mut self.composite, &buffers);
    }

    /// The march's parameters for `frame` (validated), as `prepare` computes them.
    pub(crate) fn march_uniforms(&self, frame: &FrameInputs) -> Result<MarchUniforms> {
        let (camera, sun_dir) = frame.validate()?;
        let sample = self.timeline.sample(frame.time);
        Ok(MarchUniforms::new(
            &self.settings,
            &sample,
            frame,
            &camera,
            sun_dir,
            false,
        ))
    }

    /// The device, queue, noise textures and current weather-map views, for passes that see
    /// the same medium (the path tracer).
    pub(crate) fn medium(
        &self,
    ) -> (
        &wgpu::Device,
        &wgpu::Queue,
        &NoiseTextures,
        (&wgpu::TextureView, &wgpu::TextureView),
    ) {
        (
            &self.device,
            &self.queue,
            &self.noise,
            self.weather_maps.views(),
        )
    }

    pub(crate) fn noise_volume(&self, which: NoiseVolume) -> &wgpu::Texture {
        self.noise.volume(which)
    }

    /// The (from, to) weather maps of the running transition.
    pub(crate) fn weather_maps(&self) -> (&wgpu::Texture, &wgpu::Texture) {
        self.weather_maps.textures()
    }

    /// The clouds the last encoded view composited, on the trace grid: RGBA16F with rgb = L,
    /// a = T; and RGBA32F (cloud depth, scene distance, samples held, -).
    pub(crate) fn march_textures(&self) -> Option<(&wgpu::Texture, &wgpu::Texture)> {
        let (clouds, depth, _) = self.cloud_image(self.last_view)?;
        Some((&clouds.texture, &depth.texture))
    }

    /// The last encoded view's sparse march depth (cloud depth, scene distance, density
    /// samples, light samples per traced pixel) and where those pixels lie in the grid.
    pub(crate) fn fresh_samples(&self) -> Option<(&wgpu::Texture, TraceLayout)> {
        let v = self.views.get(self.last_view).ok()?;
        let s = v.sized.as_ref()?;
        Some((&s.fresh_stats.texture, v.history.layout?))
    }
}

/// Bytes of one texture with all its mips.
fn texture_bytes(t: &wgpu::Texture) -> u64 {
    let bpp = t.format().block_copy_size(None).unwrap_or(4) as u64;
    (0..t.mip_level_count())
        .map(|m| {
            let s = t.size().mip_level_size(m, t.dimension());
            s.width as u64 * s.height as u64 * s.depth_or_array_layers as u64 * bpp
        })
        .sum()
}

/// Drops the bind groups made with one view's uniform buffers.
fn forget_binds(
    passes: &mut ComputePasses,
    composite: &mut CompositeCache,
    buffers: &[wgpu::Buffer],
) {
    for b in buffers {
        passes.forget(b);
        composite.forget(b);
    }
}

/// The compute pipelines, one per scene-depth kind.
struct ComputePasses {
    march_depth: MarchPipeline,
    march_r32: MarchPipeline,
    temporal_depth: TemporalPipeline,
    temporal_r32: TemporalPipeline,
    ambient: AmbientPipeline,
}

impl ComputePasses {
    fn new(device: &wgpu::Device) -> Self {
        Self {
            march_depth: MarchPipeline::new(device, DepthKind::Depth),
            march_r32: MarchPipeline::new(device, DepthKind::R32Float),
            temporal_depth: TemporalPipeline::new(device, DepthKind::Depth),
            temporal_r32: TemporalPipeline::new(device, DepthKind::R32Float),
            ambient: AmbientPipeline::new(device),
        }
    }

    fn march_variant_count(&self) -> usize {
        self.march_depth.variant_count() + self.march_r32.variant_count()
    }

    fn for_depth(&mut self, kind: DepthKind) -> (&mut MarchPipeline, &mut TemporalPipeline) {
        match kind {
            DepthKind::Depth => (&mut self.march_depth, &mut self.temporal_depth),
            DepthKind::R32Float => (&mut self.march_r32, &mut self.temporal_r32),
        }
    }

    fn caches(&mut self) -> [&mut crate::gpu::bind_cache::BindCache; 5] {
        [
            &mut self.march_depth.binds,
            &mut self.march_r32.binds,
            &mut self.temporal_depth.binds,
            &mut self.temporal_r32.binds,
            &mut self.ambient.binds,
        ]
    }

    fn bind_groups_created(&self) -> u64 {
        [
            &self.march_depth.binds,
            &self.march_r32.binds,
            &self.temporal_depth.binds,
            &self.temporal_r32.binds,
            &self.ambient.binds,
        ]
        .iter()
        .map(|b| b.created())
        .sum()
    }

    fn forget(&mut self, buffer: &wgpu::Buffer) {
        for c in self.caches() {
            c.forget(buffer);
        }
    }

    fn clear_bind_groups(&mut self) {
        for c in self.caches() {
            c.clear();
        }
    }
}
