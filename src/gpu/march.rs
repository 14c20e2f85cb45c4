//! The ray-march pass: uniforms, pipelines (one per scene-depth binding variant) and the
//! per-frame dispatch writing radiance + transmittance and cloud depth.

use bytemuck::{Pod, Zeroable};
use glam::{DVec2, Mat4, Vec3};

use super::bind_cache::BindCache;
use super::compute::{
    params_entry, storage_entry, texture_entry, timed_dispatch, FramePipelineParts,
};
use super::noise::NoiseTextures;
use super::shaders::DepthKind;
use crate::frame::{CameraDerived, FrameInputs};
use crate::settings::{DebugDensity, MultipleScatteringModel, Settings};
use crate::weather::WeatherSample;

/// Layout must match `MarchUniforms` in shaders/medium.wgsl field for field.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct MarchUniforms {
    inv_view_proj_rel: [f32; 16],
    camera: [f32; 4],
    planet: [f32; 4],
    sun: [f32; 4],
    sun_color: [f32; 4],
    layer: [f32; 4],
    shape: [f32; 4],
    scales: [f32; 4],
    wind: [f32; 4],
    wind_detail: [f32; 4],
    phase: [f32; 4],
    ms: [f32; 4],
    ambient_top: [f32; 4],
    ambient_bottom: [f32; 4],
    march: [f32; 4],
    haze: [f32; 4],
    misc: [f32; 4],
    debug: [f32; 4],
    debug_sphere: [f32; 4],
    tangent_x: [f32; 4],
    tangent_z: [f32; 4],
    layer_types: [f32; 4],
    horizon: [f32; 4],
    cirrus: [f32; 4],
    skew: [f32; 4],
    grid: [f32; 4],
    pattern: [f32; 4],
    opts: [f32; 4],
    viewport: [f32; 4],
    /// Multiple-scattering model (0 single, 1 octaves, 2 delta-Eddington), phase asymmetry g,
    /// the delta-Eddington peak's narrow spread and weight (PhaseModel::beam_split).
    ms_model: [f32; 4],
    /// Light from the cloud shadow map (0/1), local light distance (m), local light steps.
    shadow_light: [f32; 4],
}

/// Where the march finds the cloud shadow map: layout must match `ShadowSampling` in
/// shaders/march.wgsl. Written by the shadow pass with each update.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(crate) struct ShadowSampling {
    pub world_to_map: [f32; 16],
    /// xy: the window's origin in map coordinates; w: 1 once the map holds an update.
    pub window: [f32; 4],
}

/// Two horizontal axes perpendicular to `up` (X and Z for +Y up).
pub(crate) fn tangent_basis(up: Vec3) -> (Vec3, Vec3) {
    let reference = if up.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
    let tz = reference.cross(up).normalize();
    (up.cross(tz), tz)
}

/// A wind displacement wrapped to one tile, so f32 keeps its precision forever. Textures are
/// sampled at p - displacement, so cloud features travel along the wind.
pub(crate) fn wrapped(offset: DVec2, tile: f32) -> [f32; 2] {
    let t = tile as f64;
    [
        (-offset.x).rem_euclid(t) as f32,
        (-offset.y).rem_euclid(t) as f32,
    ]
}

