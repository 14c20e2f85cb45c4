//! The cloud shadow map: a sun-space Beer shadow map (Hillaire 2016) of the clouds over a
//! square around the camera, for the host's ground and objects (and later the march's long
//! light path). `ShadowPlan` is the CPU side (basis, texel snapping, toroidal window, which
//! texels to update this frame), pure and tested here; `ShadowPass` records the dispatch.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4, Vec3, Vec4};

use super::bind_cache::BindCache;
use super::compute::{frame_pipeline, params_entry, storage_entry, timed_dispatch};
use super::march::{
    medium_entries, medium_layout_entries, medium_views, tangent_basis, ShadowSampling,
};
use super::noise::NoiseTextures;
use super::shaders::DepthKind;
use crate::settings::CloudShadows;

/// The map's texel format: filterable, storable, and f16 keeps front depths to a few meters
/// within ±16 km of the depth origin.
pub(crate) const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// A sun that turned by less than this (radians, 0.1°) keeps the map's basis: a time-of-day
/// system turns the sun a little every frame, and rebuilding the basis means marching every
/// texel again. Over a 10 km slant path 0.1° moves a shadow by 17 m, under a texel.
const SUN_REBUILD_ANGLE: f32 = 1.745e-3;

/// The depth origin (along the light) follows the camera in steps: a new anchor, and so a
/// full update, only when the camera moved this far (m) from the old one along the light
/// (f16 depths stay precise to a few meters). Moving less changes nothing in the map.
const REANCHOR_DISTANCE: f64 = 4_000.0;

/// Layout must match `ShadowUniforms` in shaders/shadow.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub(crate) struct ShadowUniforms {
    light_dir: [f32; 4],
    axis_u: [f32; 4],
    axis_v: [f32; 4],
    grid: [f32; 4],
    update: [f32; 4],
    previous: [f32; 4],
}

/// The map's sun-space frame, kept while the sun turns by less than `SUN_REBUILD_ANGLE`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Basis {
    /// Toward the sun, as the map was built for.
    sun: Vec3,
    /// The direction light travels (−sun) and the map's two axes, orthonormal.
    light: DVec3,
    axis_u: DVec3,
    axis_v: DVec3,
    /// Depth origin along `light` (m).
    depth_origin: f64,
    /// Each texel's ray starts where it enters the sphere at this altitude (m) on the sun's
    /// side of the map's plane: above the medium, with headroom.
    medium_top: f32,
}

/// What a frame's update needs to know of the world.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadowFrame {
    pub camera: Vec3,
    /// Toward the sun (unit).
    pub sun: Vec3,
    /// The highest altitude (m) the medium reaches.
    pub medium_top: f32,
}

/// The CPU half of the shadow map: where it is, what to update.
#[derive(Clone, Debug)]
pub(crate) struct ShadowPlan {
    settings: CloudShadows,
    basis: Option<Basis>,
    /// The window's first cell along u and v (in texels from the world origin).
    window: Option<(i64, i64)>,
    frame: u32,
    full_pending: bool,
}

impl ShadowPlan {
    pub(crate) fn new(settings: CloudShadows) -> Self {
        Self {
            settings,
            basis: None,
            window: None,
            frame: 0,
            full_pending: true,
        }
    }

    /// The next update must march every texel (settings, weather or medium replaced), in a
    /// frame built afresh: the same inputs then give the same map, whatever came before.
    pub(crate) fn invalidate(&mut self) {
        self.full_pending = true;
        self.basis = None;
    }

    fn texel(&self) -> f64 {
        self.settings.extent as f64 / self.settings.resolution as f64
    }

