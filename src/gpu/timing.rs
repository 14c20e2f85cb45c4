//! GPU time of the march, temporal resolve, composite, cloud-shadow and ambient passes from timestamp queries (benchmarks only; never
//! in pass/fail tests). Lavapipe has timestamps, but cross-check them with wall time.

use crate::error::Result;

/// Milliseconds each pass took on the GPU in the last timed frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// The ray-march compute pass.
    pub march_ms: f64,
    /// The temporal resolve compute pass (0 with temporal reprojection off).
    pub resolve_ms: f64,
    /// The composite (upsample + blend) render pass.
    pub composite_ms: f64,
    /// The cloud shadow map's update (0 with the map off, or in frames of views other than
    /// the default one, which the map does not follow).
    pub shadow_ms: f64,
    /// The ambient probe at the view's camera (docs/frame-outputs.md).
    pub ambient_ms: f64,
}

pub(crate) struct GpuTimer {
    pub query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f32,
}

/// The timed passes; each has a begin and an end query.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Pass {
    March = 0,
    Resolve = 1,
    Composite = 2,
    Shadow = 3,
    Ambient = 4,
}

const QUERIES: u32 = 10;

impl GpuTimer {
    /// A timer, or `None` when the device lacks `TIMESTAMP_QUERY`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let size = (QUERIES as u64) * 8;
        Some(Self {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("nimbus pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: QUERIES,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nimbus timestamp resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nimbus timestamp readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            period_ns: queue.get_timestamp_period(),
        })
    }

    /// Timestamp writes (begin, end) for a pass.
    pub fn writes(&self, pass: Pass) -> (Option<u32>, Option<u32>) {
        let base = pass as u32 * 2;
        (Some(base), Some(base + 1))
    }

    /// Records copying the timestamps where `read` can map them.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.query_set, 0..QUERIES, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, None);
    }

    /// The pass times of the last submitted frame (waits for the GPU).
    pub fn read(&self, device: &wgpu::Device) -> Result<PassTimes> {
        let ticks: Vec<u64> =
            bytemuck::pod_collect_to_vec(&super::readback::map_read(device, &self.readback)?);
        let ms = |a: usize, b: usize| {
            ticks[b].saturating_sub(ticks[a]) as f64 * self.period_ns as f64 * 1e-6
        };
        Ok(PassTimes {
            march_ms: ms(0, 1),
            resolve_ms: ms(2, 3),
            composite_ms: ms(4, 5),
            shadow_ms: ms(6, 7),
            ambient_ms: ms(8, 9),
        })
    }
}