impl MarchUniforms {
    pub(crate) fn new(
        settings: &Settings,
        sample: &WeatherSample,
        frame: &FrameInputs,
        cam: &CameraDerived,
        sun_dir: Vec3,
        has_depth: bool,
    ) -> Self {
        let up = settings.planet.up.normalize();
        let (tx, tz) = tangent_basis(up);
        let s = settings;
        let (phase_params, phase_model) = s.lighting.phase.gpu_params();
        let (narrow_weight, narrow_spread) = s.lighting.phase.beam_split();
        let (debug_mode, debug, sphere) = match s.debug_density {
            DebugDensity::Off => (0.0, [0.0; 4], [0.0; 4]),
            DebugDensity::Slab {
                bottom_altitude,
                top_altitude,
                density,
            } => (1.0, [bottom_altitude, top_altitude, density, 0.0], [0.0; 4]),
            DebugDensity::Sphere {
                center,
                radius,
                density,
            } => (
                2.0,
                [0.0, 0.0, density, 0.0],
                center.extend(radius).to_array(),
            ),
        };
        let w = &sample.weather;
        let n = &s.noise;
        let weather_off = wrapped(sample.offsets.weather, n.weather_extent);
        let base_off = wrapped(sample.offsets.base, n.base_scale);
        let detail_off = wrapped(sample.offsets.detail, n.detail_scale);
        let wind_dir = w.wind.direction.normalize_or_zero();
        let skew = (tx * wind_dir.x + tz * wind_dir.y) * w.wind.skew;
        let mut types = [0.0f32; 4];
        for (i, l) in w.map.layers.iter().take(3).enumerate() {
            types[i] = l.cloud_type;
        }
        types[3] = sample.map_weight;
        let inv_fade = if s.haze.fade_distance.is_finite() {
            1.0 / s.haze.fade_distance
        } else {
            0.0
        };
        let depth = frame.camera.depth;
        let v4 = |v: Vec3, w: f32| v.extend(w).to_array();
        Self {
            inv_view_proj_rel: Mat4::to_cols_array(&cam.inv_view_proj_rel),
            camera: v4(cam.position, depth.near_value()),
            planet: v4(up, s.planet.radius),
            sun: v4(sun_dir, frame.sun.illuminance),
            sun_color: v4(frame.sun.color, depth.far_value()),
            layer: [
                w.layer.bottom_altitude,
                w.layer.top_altitude,
                w.clouds.layer_softness,
                s.march.max_distance,
            ],
            shape: [
                w.clouds.coverage,
                w.clouds.density,
                w.clouds.extinction,
                w.clouds.albedo,
            ],
            scales: [
                1.0 / n.base_scale,
                1.0 / n.detail_scale,
                1.0 / n.weather_extent,
                w.clouds.detail_strength,
            ],
            wind: [weather_off[0], weather_off[1], base_off[0], base_off[1]],
            wind_detail: [detail_off[0], detail_off[1], w.clouds.edge_sharpness, 0.0],
            phase: phase_params,
            ms: {
                let m = &s.lighting.multiple_scattering;
                // Only the octave model has more than the first (single-scattering) octave.
                let octaves = match m.model {
                    MultipleScatteringModel::Octaves => m.octaves,
                    _ => 1,
                };
                [
                    octaves as f32,
                    m.attenuation,
                    m.contribution,
                    m.eccentricity,
                ]
            },
            ambient_top: v4(w.ambient_top, s.lighting.light_distance),
            ambient_bottom: v4(w.ambient_bottom, s.lighting.light_steps as f32),
            march: [
                s.march.min_steps as f32,
                s.march.max_steps as f32,
                s.march.transmittance_cutoff,
                if s.march.jitter { 1.0 } else { 0.0 },
            ],
            haze: v4(s.haze.color, s.haze.start_distance),
            misc: [inv_fade, phase_model as f32, debug_mode, flag(has_depth)],
            debug,
            debug_sphere: sphere,
            tangent_x: v4(tx, 0.0),
            tangent_z: v4(tz, s.march.resolution.divisor() as f32),
            layer_types: types,
            horizon: [
                w.horizon.strength,
                w.horizon.start_distance,
                w.horizon.coverage,
                w.horizon.cloud_type,
            ],
            cirrus: [
                w.high_layer.coverage,
                w.high_layer.altitude,
                w.high_layer.optical_depth,
                s.lighting.light_step_growth,
            ],
            skew: v4(skew, 0.0),
            // The grid and pattern are known once the targets are: see `set_grid`. Until then
            // grid.w holds tan(fov_y / 2), from which `set_grid` derives the pixel angle.
            grid: [
                0.0,
                0.0,
                1.0,
                1.0 / frame.camera.projection.y_axis.y.abs().max(1e-6),
            ],
            pattern: [0.0; 4],
            opts: [
                flag(s.march.coarse_then_fine),
                flag(s.march.distance_steps),
                flag(s.march.noise_lod),
                flag(s.lighting.light_lod),
            ],
            // Set per frame from the targets (set_viewport).
            viewport: [0.0; 4],
            ms_model: [
                match s.lighting.multiple_scattering.model {
                    MultipleScatteringModel::SingleOnly => 0.0,
                    MultipleScatteringModel::Octaves => 1.0,
                    MultipleScatteringModel::DeltaEddington => 2.0,
                },
                // |g| < 0.98 keeps the delta scaling's 1 - g² away from 0 (a dual-lobe HG may
                // reach 0.999; no cloud phase comes near).
                s.lighting.phase.asymmetry().clamp(-0.98, 0.98),
                // The delta-Eddington peak's narrow part: its spread per scattering and its weight
                // (PhaseModel::beam_split, diffusion.wgsl's beam_light).
                narrow_spread,
                narrow_weight,
            ],
            shadow_light: [
                flag(s.shadows.enabled && s.shadows.march_light),
                s.shadows.local_distance,
                s.shadows.local_steps as f32,
                0.0,
            ],
        }
    }
}