    /// Plans this frame's update and returns its uniforms and the world → map matrix.
    pub(crate) fn plan(&mut self, f: &ShadowFrame) -> (ShadowUniforms, Mat4) {
        let camera = f.camera.as_dvec3();
        let mut full = std::mem::take(&mut self.full_pending);
        let keep = self.basis.filter(|b| {
            b.sun.dot(f.sun) >= SUN_REBUILD_ANGLE.cos()
                && (camera.dot(b.light) - b.depth_origin).abs() < REANCHOR_DISTANCE
                && f.medium_top <= b.medium_top
        });
        let basis = match keep {
            Some(b) => b,
            None => {
                full = true;
                let light = -f.sun.normalize().as_dvec3();
                let (u, v) = tangent_basis(light.as_vec3());
                let (u, v) = (u.as_dvec3(), v.as_dvec3());
                // Headroom: a transition that raises the layer a little keeps the basis.
                let top = f.medium_top + 2_000.0;
                let b = Basis {
                    sun: f.sun.normalize(),
                    light,
                    axis_u: u,
                    axis_v: v,
                    depth_origin: (camera.dot(light) / 1_000.0).round() * 1_000.0,
                    medium_top: top,
                };
                self.basis = Some(b);
                b
            }
        };
        let n = self.settings.resolution as i64;
        let texel = self.texel();
        // Texel snapping: the window starts at a whole cell, so moving within a cell moves
        // nothing.
        let first = |axis: DVec3| (camera.dot(axis) / texel).floor() as i64 - n / 2;
        let window = (first(basis.axis_u), first(basis.axis_v));
        let shift = match self.window {
            Some(prev) if !full => (prev.0 - window.0, prev.1 - window.1),
            _ => {
                full = true;
                (0, 0)
            }
        };
        if shift.0.abs() >= n || shift.1.abs() >= n {
            full = true;
        }
        self.window = Some(window);
        let slices = self.settings.update_slices.max(1);
        let slice = self.frame % slices;
        self.frame = self.frame.wrapping_add(1);
        let wrap = |c: i64| c.rem_euclid(n);
        let uniforms = ShadowUniforms {
            light_dir: basis
                .light
                .as_vec3()
                .extend(basis.depth_origin as f32)
                .to_array(),
            axis_u: basis
                .axis_u
                .as_vec3()
                .extend((window.0 as f64 * texel) as f32)
                .to_array(),
            axis_v: basis
                .axis_v
                .as_vec3()
                .extend((window.1 as f64 * texel) as f32)
                .to_array(),
            grid: [
                n as f32,
                texel as f32,
                wrap(window.0) as f32,
                wrap(window.1) as f32,
            ],
            update: [
                slices as f32,
                slice as f32,
                if full { 1.0 } else { 0.0 },
                self.settings.steps as f32,
            ],
            previous: [
                shift.0.clamp(-n, n) as f32,
                shift.1.clamp(-n, n) as f32,
                0.0,
                basis.medium_top,
            ],
        };
        (uniforms, self.matrix(&basis, window))
    }

    /// World → map: x, y texture coordinates (sample with repeat addressing: the map is
    /// toroidal), z depth along the light (m).
    fn matrix(&self, b: &Basis, window: (i64, i64)) -> Mat4 {
        let n = self.settings.resolution as i64;
        let extent = self.settings.extent as f64;
        let texel = self.texel();
        // uv = (p·axis − first cell·texel) / extent + (first cell mod N) / N: the window's
        // first cell lands on its own texel, and the whole window spans one unit.
        let row = |axis: DVec3, first: i64| {
            let offset = -(first as f64 * texel) / extent + first.rem_euclid(n) as f64 / n as f64;
            (axis / extent).as_vec3().extend(offset as f32)
        };
        let ru = row(b.axis_u, window.0);
        let rv = row(b.axis_v, window.1);
        let rz = b.light.as_vec3().extend(-b.depth_origin as f32);
        Mat4::from_cols(ru, rv, rz, Vec4::W).transpose()
    }
}

/// The map's texture, pipeline and per-frame parameters.
pub(crate) struct ShadowPass {
    pub plan: ShadowPlan,
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    params: wgpu::Buffer,
    /// Where the march finds the map (`ShadowSampling`), written with each update.
    pub sampling: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    binds: BindCache,
    /// The last update's world → map matrix; `None` before the first update.
    pub world_to_map: Option<Mat4>,
    /// The sun the map was built for.
    pub sun: Vec3,
    /// The map coordinates of the window's first texel corner: a point is inside the square
    /// iff both of its coordinates minus these are in [0, 1).
    pub window_origin: glam::Vec2,
}

