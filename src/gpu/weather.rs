//! The weather maps on the GPU: five textures rotating through the roles "from" and "to". A
//! new weather is generated into a free one of the three RGBA8 textures, at once or a slice
//! of rows per frame (`Generation`, so that a request costs no single frame a hitch), while
//! the running transition keeps its two; an interrupted transition is frozen by blending
//! "from" and "to" into a free one of the two RGBA16F textures, which becomes the new "from".
//!
//! The frozen blend keeps 16 bits: stored in 8 (as the generated maps are, where the bake's
//! own values are what the march and the path tracer read), the blend moved each texel by up
//! to half a step, 0.002 of coverage. With sharpened cloud edges (`CloudShape::
//! edge_sharpness` 4: a remap four times as steep) that shifted cloud outlines visibly at the
//! moment of an interruption or a cancel; in half floats a texel is within 2^-11 (4.9e-4)
//! of the blend.

use bytemuck::{Pod, Zeroable};

use super::compute::{compute_pipeline, dispatch, map_texture};
use crate::weather::{MapAction, Weather};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BakeParams {
    seed: u32,
    size: u32,
    /// The first row this dispatch writes (a slice of a generation over frames).
    row_offset: u32,
    _pad: u32,
    frequency: [u32; 4],
    amount: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BlendParams {
    weight: f32,
    size: u32,
    _pad: [u32; 2],
}

/// Generated maps (RGBA8): from, to and the one a generation writes. Slots 0..BAKED.
const BAKED: usize = 3;
/// Frozen blends (RGBA16F): the one in use as from (and to, while a cancel holds it) and the
/// one a blend writes. Slots BAKED..SLOTS.
const SLOTS: usize = BAKED + 2;

/// A weather map being generated over frames: one dispatch per slice of rows, each with its
/// parameters and bind group made up front (nothing is created in the frames it runs in).
pub(crate) struct Generation {
    /// The texture it writes (free while it runs: neither from nor to).
    pub slot: usize,
    slices: Vec<(wgpu::BindGroup, [u32; 3])>,
    next: usize,
}

impl Generation {
    /// Whether every slice has been recorded.
    pub fn done(&self) -> bool {
        self.next == self.slices.len()
    }

    /// The share of the map recorded so far, in [0, 1].
    pub fn progress(&self) -> f32 {
        self.next as f32 / self.slices.len().max(1) as f32
    }
}

pub(crate) struct WeatherMaps {
    textures: [wgpu::Texture; SLOTS],
    views: [wgpu::TextureView; SLOTS],
    from: usize,
    to: usize,
    bake: wgpu::ComputePipeline,
    blend: wgpu::ComputePipeline,
    size: u32,
}

impl WeatherMaps {
    /// Creates the maps with `weather` as both "from" and "to". Submits its own work.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, size: u32, weather: &Weather) -> Self {
        let mut maps = Self::with_pipelines(
            device,
            size,
            compute_pipeline(device, "weather_bake", "bake_weather"),
            compute_pipeline(device, "weather_blend", "blend_maps"),
        );
        maps.reset(device, queue, weather);
        maps
    }

    /// New maps of `size` holding `weather` as both "from" and "to", reusing this set's
    /// pipelines; `self` is untouched, so a failure leaves it in use. Submits its own work.
    pub fn rebuilt(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        size: u32,
        weather: &Weather,
    ) -> Self {
        let mut maps = Self::with_pipelines(device, size, self.bake.clone(), self.blend.clone());
        maps.reset(device, queue, weather);
        maps
    }

    fn with_pipelines(
        device: &wgpu::Device,
        size: u32,
        bake: wgpu::ComputePipeline,
        blend: wgpu::ComputePipeline,
    ) -> Self {
        let textures = std::array::from_fn(|i| {
            let format = if i < BAKED {
                wgpu::TextureFormat::Rgba8Unorm
            } else {
                wgpu::TextureFormat::Rgba16Float
            };
            map_texture(device, &format!("nimbus weather map {i}"), size, format)
        });
        let views = std::array::from_fn(|i: usize| textures[i].create_view(&Default::default()));
        Self {
            textures,
            views,
            from: 0,
            to: 1,
            bake,
            blend,
            size,
        }
    }

    fn groups(&self) -> [u32; 3] {
        let g = self.size.div_ceil(8);
        [g, g, 1]
    }

    /// The bake parameters of `w`'s map for the rows from `row_offset` on.
    fn bake_params(&self, w: &Weather, row_offset: u32) -> BakeParams {
        let mut frequency = [1u32; 4];
        let mut amount = [0.0f32; 4];
        for (i, l) in w.map.layers.iter().take(3).enumerate() {
            frequency[i] = l.frequency;
            amount[i] = l.amount;
        }
        BakeParams {
            seed: w.map.seed,
            size: self.size,
            row_offset,
            _pad: 0,
            frequency,
            amount,
        }
    }

    fn generate(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        slot: usize,
        w: &Weather,
    ) {
        dispatch(
            device,
            encoder,
            &self.bake,
            Some(bytemuck::bytes_of(&self.bake_params(w, 0))),
            &[(1, &self.views[slot])],
            self.groups(),
        );
    }

    /// The first slot in `range` that is neither from nor to.
    fn free_in(&self, range: std::ops::Range<usize>) -> usize {
        range
            .clone()
            .find(|&i| i != self.from && i != self.to)
            .unwrap_or_else(|| unreachable!("slots {range:?}: from and to take two at most"))
    }

    /// A generated map's texture that is neither from nor to (three, two in use at most).
    fn free_baked(&self) -> usize {
        self.free_in(0..BAKED)
    }

    /// A frozen blend's texture that is neither from nor to: only "from" holds a frozen
    /// blend ("to" too while a cancel holds it, then the same slot), so one of two is free.
    fn free_frozen(&self) -> usize {
        self.free_in(BAKED..SLOTS)
    }

    /// Whether a map of this set's size takes more than one slice of `texels_per_frame`
    /// (0 = no limit): then a request generates it with [`WeatherMaps::begin_generation`].
    pub fn needs_slices(&self, texels_per_frame: u32) -> bool {
        texels_per_frame != 0 && (self.size as u64).pow(2) > texels_per_frame as u64
    }

    /// Prepares the generation of `w`'s map into a free texture in slices of about
    /// `texels_per_frame` texels (whole rows, a multiple of the 8-row workgroup), recorded
    /// one per [`WeatherMaps::record_slice`]. Makes every slice's parameters and bind group
    /// now. The textures in use are not touched.
    pub fn begin_generation(
        &self,
        device: &wgpu::Device,
        w: &Weather,
        texels_per_frame: u32,
    ) -> Generation {
        use wgpu::util::DeviceExt;
        let slot = self.free_baked();
        let rows = (texels_per_frame / self.size.max(1)).max(8) / 8 * 8;
        let layout = self.bake.get_bind_group_layout(0);
        let mut slices = Vec::new();
        let mut row = 0;
        while row < self.size {
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("nimbus weather slice params"),
                contents: bytemuck::bytes_of(&self.bake_params(w, row)),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus weather slice"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&self.views[slot]),
                    },
                ],
            });
            let count = rows.min(self.size - row);
            slices.push((bind, [self.size.div_ceil(8), count.div_ceil(8), 1]));
            row += count;
        }
        Generation {
            slot,
            slices,
            next: 0,
        }
    }

    /// Records the next slice of `generation` (nothing once it is done).
    pub fn record_slice(&self, encoder: &mut wgpu::CommandEncoder, generation: &mut Generation) {
        let Some((bind, groups)) = generation.slices.get(generation.next) else {
            return;
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("nimbus weather slice"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.bake);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
        generation.next += 1;
    }

    /// Records what the timeline decided for a request whose map `generation` has finished
    /// (recorded, in this encoder or an earlier submission), and returns the new (from, to)
    /// slots for `commit`: the generated map is the new "to".
    pub fn settle_generated(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        action: MapAction,
        generation: &Generation,
    ) -> (usize, usize) {
        let from = match action {
            MapAction::KeepFrom => self.from,
            MapAction::ToBecomesFrom => self.to,
            MapAction::Bake(weight) => {
                let frozen = self.free_frozen();
                self.record_blend(device, encoder, weight, frozen);
                frozen
            }
        };
        (from, generation.slot)
    }

    /// Both maps become `weather`'s (an instant change): one texture in both roles, generated
    /// once (the bake is the expensive part of a start on software rasterisers).
    fn reset(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, weather: &Weather) {
        let mut encoder = device.create_command_encoder(&Default::default());
        (self.from, self.to) = (0, 0);
        self.generate(device, &mut encoder, 0, weather);
        queue.submit([encoder.finish()]);
    }

    /// Records and submits what the timeline decided for a request toward `target`, and
    /// returns the new (from, to) slots. Nothing here changes until `commit` takes them, so a
    /// failed request leaves the maps as they were.
    pub fn apply(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        action: MapAction,
        target: &Weather,
    ) -> (usize, usize) {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("nimbus weather transition"),
        });
        let from = match action {
            MapAction::KeepFrom => self.from,
            MapAction::ToBecomesFrom => self.to,
            MapAction::Bake(weight) => {
                // The frozen blend is the new start.
                let frozen = self.free_frozen();
                self.record_blend(device, &mut encoder, weight, frozen);
                frozen
            }
        };
        // The target into a texture neither role holds now: the maps in use stay as they
        // are until `commit`.
        let slots = (from, self.free_baked());
        self.generate(device, &mut encoder, slots.1, target);
        queue.submit([encoder.finish()]);
        slots
    }

    /// Records and submits a hold (see `Timeline::hold`): `action` settles the `from` map as
    /// for a request, and it takes the `to` role too, since the held sky is that map (a frozen
    /// blend cannot be regenerated from parameters). Returns the new slots for `commit`;
    /// nothing changes until then.
    pub fn hold(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        action: MapAction,
    ) -> (usize, usize) {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("nimbus weather hold"),
        });
        let from = match action {
            MapAction::KeepFrom => self.from,
            MapAction::ToBecomesFrom => self.to,
            MapAction::Bake(weight) => {
                let frozen = self.free_frozen();
                self.record_blend(device, &mut encoder, weight, frozen);
                frozen
            }
        };
        queue.submit([encoder.finish()]);
        (from, from)
    }

    fn record_blend(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        weight: f32,
        into: usize,
    ) {
        let params = BlendParams {
            weight,
            size: self.size,
            _pad: [0; 2],
        };
        dispatch(
            device,
            encoder,
            &self.blend,
            Some(bytemuck::bytes_of(&params)),
            &[
                (1, &self.views[self.from]),
                (2, &self.views[self.to]),
                (3, &self.views[into]),
            ],
            self.groups(),
        );
    }

    /// Makes `slots` (from `apply`) the current (from, to) maps.
    pub fn commit(&mut self, slots: (usize, usize)) {
        (self.from, self.to) = slots;
    }

    /// Bytes held, measured per texture by `texture_bytes`.
    pub fn memory_bytes(&self, texture_bytes: impl Fn(&wgpu::Texture) -> u64) -> u64 {
        self.textures.iter().map(texture_bytes).sum()
    }

    /// (from, to) views for the march.
    pub fn views(&self) -> (&wgpu::TextureView, &wgpu::TextureView) {
        (&self.views[self.from], &self.views[self.to])
    }

    /// (from, to) textures, for readback.
    pub fn textures(&self) -> (&wgpu::Texture, &wgpu::Texture) {
        (&self.textures[self.from], &self.textures[self.to])
    }
}