fn flag(on: bool) -> f32 {
    if on {
        1.0
    } else {
        0.0
    }
}

impl MarchUniforms {
    /// The direction toward the sun.
    pub(crate) fn sun_dir(&self) -> Vec3 {
        Vec3::from_slice(&self.sun[..3])
    }

    /// The highest altitude (m) the medium reaches: the layer's top, or the debug medium's.
    pub(crate) fn medium_top(&self) -> f32 {
        let (up, radius) = (Vec3::from_slice(&self.planet[..3]), self.planet[3]);
        match self.misc[2] as u32 {
            1 => self.debug[1],
            2 => {
                let center = Vec3::from_slice(&self.debug_sphere[..3]);
                (center + up * radius).length() - radius + self.debug_sphere[3]
            }
            _ => self.layer[1],
        }
    }

    /// Whether the march clips rays at the scene depth (known only once targets are given).
    pub(crate) fn set_has_depth(&mut self, has_depth: bool) {
        self.misc[3] = flag(has_depth);
    }

    /// The rectangle of the scene targets this frame renders (x, y, width, height in pixels).
    pub(crate) fn set_viewport(&mut self, rect: [u32; 4]) {
        self.viewport = rect.map(|v| v as f32);
    }

    /// The trace grid (`grid` pixels), the block edge `block` of the trace pattern, and which
    /// pixel of each block this frame traces (`offset`) on its `visit`-th pass over the block.
    pub(crate) fn set_grid(
        &mut self,
        grid: (u32, u32),
        block: u32,
        offset: (u32, u32),
        visit: u32,
    ) {
        let tan_half_fov = self.grid[3];
        self.grid = [
            grid.0 as f32,
            grid.1 as f32,
            block as f32,
            // Angle one grid pixel subtends at the image center: what the noise LOD filters.
            2.0 * tan_half_fov / grid.1.max(1) as f32,
        ];
        self.pattern = [offset.0 as f32, offset.1 as f32, (visit % 4096) as f32, 0.0];
    }
}

/// The layout entries of shaders/medium.wgsl's bindings (0-5 and 9), shared by every pass
/// that sees the medium (the march, the path tracer).
pub(crate) fn medium_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    use wgpu::TextureViewDimension as D;
    let filterable = wgpu::TextureSampleType::Float { filterable: true };
    vec![
        params_entry::<MarchUniforms>(0),
        texture_entry(1, filterable, D::D3),
        texture_entry(2, filterable, D::D3),
        texture_entry(3, filterable, D::D2),
        texture_entry(4, filterable, D::D2),
        wgpu::BindGroupLayoutEntry {
            binding: 5,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        },
        texture_entry(9, filterable, D::D2),
    ]
}