impl ShadowPass {
    pub(crate) fn new(device: &wgpu::Device, settings: CloudShadows) -> Self {
        use wgpu::TextureUsages as U;
        let texture = super::texture_2d(
            device,
            "nimbus cloud shadow map",
            (settings.resolution, settings.resolution),
            SHADOW_FORMAT,
            U::STORAGE_BINDING | U::TEXTURE_BINDING | U::COPY_SRC,
        );
        let view = texture.create_view(&Default::default());
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("nimbus shadow params"),
            size: std::mem::size_of::<ShadowUniforms>() as u64,
            usage: super::compute::FRAME_PARAMS_USAGE,
            mapped_at_creation: false,
        });
        let sampling = shadow_sampling_buffer(device);
        let (layout, pipeline) = frame_pipeline(
            device,
            "nimbus cloud shadows",
            "shadow",
            DepthKind::Depth,
            "shadow",
            &[
                medium_layout_entries().as_slice(),
                &[
                    params_entry::<ShadowUniforms>(6),
                    storage_entry(7, SHADOW_FORMAT),
                ],
            ]
            .concat(),
        );
        Self {
            plan: ShadowPlan::new(settings),
            texture,
            view,
            params,
            sampling,
            layout,
            pipeline,
            binds: BindCache::default(),
            world_to_map: None,
            sun: Vec3::ZERO,
            window_origin: glam::Vec2::ZERO,
        }
    }

    /// Whether this pass was made for `settings` (else a new one is needed).
    pub(crate) fn fits(&self, settings: &CloudShadows) -> bool {
        self.plan.settings.resolution == settings.resolution
    }

    /// Takes new settings of the same resolution: the next update marches every texel.
    pub(crate) fn retune(&mut self, settings: CloudShadows) {
        self.plan.settings = settings;
        self.plan.invalidate();
    }

    /// Records this frame's update. `uniforms` is the view's medium buffer (its camera,
    /// time and weather), already written for this frame.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        noise: &NoiseTextures,
        weather: (&wgpu::TextureView, &wgpu::TextureView),
        frame: &ShadowFrame,
        timer: Option<&super::timing::GpuTimer>,
    ) {
        let (params, matrix) = self.plan.plan(frame);
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut views = medium_views(noise, weather).to_vec();
        views.push(&self.view);
        let (layout, out, buffer) = (&self.layout, &self.view, &self.params);
        let bind = self.binds.get(uniforms, &views, || {
            let mut entries = medium_entries(uniforms, noise, weather);
            entries.extend([
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: wgpu::BindingResource::TextureView(out),
                },
            ]);
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("nimbus cloud shadows"),
                layout,
                entries: &entries,
            })
        });
        let n = self.plan.settings.resolution;
        timed_dispatch(
            encoder,
            "nimbus cloud shadows",
            &self.pipeline,
            &bind,
            (n, n),
            timer,
            super::timing::Pass::Shadow,
        );
        self.world_to_map = Some(matrix);
        self.window_origin = glam::Vec2::new(params.grid[2], params.grid[3]) / params.grid[0];
        let sampling = ShadowSampling {
            world_to_map: matrix.to_cols_array(),
            window: [self.window_origin.x, self.window_origin.y, 0.0, 1.0],
        };
        queue.write_buffer(&self.sampling, 0, bytemuck::bytes_of(&sampling));
        self.sun = self.plan.basis.map_or(frame.sun, |b| b.sun);
    }

    pub(crate) fn bind_groups_created(&self) -> u64 {
        self.binds.created()
    }

    pub(crate) fn clear_bind_groups(&mut self) {
        self.binds.clear();
    }
}

/// A `ShadowSampling` buffer (zeroed: "no map yet").
pub(crate) fn shadow_sampling_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("nimbus shadow sampling"),
        size: std::mem::size_of::<ShadowSampling>() as u64,
        usage: super::compute::FRAME_PARAMS_USAGE,
        mapped_at_creation: false,
    })
}

/// What the march binds when there is no shadow map: a 1×1 texture and a zeroed sampling
/// buffer (window.w = 0: the march ignores the map).
pub(crate) struct NoShadow {
    pub view: wgpu::TextureView,
    pub sampling: wgpu::Buffer,
}

