//! [`Headless`]: Nimbus on a device of its own (software Vulkan is fine), rendering into
//! textures it owns and reading them back. For tests, tools and hosts without a GPU API.

use std::time::{Duration, Instant};

use half::f16;

pub use crate::device::create_device;
use crate::device::{gpu_scope, read_texture, texture_2d, DeviceErrors};
use crate::error::{invalid_target, Error, Result};
use crate::frame::FrameInputs;
use crate::gpu::noise::NoiseVolume;
use crate::renderer::{ColorTargets, Renderer, Targets};
use crate::settings::Settings;

/// A weather map read back: RGBA in [0, 1] per texel, x fastest (`Headless::read_weather_maps`).
pub type WeatherMapTexels = Vec<[f32; 4]>;

/// Largest edge Headless accepts for its targets.
pub const MAX_HEADLESS_SIZE: u32 = 8192;

/// The targets and their views, made once per size: a frame makes no views.
struct OwnedTargets {
    width: u32,
    height: u32,
    scene: wgpu::Texture,
    depth: wgpu::Texture,
    output: wgpu::Texture,
    scene_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    output_view: wgpu::TextureView,
    has_depth: bool,
}

/// Per-ray counters of one frame's march.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayStats {
    /// Rays traced (one per traced pixel of the trace grid).
    pub rays: u64,
    /// Density samples per ray along the view ray (coarse probes included).
    pub mean_samples: f64,
    /// Density samples per ray toward the sun.
    pub mean_light_samples: f64,
}

/// Live wgpu objects on a device and the GPU memory wgpu has allocated for them, from wgpu's
/// internal counters. On a [`Headless`] device every object is Nimbus's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LiveObjects {
    /// Buffers alive.
    pub buffers: isize,
    /// Textures alive.
    pub textures: isize,
    /// Texture views alive.
    pub texture_views: isize,
    /// Bind groups alive.
    pub bind_groups: isize,
    /// Render and compute pipelines alive.
    pub pipelines: isize,
    /// Shader modules alive.
    pub shader_modules: isize,
    /// Command encoders alive (0 between frames).
    pub command_encoders: isize,
    /// Bytes of GPU memory held by buffers.
    pub buffer_memory: isize,
    /// Bytes of GPU memory held by textures.
    pub texture_memory: isize,
}

impl LiveObjects {
    /// Reads the counters of `device`.
    pub fn of(device: &wgpu::Device) -> Self {
        let c = device.get_internal_counters().hal;
        Self {
            buffers: c.buffers.read(),
            textures: c.textures.read(),
            texture_views: c.texture_views.read(),
            bind_groups: c.bind_groups.read(),
            pipelines: c.render_pipelines.read() + c.compute_pipelines.read(),
            shader_modules: c.shader_modules.read(),
            command_encoders: c.command_encoders.read(),
            buffer_memory: c.buffer_memory.read(),
            texture_memory: c.texture_memory.read(),
        }
    }

    /// The counts of objects Nimbus creates: buffers, texture views, bind groups, pipelines,
    /// shader modules. Left out: memory (it follows the target size); textures (wgpu-hal 30's
    /// Vulkan backend counts only their destruction, so that number only falls); command
    /// encoders (wgpu pools and reuses them).
    pub fn counts(&self) -> [isize; 5] {
        [
            self.buffers,
            self.texture_views,
            self.bind_groups,
            self.pipelines,
            self.shader_modules,
        ]
    }
}

impl std::fmt::Display for LiveObjects {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "buffers {} textures {} views {} bind groups {} pipelines {} shaders {} encoders {} \
             (memory: buffers {} KiB, textures {} KiB)",
            self.buffers,
            self.textures,
            self.texture_views,
            self.bind_groups,
            self.pipelines,
            self.shader_modules,
            self.command_encoders,
            self.buffer_memory / 1024,
            self.texture_memory / 1024
        )
    }
}

/// A renderer with its own device and targets: scene color (RGBA16F), scene depth (R32F,
/// clip-space depth in the camera's convention) and output (RGBA16F, linear HDR).
pub struct Headless {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_info: wgpu::AdapterInfo,
    renderer: Renderer,
    errors: DeviceErrors,
    targets: Option<OwnedTargets>,
    in_place: bool,
    storage_output: bool,
}

fn to_f16(data: &[[f32; 4]]) -> Vec<u8> {
    data.iter()
        .flat_map(|p| p.iter().flat_map(|v| f16::from_f32(*v).to_le_bytes()))
        .collect()
}

fn from_f16(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytes
        .chunks_exact(8)
        .map(|c| {
            let v = |i: usize| f16::from_le_bytes([c[2 * i], c[2 * i + 1]]).to_f32();
            [v(0), v(1), v(2), v(3)]
        })
        .collect()
}