/// The layout entries of the cloud shadow map the light march reads (shaders/march_ray.wgsl:
/// the map at 10, where it lies at 11), for every pass built on `march_ray`.
pub(crate) fn shadow_layout_entries() -> [wgpu::BindGroupLayoutEntry; 2] {
    [
        texture_entry(
            10,
            wgpu::TextureSampleType::Float { filterable: true },
            wgpu::TextureViewDimension::D2,
        ),
        params_entry::<ShadowSampling>(11),
    ]
}

/// The texture views the medium's bind group holds, in binding order (its cache key).
pub(crate) fn medium_views<'a>(
    noise: &'a NoiseTextures,
    weather: (&'a wgpu::TextureView, &'a wgpu::TextureView),
) -> [&'a wgpu::TextureView; 5] {
    [
        &noise.base_view,
        &noise.detail_view,
        weather.0,
        &noise.blue_noise_view,
        weather.1,
    ]
}

/// The bind-group entries of the medium's bindings (0-5 and 9).
pub(crate) fn medium_entries<'a>(
    uniforms: &'a wgpu::Buffer,
    noise: &'a NoiseTextures,
    weather: (&'a wgpu::TextureView, &'a wgpu::TextureView),
) -> Vec<wgpu::BindGroupEntry<'a>> {
    let tex = |b, v| wgpu::BindGroupEntry {
        binding: b,
        resource: wgpu::BindingResource::TextureView(v),
    };
    vec![
        wgpu::BindGroupEntry {
            binding: 0,
            resource: uniforms.as_entire_binding(),
        },
        tex(1, &noise.base_view),
        tex(2, &noise.detail_view),
        tex(3, weather.0),
        tex(4, &noise.blue_noise_view),
        wgpu::BindGroupEntry {
            binding: 5,
            resource: wgpu::BindingResource::Sampler(&noise.sampler),
        },
        tex(9, weather.1),
    ]
}

/// What a march pipeline is specialised for (the pipeline-overridable constants `MEDIUM` in
/// shaders/medium.wgsl and `SHADOW_LIGHT` in shaders/march_ray.wgsl). A software rasteriser
/// runs the body of every branch under a mask, taken or not, so a pipeline that could draw the
/// debug media or take its light from the shadow map pays for their code at every sample of
/// every frame (about 10% of a frame on lavapipe, docs/performance.md); the constants remove it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct MarchVariant {
    /// 0 the noise model, 1 the debug slab, 2 the debug sphere.
    pub medium: u32,
    /// The light march reads the cloud shadow map for the long part of its path.
    pub shadow_light: bool,
}

impl MarchVariant {
    /// The variant the frame parameters ask for: the pipeline then draws exactly what the
    /// generic one would with them.
    pub(crate) fn of(u: &MarchUniforms) -> Self {
        Self {
            medium: u.misc[2] as u32,
            shadow_light: u.shadow_light[0] > 0.5,
        }
    }

    fn constants(self) -> [(&'static str, f64); 2] {
        [
            ("MEDIUM", f64::from(self.medium)),
            ("SHADOW_LIGHT", f64::from(u32::from(self.shadow_light))),
        ]
    }
}

pub(crate) struct MarchPipeline {
    parts: FramePipelineParts,
    /// The specialisations built so far (at most the three media with and without the
    /// shadow-map light): the noise model's at creation, the others at the first frame whose
    /// settings ask for them (a settings change, never per frame).
    variants: Vec<(MarchVariant, wgpu::ComputePipeline)>,
    /// Bind groups by the views they bind; `uniforms` is the renderer's one buffer.
    pub binds: BindCache,
}

impl MarchPipeline {
    pub(crate) fn new(device: &wgpu::Device, kind: DepthKind) -> Self {
        use wgpu::TextureSampleType as S;
        use wgpu::TextureViewDimension as D;
        let depth_type = match kind {
            DepthKind::Depth => S::Depth,
            DepthKind::R32Float => S::Float { filterable: false },
        };
        let parts = FramePipelineParts::new(
            device,
            "nimbus march",
            "march",
            kind,
            &[
                medium_layout_entries().as_slice(),
                &[
                    texture_entry(6, depth_type, D::D2),
                    storage_entry(7, wgpu::TextureFormat::Rgba16Float),
                    storage_entry(8, wgpu::TextureFormat::Rgba32Float),
                    storage_entry(12, wgpu::TextureFormat::Rg32Float),
                ],
                &shadow_layout_entries(),
            ]
            .concat(),
        );
        let mut pipeline = Self {
            parts,
            variants: Vec::new(),
            binds: BindCache::default(),
        };
        pipeline.variant(
            device,
            MarchVariant {
                medium: 0,
                shadow_light: false,
            },
        );
        pipeline
    }

