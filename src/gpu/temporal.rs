//! The temporal resolve pass: rebuilds the full trace grid from this frame's sparse march and
//! last frame's resolved grid (shaders/temporal.wgsl), plus the ping-pong history it owns.

use super::bind_cache::BindCache;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use super::compute::{frame_pipeline, params_entry, storage_entry, texture_entry, timed_dispatch};
use super::shaders::DepthKind;

/// Layout must match `TemporalUniforms` in shaders/temporal.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct TemporalUniforms {
    inv_view_proj_rel: [f32; 16],
    prev_view_proj: [f32; 16],
    camera: [f32; 4],
    grid: [f32; 4],
    pattern: [f32; 4],
    misc: [f32; 4],
    viewport: [f32; 4],
}

/// What the resolve of one frame needs to know.
pub(crate) struct ResolveFrame {
    /// NDC to positions relative to the camera (`CameraDerived::inv_view_proj_rel`).
    pub inv_view_proj_rel: Mat4,
    /// The view-projection the history was rendered with; `None` when there is no usable
    /// history (first frame, reset, resize, new settings).
    pub prev_view_proj: Option<Mat4>,
    pub camera: Vec3,
    pub near_value: f32,
    pub far_value: f32,
    pub grid: (u32, u32),
    pub block: u32,
    pub offset: (u32, u32),
    pub divisor: u32,
    pub max_samples: u32,
    pub has_depth: bool,
    pub max_distance: f32,
    /// The rectangle of the scene depth rendered (x, y, width, height).
    pub viewport: [u32; 4],
}

impl TemporalUniforms {
    pub(crate) fn new(f: &ResolveFrame) -> Self {
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        Self {
            inv_view_proj_rel: f.inv_view_proj_rel.to_cols_array(),
            prev_view_proj: f.prev_view_proj.unwrap_or(Mat4::IDENTITY).to_cols_array(),
            camera: f.camera.extend(f.near_value).to_array(),
            grid: [
                f.grid.0 as f32,
                f.grid.1 as f32,
                f.block as f32,
                f.divisor as f32,
            ],
            pattern: [
                f.offset.0 as f32,
                f.offset.1 as f32,
                flag(f.prev_view_proj.is_some()),
                f.max_samples as f32,
            ],
            misc: [flag(f.has_depth), f.far_value, f.max_distance, 0.0],
            viewport: f.viewport.map(|v| v as f32),
        }
    }
}

/// A texture and its full view.
pub(crate) struct Target {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl Target {
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        size: (u32, u32),
        format: wgpu::TextureFormat,
    ) -> Self {
        use wgpu::TextureUsages as U;
        let usage = U::STORAGE_BINDING | U::TEXTURE_BINDING | U::COPY_SRC;
        let texture = super::texture_2d(device, label, size, format, usage);
        let view = texture.create_view(&Default::default());
        Self { texture, view }
    }
}

/// A resolved grid: (L, T) in RGBA16F and (cloud depth, scene distance, samples) in RGBA32F.
pub(crate) struct CloudImage {
    pub clouds: Target,
    pub depth: Target,
}

impl CloudImage {
    pub(crate) fn new(device: &wgpu::Device, label: &str, size: (u32, u32)) -> Self {
        Self {
            clouds: Target::new(
                device,
                &format!("nimbus {label} (L, T)"),
                size,
                wgpu::TextureFormat::Rgba16Float,
            ),
            depth: Target::new(
                device,
                &format!("nimbus {label} depth"),
                size,
                wgpu::TextureFormat::Rgba32Float,
            ),
        }
    }
}

pub(crate) struct TemporalPipeline {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// Bind groups by the views they bind (the history ping-pong gives two per target set).
    pub binds: BindCache,
}

impl TemporalPipeline {
    pub(crate) fn new(device: &wgpu::Device, kind: DepthKind) -> Self {
        use wgpu::TextureSampleType as S;
        let texture = |binding, sample_type| {
            texture_entry(binding, sample_type, wgpu::TextureViewDimension::D2)
        };
        let unfiltered = S::Float { filterable: false };
        let (layout, pipeline) = frame_pipeline(
            device,
            "nimbus temporal",
            "temporal",
            kind,
            "resolve",
            &[
                params_entry::<TemporalUniforms>(0),
                texture(1, unfiltered),
                texture(2, unfiltered),
                texture(3, unfiltered),
                texture(4, unfiltered),
                texture(
                    5,
                    match kind {
                        DepthKind::Depth => S::Depth,
                        DepthKind::R32Float => unfiltered,
                    },
                ),
                storage_entry(6, wgpu::TextureFormat::Rgba16Float),
                storage_entry(7, wgpu::TextureFormat::Rgba32Float),
            ],
        );
        Self {
            layout,
            pipeline,
            binds: BindCache::default(),
        }
    }

    /// Records the resolve of `fresh` and `history` into `out` over a `grid`-sized dispatch.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        fresh: &CloudImage,
        history: &CloudImage,
        scene_depth: &wgpu::TextureView,
        out: &CloudImage,
        grid: (u32, u32),
        timer: Option<&super::timing::GpuTimer>,
    ) {
        let tex = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let views = [
            &fresh.clouds.view,
            &fresh.depth.view,
            &history.clouds.view,
            &history.depth.view,
            scene_depth,
            &out.clouds.view,
            &out.depth.view,
        ];
        let layout = &self.layout;
        let bind = self.binds.get(uniforms, &views, || {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus temporal"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniforms.as_entire_binding(),
                    },
                    tex(1, &fresh.clouds.view),
                    tex(2, &fresh.depth.view),
                    tex(3, &history.clouds.view),
                    tex(4, &history.depth.view),
                    tex(5, scene_depth),
                    tex(6, &out.clouds.view),
                    tex(7, &out.depth.view),
                ],
            })
        });
        timed_dispatch(
            encoder,
            "nimbus temporal",
            &self.pipeline,
            &bind,
            grid,
            timer,
            super::timing::Pass::Resolve,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::pass_source;

    #[test]
    fn uniforms_match_the_wgsl_struct_size() {
        assert_eq!(std::mem::size_of::<TemporalUniforms>(), 2 * 64 + 5 * 16);
        let src = pass_source("temporal", DepthKind::Depth);
        let start = src.find("struct TemporalUniforms").unwrap();
        let body = &src[start..start + src[start..].find('}').unwrap()];
        assert_eq!(body.matches(": vec4f").count(), 5);
        assert_eq!(body.matches(": mat4x4f").count(), 2);
    }
}