/// Reads a frame's cloud textures back as (T, front depth, representative depth, 0) per grid
/// pixel.
pub(crate) fn read_outputs(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    out: &crate::FrameOutputs,
) -> Result<Vec<[f32; 4]>> {
    let clouds = from_f16(&read_texture(device, queue, out.clouds.texture(), 0)?);
    let depth: Vec<f32> =
        bytemuck::pod_collect_to_vec(&read_texture(device, queue, out.depth.texture(), 0)?);
    Ok(clouds
        .iter()
        .zip(depth.chunks_exact(4))
        .map(|(c, d)| [c[3], d[3], d[0], 0.0])
        .collect())
}

impl Headless {
    /// Creates a device of its own and a renderer on it.
    pub fn new(settings: Settings) -> Result<Self> {
        Self::with_noise(settings, crate::NoiseStart::Bake)
    }

    /// As [`Headless::new`], with the noise volumes from `noise` (see
    /// [`Renderer::with_noise`]).
    pub fn with_noise(settings: Settings, noise: crate::NoiseStart<'_>) -> Result<Self> {
        settings.validate()?;
        let (device, queue, adapter_info) = create_device()?;
        // Nothing may panic: wgpu errors outside our scopes are collected and reported.
        let errors = DeviceErrors::install(&device);
        let renderer = Renderer::with_noise(&device, &queue, settings, noise)?;
        Ok(Self {
            device,
            queue,
            adapter_info,
            renderer,
            errors,
            targets: None,
            in_place: false,
            storage_output: true,
        })
    }

