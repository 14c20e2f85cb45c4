//! Views: the per-camera state of a [`crate::Renderer`]. One renderer's noise volumes, weather
//! maps and pipelines serve every view; each view owns what belongs to one camera: its uniform
//! buffers, its trace-grid textures (sized to its viewport), its temporal history and its
//! frame counter. Split screen, stereo and reflection probes are views of one renderer.

use crate::error::{Error, Result};
use crate::gpu::composite::CompositeUniforms;
use crate::gpu::march::MarchUniforms;
use crate::gpu::temporal::{CloudImage, Target, TemporalUniforms};
use crate::settings::Settings;

/// A view of a [`crate::Renderer`]: its own camera history and trace-grid textures. Made by
/// [`crate::Renderer::create_view`]; [`ViewId::DEFAULT`] always exists and is the one
/// `prepare` / `encode` use. An id stays invalid once its view is destroyed (a generation
/// count tells a reused slot from the old view).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ViewId(u32);

impl ViewId {
    /// The view every renderer has.
    pub const DEFAULT: ViewId = ViewId(0);

    /// The id as one number (for the C API): slot in the low 16 bits, generation above.
    pub fn to_raw(self) -> u32 {
        self.0
    }

    /// The id from [`ViewId::to_raw`]. Any number is accepted here; one that names no live
    /// view is refused by the renderer's calls.
    pub fn from_raw(raw: u32) -> Self {
        Self(raw)
    }

    fn slot(self) -> usize {
        (self.0 & 0xffff) as usize
    }

    fn generation(self) -> u16 {
        (self.0 >> 16) as u16
    }
}

/// Views one renderer can hold at once (the default one included).
pub const MAX_VIEWS: usize = 64;

/// What the per-size textures depend on: viewport size, trace divisor, pattern block, temporal.
type SizeKey = ((u32, u32), u32, u32, bool);

pub(crate) struct SizedTextures {
    key: SizeKey,
    /// The trace grid: the output divided by the trace divisor.
    pub grid: (u32, u32),
    /// This frame's march: one texel per traced pixel (the grid divided by the block edge).
    pub fresh: CloudImage,
    /// The march's per-ray counters (density samples, light samples), RG32F, like `fresh`.
    pub fresh_stats: Target,
    /// The resolved grid, ping-pong (this frame's and last frame's); empty with temporal off.
    pub history: Vec<CloudImage>,
}

/// Where the last frame traced: the grid, the pattern block and this frame's offset in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TraceLayout {
    pub grid: (u32, u32),
    pub block: u32,
    pub offset: (u32, u32),
}

/// What `prepare` derived for `encode`.
#[derive(Clone, Copy)]
pub(crate) struct Pending {
    pub march: MarchUniforms,
    pub composite: CompositeUniforms,
    pub view_proj: glam::Mat4,
    pub inv_view_proj_rel: glam::Mat4,
    pub camera: glam::Vec3,
    pub near_value: f32,
    pub far_value: f32,
}

/// Temporal reprojection state between frames.
#[derive(Default)]
pub(crate) struct History {
    /// Index into `SizedTextures::history` of the last resolved grid.
    pub current: usize,
    /// The view-projection the last resolved grid was rendered with; `None`: no usable history.
    pub view_proj: Option<glam::Mat4>,
    /// Where the last frame traced (for the readback helpers).
    pub layout: Option<TraceLayout>,
    /// Whether the last frame ran the resolve pass.
    pub resolved: bool,
}

/// The state of one view.
pub(crate) struct ViewState {
    pub uniforms: wgpu::Buffer,
    pub temporal_uniforms: wgpu::Buffer,
    pub composite_uniforms: wgpu::Buffer,
    /// The ambient probe's buffers (src/gpu/ambient.rs), and where a read copies its output.
    pub ambient: crate::gpu::ambient::AmbientBuffers,
    pub ambient_readback: wgpu::Buffer,
    pub sized: Option<SizedTextures>,
    pub pending: Option<Pending>,
    pub history: History,
    pub frame_index: u32,
}

fn params_buffer<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: std::mem::size_of::<T>() as u64,
        usage: crate::gpu::compute::FRAME_PARAMS_USAGE,
        mapped_at_creation: false,
    })
}

