//! The weather maps on the GPU: three RGBA8 textures rotating through the roles "from", "to"
//! and spare. A new weather is generated into a free texture; an interrupted transition is
//! frozen by blending "from" and "to" into the spare, which becomes the new "from".

use bytemuck::{Pod, Zeroable};

use super::compute::{compute_pipeline, dispatch, map_texture};
use crate::weather::{MapAction, Weather};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BakeParams {
    seed: u32,
    size: u32,
    _pad: [u32; 2],
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

pub(crate) struct WeatherMaps {
    textures: [wgpu::Texture; 3],
    views: [wgpu::TextureView; 3],
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
        let textures =
            [0, 1, 2].map(|i| map_texture(device, &format!("nimbus weather map {i}"), size));
        let views = [0, 1, 2].map(|i| textures[i].create_view(&Default::default()));
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

    fn generate(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        slot: usize,
        w: &Weather,
    ) {
        let mut frequency = [1u32; 4];
        let mut amount = [0.0f32; 4];
        for (i, l) in w.map.layers.iter().take(3).enumerate() {
            frequency[i] = l.frequency;
            amount[i] = l.amount;
        }
        let params = BakeParams {
            seed: w.map.seed,
            size: self.size,
            _pad: [0; 2],
            frequency,
            amount,
        };
        dispatch(
            device,
            encoder,
            &self.bake,
            Some(bytemuck::bytes_of(&params)),
            &[(1, &self.views[slot])],
            self.groups(),
        );
    }

    /// Both maps become `weather`'s (an instant change). Generated once and copied: the
    /// bake is the expensive part of a start on software rasterisers.
    fn reset(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, weather: &Weather) {
        let mut encoder = device.create_command_encoder(&Default::default());
        self.generate(device, &mut encoder, self.from, weather);
        self.copy_slot(&mut encoder, self.from, self.to);
        queue.submit([encoder.finish()]);
    }

    fn copy_slot(&self, encoder: &mut wgpu::CommandEncoder, from: usize, to: usize) {
        let size = wgpu::Extent3d {
            width: self.size,
            height: self.size,
            depth_or_array_layers: 1,
        };
        encoder.copy_texture_to_texture(
            self.textures[from].as_image_copy(),
            self.textures[to].as_image_copy(),
            size,
        );
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
        let spare = 3 - self.from - self.to;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("nimbus weather transition"),
        });
        let slots = match action {
            MapAction::KeepFrom => (self.from, self.to),
            MapAction::ToBecomesFrom => (self.to, self.from),
            MapAction::Bake(weight) => {
                self.record_blend(device, &mut encoder, weight, spare);
                // The frozen blend is the new start; the old start's texture is free.
                (spare, self.from)
            }
        };
        self.generate(device, &mut encoder, slots.1, target);
        queue.submit([encoder.finish()]);
        slots
    }

    /// Records and submits a hold (see `Timeline::hold`): `action` settles the `from` map as
    /// for a request, and the `to` slot receives a copy of it, since the held sky is that map
    /// (a frozen blend cannot be regenerated from parameters). Returns the new slots for
    /// `commit`; nothing changes until then.
    pub fn hold(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        action: MapAction,
    ) -> (usize, usize) {
        let spare = 3 - self.from - self.to;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("nimbus weather hold"),
        });
        let from = match action {
            MapAction::KeepFrom => self.from,
            MapAction::ToBecomesFrom => self.to,
            MapAction::Bake(weight) => {
                self.record_blend(device, &mut encoder, weight, spare);
                spare
            }
        };
        // Any slot but `from` takes the copy.
        let to = if from == self.to { self.from } else { self.to };
        self.copy_slot(&mut encoder, from, to);
        queue.submit([encoder.finish()]);
        (from, to)
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