    /// The adapter in use (name, backend, driver).
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.adapter_info
    }

    /// The renderer, e.g. to change settings.
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The owned device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// Composite onto the scene texture itself (blend path) instead of a separate output.
    pub fn set_in_place(&mut self, in_place: bool) {
        self.in_place = in_place;
    }

    /// Whether the output texture allows storage writes, so that the composite runs as a
    /// compute pass (the default); `false` makes it a render-pass-only target, composited by
    /// a fullscreen triangle. Recreates the targets (the scene starts black again).
    pub fn set_storage_output(&mut self, storage: bool) -> Result<()> {
        self.storage_output = storage;
        match self.targets.as_ref().map(|t| (t.width, t.height)) {
            Some((w, h)) => self.resize(w, h),
            None => Ok(()),
        }
    }

    fn take_errors(&self) -> Result<()> {
        self.errors.take()
    }

    /// (Re)creates the targets at `width`×`height`. The scene starts black with no depth.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        for (name, v) in [("width", width), ("height", height)] {
            if v == 0 || v > MAX_HEADLESS_SIZE {
                return Err(invalid_target(
                    "output",
                    format!("{name} must be in 1..={MAX_HEADLESS_SIZE}, got {v}"),
                ));
            }
        }
        let make =
            |label, format, usage| texture_2d(&self.device, label, (width, height), format, usage);
        use wgpu::TextureUsages as U;
        let color_usage = U::TEXTURE_BINDING | U::RENDER_ATTACHMENT | U::COPY_DST | U::COPY_SRC;
        let targets = gpu_scope(&self.device, || {
            let scene = make(
                "nimbus scene color",
                wgpu::TextureFormat::Rgba16Float,
                color_usage,
            );
            let depth = make(
                "nimbus scene depth",
                wgpu::TextureFormat::R32Float,
                U::TEXTURE_BINDING | U::COPY_DST,
            );
            let storage = if self.storage_output {
                U::STORAGE_BINDING
            } else {
                U::empty()
            };
            let output = make(
                "nimbus output",
                wgpu::TextureFormat::Rgba16Float,
                color_usage | storage,
            );
            OwnedTargets {
                width,
                height,
                scene_view: scene.create_view(&Default::default()),
                depth_view: depth.create_view(&Default::default()),
                output_view: output.create_view(&Default::default()),
                scene,
                depth,
                output,
                has_depth: false,
            }
        })?;
        self.targets = Some(targets);
        Ok(())
    }

    fn targets(&self) -> Result<&OwnedTargets> {
        self.targets
            .as_ref()
            .ok_or_else(|| invalid_target("output", "no targets yet: call resize() first"))
    }

    /// Current target size.
    pub fn size(&self) -> Option<(u32, u32)> {
        self.targets.as_ref().map(|t| (t.width, t.height))
    }

    /// Uploads the scene color (linear RGBA, row-major from the top) and optionally its depth
    /// (clip-space depth in the camera's convention). Lengths must be width × height.
    pub fn upload_scene(&mut self, color: &[[f32; 4]], depth: Option<&[f32]>) -> Result<()> {
        let t = self.targets()?;
        let n = (t.width * t.height) as usize;
        if color.len() != n {
            return Err(invalid_target(
                "scene_color",
                format!(
                    "has {} pixels, expected {}x{} = {n}",
                    color.len(),
                    t.width,
                    t.height
                ),
            ));
        }
        if let Some(d) = depth {
            if d.len() != n {
                return Err(invalid_target(
                    "scene_depth",
                    format!("has {} pixels, expected {n}", d.len()),
                ));
            }
            if let Some(bad) = d.iter().find(|v| !v.is_finite() || **v < 0.0 || **v > 1.0) {
                return Err(invalid_target(
                    "scene_depth",
                    format!("depth values must be in [0, 1], found {bad}"),
                ));
            }
        }
        let extent = wgpu::Extent3d {
            width: t.width,
            height: t.height,
            depth_or_array_layers: 1,
        };
        let write = |texture: &wgpu::Texture, bytes: &[u8], bpp: u32| {
            self.queue.write_texture(
                texture.as_image_copy(),
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(t.width * bpp),
                    rows_per_image: Some(t.height),
                },
                extent,
            )
        };
        write(&t.scene, &to_f16(color), 8);
        if let Some(d) = depth {
            write(&t.depth, bytemuck::cast_slice(d), 4);
        }
        let has_depth = depth.is_some();
        if let Some(t) = self.targets.as_mut() {
            t.has_depth = has_depth;
        }
        self.take_errors()
    }

    /// Renders one frame and waits for it. Returns the wall time from submit to completion.
    pub fn render(&mut self, frame: &FrameInputs) -> Result<Duration> {
        self.errors.check_lost()?;
        self.renderer.prepare(frame)?;
        // The field, not `targets()`: the renderer is borrowed mutably beside it.
        let t = self
            .targets
            .as_ref()
            .ok_or_else(|| invalid_target("output", "no targets yet: call resize() first"))?;
        let color = if self.in_place {
            ColorTargets::InPlace(&t.scene_view)
        } else {
            ColorTargets::Separate {
                scene: &t.scene_view,
                output: &t.output_view,
            }
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("nimbus headless frame"),
            });
        self.renderer.encode(
            &mut encoder,
            &Targets {
                color,
                depth: t.has_depth.then_some(&t.depth_view),
                viewport: None,
            },
        )?;
        let start = Instant::now();
        let commands = gpu_scope(&self.device, || encoder.finish())?;
        self.queue.submit([commands]);
        let polled = self.device.poll(wgpu::PollType::wait_indefinitely());
        // A lost device fails the poll: report the loss, not the poll.
        self.errors.check_lost()?;
        polled.map_err(|e| Error::Gpu(e.to_string()))?;
        let elapsed = start.elapsed();
        self.take_errors()?;
        Ok(elapsed)
    }

    /// The composited image (linear HDR RGBA), row-major from the top. In place, this is the
    /// scene texture the clouds were drawn onto.
    pub fn read_output(&self) -> Result<Vec<[f32; 4]>> {
        let t = self.targets()?;
        let texture = if self.in_place { &t.scene } else { &t.output };
        Ok(from_f16(&read_texture(
            &self.device,
            &self.queue,
            texture,
            0,
        )?))
    }

    /// The last march result at the trace resolution: rgb = in-scattered radiance L,
    /// a = transmittance T.
    pub fn read_clouds(&self) -> Result<Vec<[f32; 4]>> {
        let (march, _) = self
            .renderer
            .march_textures()
            .ok_or_else(|| invalid_target("output", "nothing rendered yet"))?;
        Ok(from_f16(&read_texture(
            &self.device,
            &self.queue,
            march,
            0,
        )?))
    }

    /// The default view's last frame outputs on the trace grid, per pixel (transmittance,
    /// front depth m, representative depth m, 0): the read-back form of
    /// [`Renderer::frame_outputs`]'s cloud textures (0 depths = no cloud).
    pub fn read_frame_outputs(&self) -> Result<Vec<[f32; 4]>> {
        let out = self.renderer.frame_outputs(crate::ViewId::DEFAULT)?;
        read_outputs(&self.device, &self.queue, &out)
    }

    /// The last frame's representative cloud depth in meters (0 where there is no cloud), at
    /// the trace resolution.
    pub fn read_cloud_depth(&self) -> Result<Vec<f32>> {
        let (_, depth) = self
            .renderer
            .march_textures()
            .ok_or_else(|| invalid_target("output", "nothing rendered yet"))?;
        let bytes = read_texture(&self.device, &self.queue, depth, 0)?;
        // RGBA32F: cloud depth, the scene distance the ray was clipped at, samples, -.
        let rgba: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(rgba.chunks_exact(4).map(|p| p[0]).collect())
    }

    /// What the last frame's march did: rays traced and density samples per ray (read back
    /// from per-ray counters the march writes).
    pub fn read_ray_stats(&self) -> Result<RayStats> {
        let (texture, layout) = self
            .renderer
            .fresh_samples()
            .ok_or_else(|| invalid_target("output", "nothing rendered yet"))?;
        let bytes = read_texture(&self.device, &self.queue, texture, 0)?;
        let texels: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        let width = texture.width();
        let (mut rays, mut samples, mut light) = (0u64, 0f64, 0f64);
        for (i, t) in texels.chunks_exact(2).enumerate() {
            let (x, y) = (i as u32 % width, i as u32 / width);
            // Texels whose grid pixel lies outside the grid were not traced.
            let gx = x * layout.block + layout.offset.0;
            let gy = y * layout.block + layout.offset.1;
            if gx < layout.grid.0 && gy < layout.grid.1 {
                rays += 1;
                samples += t[0] as f64;
                light += t[1] as f64;
            }
        }
        let per_ray = |v: f64| if rays == 0 { 0.0 } else { v / rays as f64 };
        Ok(RayStats {
            rays,
            mean_samples: per_ray(samples),
            mean_light_samples: per_ray(light),
        })
    }

    /// The cloud shadow map's texels (r front depth, g mean extinction, b optical depth,
    /// a transmittance), row-major, as the last frame of the default view left them (see
    /// [`Renderer::cloud_shadows`] for the matrix).
    pub fn read_cloud_shadows(&self) -> Result<Vec<[f32; 4]>> {
        let map = self.renderer.cloud_shadows().ok_or_else(|| {
            invalid_target(
                "output",
                "no cloud shadow map: enable settings.shadows and render a frame first",
            )
        })?;
        Ok(from_f16(&read_texture(
            &self.device,
            &self.queue,
            map.texture,
            0,
        )?))
    }

    /// The GPU's cloud density (unitless, finest noise mip) at `points` for the frame
    /// `frame` (its time, and its camera for the horizon gradient): the reference the CPU
    /// queries ([`Renderer::cloud_query`]) are tested against. Builds a pipeline per call:
    /// for tests, not frame loops.
    pub fn gpu_density(&self, frame: &FrameInputs, points: &[glam::Vec3]) -> Result<Vec<f32>> {
        let uniforms = self.renderer.march_uniforms(frame)?;
        let (device, queue, noise, weather) = self.renderer.medium();
        let out = gpu_scope(device, || {
            crate::gpu::probe::probe_density(device, queue, noise, weather, &uniforms, points)
        })??;
        self.take_errors()?;
        Ok(out)
    }

    /// One mip level of a baked noise volume, RGBA8, x fastest then y then z.
    pub fn read_noise(&self, which: NoiseVolume, mip: u32) -> Result<Vec<u8>> {
        let texture = self.renderer.noise_volume(which);
        if mip >= texture.mip_level_count() {
            return Err(invalid_target(
                "noise",
                format!(
                    "mip {mip} does not exist ({} levels)",
                    texture.mip_level_count()
                ),
            ));
        }
        read_texture(&self.device, &self.queue, texture, mip)
    }

    /// The running transition's (from, to) weather maps, texel by texel as the march reads
    /// them (x fastest): R, G, B coverage of cloud layers 1-3, A cirrus, in [0, 1]. A generated
    /// map holds multiples of 1/255 (RGBA8), the frozen blend of an interrupted transition
    /// half floats (RGBA16F).
    pub fn read_weather_maps(&self) -> Result<(WeatherMapTexels, WeatherMapTexels)> {
        let (from, to) = self.renderer.weather_maps();
        let read = |t: &wgpu::Texture| -> Result<Vec<[f32; 4]>> {
            let values = crate::query::TexelValues::read(&self.device, &self.queue, t)?;
            Ok((0..values.len()).map(|i| values.texel(i)).collect())
        };
        Ok((read(from)?, read(to)?))
    }

    /// Live wgpu objects on the owned device (all of them Nimbus's) and their GPU memory.
    pub fn live_objects(&self) -> LiveObjects {
        LiveObjects::of(&self.device)
    }

    /// The renderer.
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::noise::NoiseTextures;

    /// The base volume's two bake entry points give the same texels, byte for byte: the
    /// workgroup feature-point table is a speed-up, not another noise (noise caches baked by
    /// either load in the other).
    #[test]
    fn the_table_bake_and_the_plain_bake_agree() {
        let mut settings = Settings::default();
        settings.noise.base_size = 8;
        settings.noise.detail_size = 8;
        let h = Headless::new(settings).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
        let table = NoiseTextures::bake_base_texels(&h.device, &h.queue, "bake_base", 128, 5);
        let plain = NoiseTextures::bake_base_texels(&h.device, &h.queue, "bake_base_plain", 128, 5);
        assert_eq!(table.len(), 128 * 128 * 128 * 4);
        let differing = table.iter().zip(&plain).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{differing} bytes differ");
        // Not a constant volume: the comparison can fail.
        assert!(table.iter().any(|&b| b != table[0]));
    }
}