    /// The pipeline specialised for `variant`, built on first use.
    fn variant(&mut self, device: &wgpu::Device, variant: MarchVariant) -> &wgpu::ComputePipeline {
        let index = match self.variants.iter().position(|(v, _)| *v == variant) {
            Some(i) => i,
            None => {
                let pipeline =
                    self.parts
                        .pipeline(device, "nimbus march", "march", &variant.constants());
                self.variants.push((variant, pipeline));
                self.variants.len() - 1
            }
        };
        &self.variants[index].1
    }

    /// How many specialisations have been built.
    pub(crate) fn variant_count(&self) -> usize {
        self.variants.len()
    }

    /// Records the march dispatch over the sparse grid of `size` invocations.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        noise: &NoiseTextures,
        weather: (&wgpu::TextureView, &wgpu::TextureView),
        scene_depth: &wgpu::TextureView,
        march_out: &wgpu::TextureView,
        depth_out: &wgpu::TextureView,
        stats_out: &wgpu::TextureView,
        shadow: (&wgpu::TextureView, &wgpu::Buffer),
        size: (u32, u32),
        variant: MarchVariant,
        timer: Option<&super::timing::GpuTimer>,
    ) {
        let tex = |b, v| wgpu::BindGroupEntry {
            binding: b,
            resource: wgpu::BindingResource::TextureView(v),
        };
        let mut views = medium_views(noise, weather).to_vec();
        // The shadow buffer belongs to the shadow view's pass (or is the renderer's stand-in
        // with its stand-in view): the view alone keys it.
        views.extend([scene_depth, march_out, depth_out, stats_out, shadow.0]);
        let layout = &self.parts.layout;
        let bind = self.binds.get(uniforms, &views, || {
            let mut entries = medium_entries(uniforms, noise, weather);
            entries.extend([
                tex(6, scene_depth),
                tex(7, march_out),
                tex(8, depth_out),
                tex(10, shadow.0),
                tex(12, stats_out),
                wgpu::BindGroupEntry {
                    binding: 11,
                    resource: shadow.1.as_entire_binding(),
                },
            ]);
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus march"),
                layout,
                entries: &entries,
            })
        });
        let pipeline = self.variant(device, variant);
        timed_dispatch(
            encoder,
            "nimbus march",
            pipeline,
            &bind,
            size,
            timer,
            super::timing::Pass::March,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::pass_source;

    #[test]
    fn uniforms_match_the_wgsl_struct_size() {
        // 1 mat4 + 30 vec4 in shaders/medium.wgsl.
        assert_eq!(std::mem::size_of::<MarchUniforms>(), 64 + 30 * 16);
        let src = pass_source("march", DepthKind::Depth);
        let start = src.find("struct MarchUniforms").unwrap();
        let body = &src[start..start + src[start..].find('}').unwrap()];
        assert_eq!(body.matches(": vec4f").count(), 30);
        assert_eq!(body.matches(": mat4x4f").count(), 1);
    }

    #[test]
    fn tangent_basis_is_orthonormal() {
        for up in [
            Vec3::Y,
            Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 2.0, 3.0).normalize(),
        ] {
            let (x, z) = tangent_basis(up);
            assert!(x.dot(up).abs() < 1e-6 && z.dot(up).abs() < 1e-6 && x.dot(z).abs() < 1e-6);
            assert!((x.length() - 1.0).abs() < 1e-6 && (z.length() - 1.0).abs() < 1e-6);
        }
        assert_eq!(tangent_basis(Vec3::Y), (Vec3::X, Vec3::Z));
    }
}