impl ViewState {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self {
            uniforms: params_buffer::<MarchUniforms>(device, "nimbus march uniforms"),
            temporal_uniforms: params_buffer::<TemporalUniforms>(
                device,
                "nimbus temporal uniforms",
            ),
            composite_uniforms: params_buffer::<CompositeUniforms>(
                device,
                "nimbus composite uniforms",
            ),
            ambient: crate::gpu::ambient::AmbientBuffers::new(device),
            ambient_readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("nimbus ambient light readback"),
                size: crate::gpu::ambient::AMBIENT_BYTES,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            sized: None,
            pending: None,
            history: History::default(),
            frame_index: 0,
        }
    }

    /// (Re)creates the per-size textures: only when the viewport size, the trace resolution,
    /// the pattern or temporal on/off changes. New textures drop the history. Returns whether
    /// they were made anew (the caller then drops the bind groups that bound the old ones).
    pub(crate) fn ensure_size(
        &mut self,
        device: &wgpu::Device,
        settings: &Settings,
        size: (u32, u32),
    ) -> bool {
        let divisor = settings.march.resolution.divisor();
        let temporal = settings.march.temporal;
        let block = temporal.pattern.block();
        let key = (size, divisor, block, temporal.enabled);
        if self.sized.as_ref().is_some_and(|s| s.key == key) {
            return false;
        }
        let grid = (size.0.div_ceil(divisor), size.1.div_ceil(divisor));
        let sparse = (grid.0.div_ceil(block), grid.1.div_ceil(block));
        let history = if temporal.enabled {
            (0..2)
                .map(|i| CloudImage::new(device, &format!("history {i}"), grid))
                .collect()
        } else {
            Vec::new()
        };
        // The old textures go first, so a resize never holds both sets.
        self.sized = None;
        self.sized = Some(SizedTextures {
            key,
            grid,
            fresh: CloudImage::new(device, "march", sparse),
            fresh_stats: Target::new(
                device,
                "nimbus march counters",
                sparse,
                wgpu::TextureFormat::Rg32Float,
            ),
            history,
        });
        self.history = History::default();
        true
    }

    /// The uniform buffers this view's bind groups are keyed by.
    pub(crate) fn buffers(&self) -> [&wgpu::Buffer; 3] {
        [
            &self.uniforms,
            &self.temporal_uniforms,
            &self.composite_uniforms,
        ]
    }

    /// Bytes of GPU memory this view holds (trace-grid textures and uniforms).
    pub(crate) fn memory_bytes(&self, texture_bytes: impl Fn(&wgpu::Texture) -> u64) -> u64 {
        let mut total: u64 = self.buffers().iter().map(|b| b.size()).sum::<u64>()
            + self.ambient.bytes()
            + self.ambient_readback.size();
        if let Some(s) = &self.sized {
            for image in std::iter::once(&s.fresh).chain(&s.history) {
                total += texture_bytes(&image.clouds.texture) + texture_bytes(&image.depth.texture);
            }
            total += texture_bytes(&s.fresh_stats.texture);
        }
        total
    }
}

struct Slot {
    generation: u16,
    state: Option<ViewState>,
}

/// The views of one renderer, by slot; slot 0 is the default view.
pub(crate) struct Views {
    slots: Vec<Slot>,
}

fn unknown(view: ViewId) -> Error {
    Error::InvalidView(format!(
        "view {:#x} is not a live view of this renderer (destroyed, or from another one)",
        view.0
    ))
}

impl Views {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self {
            slots: vec![Slot {
                generation: 0,
                state: Some(ViewState::new(device)),
            }],
        }
    }

    pub(crate) fn get(&self, view: ViewId) -> Result<&ViewState> {
        self.slots
            .get(view.slot())
            .filter(|s| s.generation == view.generation())
            .and_then(|s| s.state.as_ref())
            .ok_or_else(|| unknown(view))
    }

    pub(crate) fn get_mut(&mut self, view: ViewId) -> Result<&mut ViewState> {
        self.slots
            .get_mut(view.slot())
            .filter(|s| s.generation == view.generation())
            .and_then(|s| s.state.as_mut())
            .ok_or_else(|| unknown(view))
    }

    pub(crate) fn create(&mut self, device: &wgpu::Device) -> Result<ViewId> {
        let free = self.slots.iter().skip(1).position(|s| s.state.is_none());
        let slot = match free {
            Some(i) => i + 1,
            None if self.slots.len() < MAX_VIEWS => {
                self.slots.push(Slot {
                    generation: 0,
                    state: None,
                });
                self.slots.len() - 1
            }
            None => {
                return Err(Error::InvalidView(format!(
                    "a renderer holds at most {MAX_VIEWS} views; destroy one first"
                )))
            }
        };
        let s = &mut self.slots[slot];
        // Generation 0 is never handed out for slots above 0, so no raw id of a made view is 0.
        s.generation = s.generation.wrapping_add(1).max(1);
        s.state = Some(ViewState::new(device));
        Ok(ViewId(((s.generation as u32) << 16) | slot as u32))
    }

    /// Removes a view, returning its state (the caller drops its bind groups).
    pub(crate) fn destroy(&mut self, view: ViewId) -> Result<ViewState> {
        if view == ViewId::DEFAULT {
            return Err(Error::InvalidView(
                "the default view cannot be destroyed".into(),
            ));
        }
        self.get(view)?;
        Ok(self.slots[view.slot()]
            .state
            .take()
            .expect("checked just above"))
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = &ViewState> {
        self.slots.iter().filter_map(|s| s.state.as_ref())
    }

    pub(crate) fn iter_mut(&mut self) -> impl Iterator<Item = &mut ViewState> {
        self.slots.iter_mut().filter_map(|s| s.state.as_mut())
    }

    pub(crate) fn len(&self) -> usize {
        self.iter().count()
    }
}