impl NoShadow {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let view = super::texture_2d(
            device,
            "nimbus no cloud shadow map",
            (1, 1),
            SHADOW_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )
        .create_view(&Default::default());
        Self {
            view,
            sampling: shadow_sampling_buffer(device),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> CloudShadows {
        CloudShadows {
            enabled: true,
            extent: 25_600.0,
            resolution: 256,
            steps: 32,
            update_slices: 4,
            ..CloudShadows::default()
        }
    }

    fn frame(camera: Vec3, sun: Vec3) -> ShadowFrame {
        ShadowFrame {
            camera,
            sun: sun.normalize(),
            medium_top: 4_000.0,
        }
    }

    /// The texel (x, y) and depth a world point falls on, through the matrix.
    fn texel_of(m: Mat4, p: Vec3, n: u32) -> (u32, u32, f32) {
        let q = m * p.extend(1.0);
        let wrap = |c: f32| ((c.rem_euclid(1.0)) * n as f32).floor() as u32 % n;
        (wrap(q.x), wrap(q.y), q.z)
    }

    #[test]
    fn the_first_update_is_full_then_a_slice_per_frame() {
        let mut plan = ShadowPlan::new(settings());
        let f = frame(Vec3::new(10.0, 2.0, -30.0), Vec3::new(0.3, 1.0, 0.2));
        let (a, _) = plan.plan(&f);
        assert_eq!(a.update[2], 1.0);
        for i in 1..6 {
            let (b, _) = plan.plan(&f);
            assert_eq!(b.update[2], 0.0, "frame {i}");
            assert_eq!(b.update[1], (i % 4) as f32);
            assert_eq!([b.previous[0], b.previous[1]], [0.0, 0.0]);
        }
        plan.invalidate();
        assert_eq!(plan.plan(&f).0.update[2], 1.0);
    }

    #[test]
    fn moving_within_a_texel_changes_nothing_and_a_texel_shifts_the_window() {
        let mut plan = ShadowPlan::new(settings());
        let sun = Vec3::new(0.3, 1.0, 0.2);
        let texel = 100.0;
        let (a, ma) = plan.plan(&frame(Vec3::new(50.0, 0.0, 50.0), sun));
        let (mut b, mb) = plan.plan(&frame(Vec3::new(50.0 + 0.2 * texel, 0.0, 50.0), sun));
        assert_eq!(ma, mb);
        b.update = a.update;
        assert_eq!(a, b);
        // Far enough along u to cross at least one cell boundary.
        let (u, _) = tangent_basis(-sun.normalize());
        let (c, _) = plan.plan(&frame(Vec3::new(50.0, 0.0, 50.0) + u * 1.5 * texel, sun));
        assert_eq!(c.update[2], 0.0);
        assert!(c.previous[0] <= -1.0, "{:?}", c.previous);
    }

    #[test]
    fn the_matrix_puts_a_point_on_the_texel_whose_ray_passes_through_it() {
        let s = settings();
        let mut plan = ShadowPlan::new(s);
        let sun = Vec3::new(0.4, 1.0, -0.3).normalize();
        let cam = Vec3::new(1234.0, 10.0, -777.0);
        let (u, m) = plan.plan(&frame(cam, sun));
        let n = s.resolution;
        // Rebuild each texel's plane point as the shader does, and check the matrix maps it
        // (and any point along its ray) back onto the texel.
        for (x, y) in [(0u32, 0u32), (17, 200), (255, 255), (128, 3)] {
            let j = |c: u32, first_mod: f32| {
                ((c + n) as i64 - first_mod as i64).rem_euclid(n as i64) as f32
            };
            let (jx, jy) = (j(x, u.grid[2]), j(y, u.grid[3]));
            let axis =
                |a: [f32; 4], jj: f32| Vec3::from_slice(&a[..3]) * (a[3] + (jj + 0.5) * u.grid[1]);
            let light = Vec3::from_slice(&u.light_dir[..3]);
            let plane = axis(u.axis_u, jx) + axis(u.axis_v, jy) + light * u.light_dir[3];
            for along in [-3000.0, 0.0, 2500.0] {
                let (tx, ty, depth) = texel_of(m, plane + light * along, n);
                assert_eq!((tx, ty), (x, y), "along {along}");
                assert!((depth - along).abs() < 0.5, "{depth} vs {along}");
            }
        }
        // The camera sits at the window's center.
        let q = m * cam.extend(1.0);
        let first = Vec2f::new(u.grid[2], u.grid[3]) / n as f32;
        let centre = Vec2f::new(q.x, q.y) - first;
        assert!(
            (centre - Vec2f::splat(0.5)).abs().max_element() < 1.5 / n as f32,
            "{centre}"
        );
    }

    type Vec2f = glam::Vec2;

    #[test]
    fn a_small_turn_of_the_sun_keeps_the_basis_a_large_one_rebuilds_it() {
        let mut plan = ShadowPlan::new(settings());
        let cam = Vec3::new(0.0, 5.0, 0.0);
        let sun = Vec3::new(0.3, 1.0, 0.2).normalize();
        plan.plan(&frame(cam, sun));
        let small = (sun + Vec3::new(1e-4, 0.0, 0.0)).normalize();
        assert_eq!(plan.plan(&frame(cam, small)).0.update[2], 0.0);
        let large = (sun + Vec3::new(0.05, 0.0, 0.0)).normalize();
        let (u, _) = plan.plan(&frame(cam, large));
        assert_eq!(u.update[2], 1.0);
        assert!((Vec3::from_slice(&u.light_dir[..3]) + large).length() < 1e-5);
    }
}
