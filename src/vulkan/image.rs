//! The host's images, wrapped for one frame of Nimbus's work on its queue.
//!
//! Wrappers (wgpu textures on the host's `VkImage`s, with their views) are kept between frames,
//! so nothing is created per frame while the host hands in the same images in the same layouts:
//! the host calls [`HostFrame::release`] before it destroys an image it handed in.

use ash::vk;
use wgpu::hal::vulkan as hv;
use wgpu::TextureFormat as F;

use crate::error::{Error, Result};
use crate::frame::FrameInputs;
use crate::renderer::{ColorTargets, Renderer, Targets};

/// What an image is to Nimbus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageRole {
    /// The scene color: the clouds are composited into it in place.
    Color,
    /// The scene depth, read through its depth aspect.
    Depth,
}

impl ImageRole {
    fn field(self) -> &'static str {
        match self {
            ImageRole::Color => "color",
            ImageRole::Depth => "depth",
        }
    }
}

/// One of the host's images as it hands it in for a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostImage {
    /// The `VkImage` (2D, one sample).
    pub image: vk::Image,
    /// Its format.
    pub format: vk::Format,
    /// Width of mip 0.
    pub width: u32,
    /// Height of mip 0.
    pub height: u32,
    /// Its mip count (0 counts as 1).
    pub mip_levels: u32,
    /// Its layer count (0 counts as 1).
    pub array_layers: u32,
    /// The mip Nimbus uses (below `mip_levels`); its size is mip 0's halved per level, at
    /// least 1. Color and depth are compared at their used mips.
    pub mip_level: u32,
    /// The layer Nimbus uses.
    pub array_layer: u32,
    /// The usage flags it was created with.
    pub usage: vk::ImageUsageFlags,
    /// The layout of the used mip and layer when Nimbus's work runs.
    pub layout: vk::ImageLayout,
    /// The layout to leave them in; `UNDEFINED`: the same as `layout`.
    pub final_layout: vk::ImageLayout,
}

/// A semaphore to wait on before Nimbus's work, or to signal after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Semaphore {
    /// The `VkSemaphore`.
    pub semaphore: vk::Semaphore,
    /// `Some(value)`: a timeline semaphore and the value; `None`: a binary semaphore.
    pub value: Option<u64>,
    /// For waits: the stages the wait blocks (empty: all commands). Ignored for signals.
    pub stage: vk::PipelineStageFlags,
}

/// The layouts Nimbus accepts, entry and final, per role, with the usage each one needs the
/// image to have and the wgpu state it is to wgpu.
pub const ACCEPTED_LAYOUTS: &[(ImageRole, vk::ImageLayout, vk::ImageUsageFlags)] = &[
    (
        ImageRole::Color,
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        vk::ImageUsageFlags::COLOR_ATTACHMENT,
    ),
    (
        ImageRole::Color,
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        vk::ImageUsageFlags::SAMPLED,
    ),
    (
        ImageRole::Color,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        vk::ImageUsageFlags::TRANSFER_SRC,
    ),
    (
        ImageRole::Color,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::ImageUsageFlags::TRANSFER_DST,
    ),
    (
        ImageRole::Depth,
        vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
    ),
    (
        ImageRole::Depth,
        vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
        vk::ImageUsageFlags::SAMPLED,
    ),
    (
        ImageRole::Depth,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        vk::ImageUsageFlags::TRANSFER_SRC,
    ),
    (
        ImageRole::Depth,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::ImageUsageFlags::TRANSFER_DST,
    ),
    // Layouts wgpu has no state for: Nimbus moves the image between them and a stand-in
    // (`wgpu_layout`) with barriers of its own at the start and end of its work.
    (
        ImageRole::Color,
        vk::ImageLayout::PRESENT_SRC_KHR,
        vk::ImageUsageFlags::empty(),
    ),
    (
        ImageRole::Color,
        vk::ImageLayout::GENERAL,
        vk::ImageUsageFlags::empty(),
    ),
    (
        ImageRole::Depth,
        vk::ImageLayout::GENERAL,
        vk::ImageUsageFlags::empty(),
    ),
];

/// The layout wgpu is told the image is in for a host layout: the layout itself, or for the
/// layouts wgpu has no state for (PRESENT_SRC_KHR, GENERAL) the one Nimbus uses the image in,
/// which Nimbus's own first and last barriers move it from and to.
fn wgpu_layout(role: ImageRole, layout: vk::ImageLayout) -> vk::ImageLayout {
    match (role, layout) {
        (ImageRole::Color, vk::ImageLayout::PRESENT_SRC_KHR | vk::ImageLayout::GENERAL) => {
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
        }
        (ImageRole::Depth, vk::ImageLayout::GENERAL) => {
            vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
        }
        _ => layout,
    }
}

/// The wgpu state of a layout (wgpu-hal's `derive_image_layout`, inverted).
fn state_of(layout: vk::ImageLayout) -> wgpu::TextureUses {
    match layout {
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL => wgpu::TextureUses::COLOR_TARGET,
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL => wgpu::TextureUses::RESOURCE,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL => wgpu::TextureUses::COPY_SRC,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL => wgpu::TextureUses::COPY_DST,
        vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL => wgpu::TextureUses::DEPTH_STENCIL_WRITE,
        // A sampled depth image: wgpu keeps it in DEPTH_STENCIL_READ_ONLY_OPTIMAL, so this is
        // the state Nimbus reads depth in and no transition is needed.
        vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL => wgpu::TextureUses::RESOURCE,
        // Only accepted layouts reach here (check_image).
        _ => wgpu::TextureUses::UNINITIALIZED,
    }
}

const COLOR_NAMES: &str =
    "VK_FORMAT_R8G8B8A8_UNORM, R8G8B8A8_SRGB, B8G8R8A8_UNORM, B8G8R8A8_SRGB, \
     A2B10G10R10_UNORM_PACK32, B10G11R11_UFLOAT_PACK32, R16G16B16A16_SFLOAT";
const DEPTH_NAMES: &str = "VK_FORMAT_D32_SFLOAT, D24_UNORM_S8_UINT, D32_SFLOAT_S8_UINT, D16_UNORM";

/// The Vulkan formats Nimbus takes, per role, as wgpu formats.
const FORMATS: &[(vk::Format, F, ImageRole)] = &[
    (vk::Format::R8G8B8A8_UNORM, F::Rgba8Unorm, ImageRole::Color),
    (
        vk::Format::R8G8B8A8_SRGB,
        F::Rgba8UnormSrgb,
        ImageRole::Color,
    ),
    (vk::Format::B8G8R8A8_UNORM, F::Bgra8Unorm, ImageRole::Color),
    (
        vk::Format::B8G8R8A8_SRGB,
        F::Bgra8UnormSrgb,
        ImageRole::Color,
    ),
    (
        vk::Format::A2B10G10R10_UNORM_PACK32,
        F::Rgb10a2Unorm,
        ImageRole::Color,
    ),
    (
        vk::Format::B10G11R11_UFLOAT_PACK32,
        F::Rg11b10Ufloat,
        ImageRole::Color,
    ),
    (
        vk::Format::R16G16B16A16_SFLOAT,
        F::Rgba16Float,
        ImageRole::Color,
    ),
    (vk::Format::D32_SFLOAT, F::Depth32Float, ImageRole::Depth),
    (
        vk::Format::D24_UNORM_S8_UINT,
        F::Depth24PlusStencil8,
        ImageRole::Depth,
    ),
    (
        vk::Format::D32_SFLOAT_S8_UINT,
        F::Depth32FloatStencil8,
        ImageRole::Depth,
    ),
    (vk::Format::D16_UNORM, F::Depth16Unorm, ImageRole::Depth),
];

fn layout_name(layout: vk::ImageLayout) -> String {
    let name = format!("{layout:?}");
    if name.chars().all(|c| c.is_ascii_digit()) {
        format!("VkImageLayout {name}")
    } else {
        format!("VK_IMAGE_LAYOUT_{name}")
    }
}

fn bad(role: ImageRole, reason: String) -> Error {
    Error::InvalidTarget {
        target: role.field(),
        reason,
    }
}

/// A wrapper kept between frames.
struct Wrapped {
    key: (ImageRole, HostImageShape),
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// The layout wgpu believes the image is in (where the last frame left it).
    layout: vk::ImageLayout,
    last_used: u64,
}

/// What a wrapper depends on: the image and everything its wgpu texture was made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct HostImageShape {
    image: vk::Image,
    format: vk::Format,
    size: (u32, u32, u32, u32),
    mip_level: u32,
    array_layer: u32,
    usage: vk::ImageUsageFlags,
}

/// A layout transition Nimbus records itself (to or from a layout wgpu has no state for).
struct LayoutMove {
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: vk::ImageLayout,
    to: vk::ImageLayout,
}

/// The used mip and layer of an image, with every aspect of its format (a layout
/// transition of a depth-stencil image covers both aspects).
fn subresource(role: ImageRole, image: &HostImage) -> vk::ImageSubresourceRange {
    let aspect = match (role, image.format) {
        (ImageRole::Color, _) => vk::ImageAspectFlags::COLOR,
        (_, vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT) => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::DEPTH,
    };
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: image.mip_level,
        level_count: 1,
        base_array_layer: image.array_layer,
        layer_count: 1,
    }
}

/// The size of the mip an image is used at.
fn used_size(image: &HostImage) -> (u32, u32) {
    let at = |side: u32| (side >> image.mip_level.min(31)).max(1);
    (at(image.width), at(image.height))
}

/// Wrappers kept at most: two images a frame, a few frames in flight, with room to spare.
const MAX_WRAPPERS: usize = 8;

/// Nimbus's per-frame work on the host's images and queue.
pub struct HostFrame {
    device: wgpu::Device,
    queue: wgpu::Queue,
    raw: ash::Device,
    /// Formats this device takes (D24S8 only where wgpu maps it to D24_UNORM_S8_UINT, the
    /// feature-gated ones only with their feature).
    formats: Vec<(vk::Format, F, ImageRole)>,
    wrappers: Vec<Wrapped>,
    frame: u64,
    wraps_created: u64,
    /// CPU time of the last frame's hand-off: checks, wrapping, final transitions, barrier
    /// buffers and semaphores (everything but the renderer's own work and the submit).
    last_handoff: std::time::Duration,
}

impl HostFrame {
    /// Per-frame state for a renderer on an adopted device (see [`super::adopt_device`]).
    pub fn new(adopted: &super::AdoptedDevice) -> Result<Self> {
        // SAFETY: only the raw handles are read, and the device outlives this (its clone is kept).
        let hal_device = unsafe { adopted.device.as_hal::<hv::Api>() }
            .ok_or_else(|| Error::Vulkan("the device is not a Vulkan device".into()))?;
        let raw = hal_device.raw_device().clone();
        drop(hal_device);
        // SAFETY: as above, for the adapter.
        let d24 = unsafe { adopted.adapter.as_hal::<hv::Api>() }
            .map(|a| a.texture_format_as_raw(F::Depth24PlusStencil8));
        let features = adopted.device.features();
        let formats = FORMATS
            .iter()
            .copied()
            .filter(|(vkf, wf, _)| match wf {
                F::Depth24PlusStencil8 => d24 == Some(*vkf),
                F::Depth32FloatStencil8 => features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8),
                F::Rg11b10Ufloat => features.contains(wgpu::Features::RG11B10UFLOAT_RENDERABLE),
                _ => true,
            })
            .collect();
        Ok(Self {
            device: adopted.device.clone(),
            queue: adopted.queue.clone(),
            raw,
            formats,
            wrappers: Vec::new(),
            frame: 0,
            wraps_created: 0,
            last_handoff: std::time::Duration::ZERO,
        })
    }

    /// How many wgpu textures were made on host images so far (for the no-per-frame tests).
    pub fn wraps_created(&self) -> u64 {
        self.wraps_created
    }

    /// The CPU time the last [`HostFrame::render`] spent on the hand-off itself: checking and
    /// wrapping the images, their final transitions, the two barrier command buffers and the
    /// semaphores; the renderer's encoding and the submit are not in it (for benchmarks).
    pub fn last_handoff_time(&self) -> std::time::Duration {
        self.last_handoff
    }

    /// Checks one image against its role: format, usage, layouts, size, mip and layer.
    pub fn check_image(&self, role: ImageRole, image: &HostImage) -> Result<F> {
        let field = role.field();
        if image.image == vk::Image::null() {
            return Err(bad(role, "has a null VkImage".into()));
        }
        let format =
            match self.formats.iter().find(|f| f.0 == image.format) {
                Some(&(_, wf, r)) if r == role => wf,
                Some(_) => {
                    let other = if role == ImageRole::Color {
                        "a depth"
                    } else {
                        "a color"
                    };
                    return Err(bad(
                        role,
                        format!(
                            "has format {:?}, {other} format: `{field}` needs one of {}",
                            image.format,
                            if role == ImageRole::Color {
                                COLOR_NAMES
                            } else {
                                DEPTH_NAMES
                            }
                        ),
                    ));
                }
                None => {
                    return Err(bad(
                        role,
                        format!(
                        "has unsupported format {:?} (VkFormat {}); supported on this device: {}",
                        image.format,
                        image.format.as_raw(),
                        if role == ImageRole::Color { COLOR_NAMES } else { DEPTH_NAMES }
                    ),
                    ))
                }
            };
        if image.width == 0 || image.height == 0 || image.width > 16384 || image.height > 16384 {
            return Err(bad(
                role,
                format!(
                    "has size {}x{}: each side must be 1..=16384",
                    image.width, image.height
                ),
            ));
        }
        let mips = image.mip_levels.max(1);
        let layers = image.array_layers.max(1);
        if image.mip_level >= mips || mips > 15 {
            return Err(bad(
                role,
                format!(
                    "mip_level {} is out of range of {mips} mip level(s) (at most 15)",
                    image.mip_level
                ),
            ));
        }
        if image.array_layer >= layers || layers > 2048 {
            return Err(bad(
                role,
                format!(
                    "array_layer {} is out of range of {layers} layer(s) (at most 2048)",
                    image.array_layer
                ),
            ));
        }
        let needed = match role {
            ImageRole::Color => vk::ImageUsageFlags::COLOR_ATTACHMENT,
            ImageRole::Depth => vk::ImageUsageFlags::SAMPLED,
        };
        if !image.usage.contains(needed) {
            return Err(bad(
                role,
                format!(
                    "usage {:?} lacks {needed:?}, which Nimbus needs for `{field}`",
                    image.usage
                ),
            ));
        }
        for (what, layout) in [
            ("layout", image.layout),
            ("final_layout", final_layout(image)),
        ] {
            let Some(&(_, _, usage)) = ACCEPTED_LAYOUTS
                .iter()
                .find(|(r, l, _)| *r == role && *l == layout)
            else {
                let accepted: Vec<String> = ACCEPTED_LAYOUTS
                    .iter()
                    .filter(|(r, _, _)| *r == role)
                    .map(|(_, l, _)| layout_name(*l))
                    .collect();
                return Err(bad(
                    role,
                    format!(
                        "{what} {} is not accepted for `{field}`; accepted: {}",
                        layout_name(layout),
                        accepted.join(", ")
                    ),
                ));
            };
            if !image.usage.contains(usage) {
                return Err(bad(
                    role,
                    format!(
                        "{what} {} needs usage {usage:?}, which the image lacks (usage {:?})",
                        layout_name(layout),
                        image.usage
                    ),
                ));
            }
        }
        Ok(format)
    }

    /// The wrapper of `image`, kept from an earlier frame when wgpu's idea of its layout is
    /// right, else made anew.
    fn wrap(&mut self, role: ImageRole, image: &HostImage, format: F) -> usize {
        let shape = HostImageShape {
            image: image.image,
            format: image.format,
            size: (
                image.width,
                image.height,
                image.mip_levels.max(1),
                image.array_layers.max(1),
            ),
            mip_level: image.mip_level,
            array_layer: image.array_layer,
            usage: image.usage,
        };
        let key = (role, shape);
        let slot = match self.wrappers.iter().position(|w| w.key == key) {
            Some(i) if self.wrappers[i].layout == wgpu_layout(role, image.layout) => {
                self.wrappers[i].last_used = self.frame;
                return i;
            }
            // wgpu would transition from where it last left the image: wrap it afresh.
            Some(i) => Some(i),
            None if self.wrappers.len() >= MAX_WRAPPERS => (0..self.wrappers.len())
                .filter(|&i| self.wrappers[i].last_used != self.frame)
                .min_by_key(|&i| self.wrappers[i].last_used),
            None => None,
        };
        let mut usage = wgpu::TextureUsages::empty();
        let mut hal_usage = wgpu::TextureUses::empty();
        for (flag, u, h) in [
            (
                vk::ImageUsageFlags::TRANSFER_SRC,
                wgpu::TextureUsages::COPY_SRC,
                wgpu::TextureUses::COPY_SRC,
            ),
            (
                vk::ImageUsageFlags::TRANSFER_DST,
                wgpu::TextureUsages::COPY_DST,
                wgpu::TextureUses::COPY_DST,
            ),
            (
                vk::ImageUsageFlags::SAMPLED,
                wgpu::TextureUsages::TEXTURE_BINDING,
                wgpu::TextureUses::RESOURCE,
            ),
            (
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
                wgpu::TextureUses::COLOR_TARGET,
            ),
            (
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
                wgpu::TextureUses::DEPTH_STENCIL_READ | wgpu::TextureUses::DEPTH_STENCIL_WRITE,
            ),
        ] {
            if image.usage.contains(flag) {
                usage |= u;
                hal_usage |= h;
            }
        }
        let size = wgpu::Extent3d {
            width: image.width,
            height: image.height,
            depth_or_array_layers: shape.size.3,
        };
        // No label: wgpu-hal would rename the host's image with it.
        let hal_desc = wgpu::hal::TextureDescriptor {
            label: None,
            size,
            mip_level_count: shape.size.2,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: hal_usage,
            memory_flags: wgpu::hal::MemoryFlags::empty(),
            view_formats: Vec::new(),
        };
        // SAFETY: the host promises (nimbus_context_render_vulkan's contract) that the image was
        // created as described; the drop callback keeps wgpu-hal from destroying it, and
        // `External` from freeing its memory.
        let texture = unsafe {
            let hal_device = self
                .device
                .as_hal::<hv::Api>()
                .expect("HostFrame::new checked the backend");
            let raw = hal_device.texture_from_raw(
                image.image,
                &hal_desc,
                Some(Box::new(|| ())),
                hv::TextureMemory::External,
            );
            drop(hal_device);
            self.device.create_texture_from_hal::<hv::Api>(
                raw,
                &wgpu::TextureDescriptor {
                    label: None,
                    size,
                    mip_level_count: shape.size.2,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                },
                state_of(wgpu_layout(role, image.layout)),
            )
        };
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            aspect: match role {
                ImageRole::Color => wgpu::TextureAspect::All,
                ImageRole::Depth => wgpu::TextureAspect::DepthOnly,
            },
            base_mip_level: image.mip_level,
            mip_level_count: Some(1),
            base_array_layer: image.array_layer,
            array_layer_count: Some(1),
            ..Default::default()
        });
        self.wraps_created += 1;
        let wrapped = Wrapped {
            key,
            texture,
            view,
            layout: wgpu_layout(role, image.layout),
            last_used: self.frame,
        };
        match slot {
            Some(i) => {
                self.wrappers[i] = wrapped;
                i
            }
            None => {
                self.wrappers.push(wrapped);
                self.wrappers.len() - 1
            }
        }
    }

    /// A command buffer holding one global memory barrier, ALL_COMMANDS / MEMORY_WRITE to
    /// ALL_COMMANDS / MEMORY_READ | MEMORY_WRITE: it orders Nimbus's work after everything
    /// submitted before it on the queue, and everything after it behind Nimbus's work. With
    /// it, the layout transitions wgpu cannot make (`layouts`: image, subresource, from, to).
    fn global_barrier(&self, layouts: &[LayoutMove]) -> wgpu::CommandBuffer {
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let barrier = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE);
        let images: Vec<vk::ImageMemoryBarrier> = layouts
            .iter()
            .map(|m| {
                vk::ImageMemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
                    .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
                    .old_layout(m.from)
                    .new_layout(m.to)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(m.image)
                    .subresource_range(m.range)
            })
            .collect();
        // SAFETY: plain barriers recorded into the open raw command buffer of an encoder that
        // records nothing else (wgpu forbids mixing raw and wgpu encoding in one encoder).
        unsafe {
            encoder.as_hal_mut::<hv::Api, _, _>(|e| {
                if let Some(e) = e {
                    self.raw.cmd_pipeline_barrier(
                        e.raw_handle(),
                        vk::PipelineStageFlags::ALL_COMMANDS,
                        vk::PipelineStageFlags::ALL_COMMANDS,
                        vk::DependencyFlags::empty(),
                        &[barrier],
                        &[],
                        &images,
                    );
                }
            })
        };
        encoder.finish()
    }

    /// Validates the images, composites the clouds of `view` into `color` in place (reading
    /// `depth`; in `viewport` only, when given),
    /// leaves both in their final layouts and submits on the host's queue, waiting on and
    /// signalling the given semaphores. Nothing is submitted when a check fails. The cloud
    /// shadow map, when there is one, is left in [`super::SHADOW_MAP_LAYOUT`].
    ///
    /// # Safety
    ///
    /// the images must be live and created as described, in the layouts described
    /// when the work runs, and stay alive until it has finished; the semaphores must be live;
    /// the cloud shadow map's image, if the host used it, must be back in
    /// [`super::SHADOW_MAP_LAYOUT`] when the work runs.
    pub unsafe fn render(
        &mut self,
        renderer: &mut Renderer,
        view: crate::ViewId,
        frame: &FrameInputs,
        (color, depth, viewport): (&HostImage, Option<&HostImage>, Option<crate::Viewport>),
        waits: &[Semaphore],
        signals: &[Semaphore],
    ) -> Result<()> {
        let started = std::time::Instant::now();
        let color_format = self.check_image(ImageRole::Color, color)?;
        let depth_format = match depth {
            Some(d) => Some(self.check_image(ImageRole::Depth, d)?),
            None => None,
        };
        if let Some(d) = depth {
            let (ds, cs) = (used_size(d), used_size(color));
            if ds != cs {
                return Err(bad(
                    ImageRole::Depth,
                    format!(
                        "has size {}x{} at mip {} but color is {}x{} at mip {}: the used mips \
                         must have one size",
                        ds.0, ds.1, d.mip_level, cs.0, cs.1, color.mip_level
                    ),
                ));
            }
        }
        for s in waits.iter().chain(signals) {
            if s.semaphore == vk::Semaphore::null() {
                return Err(Error::InvalidTarget {
                    target: "semaphores",
                    reason: "a semaphore is null".into(),
                });
            }
        }
        let mut handoff = started.elapsed();
        renderer.prepare_view(view, frame)?;
        let started = std::time::Instant::now();
        self.frame += 1;
        let c = self.wrap(ImageRole::Color, color, color_format);
        let d = match (depth, depth_format) {
            (Some(image), Some(format)) => Some(self.wrap(ImageRole::Depth, image, format)),
            _ => None,
        };
        handoff += started.elapsed();
        let mut encoder = self.device.create_command_encoder(&Default::default());
        renderer.encode_view_at(
            view,
            &mut encoder,
            &Targets {
                color: ColorTargets::InPlace(&self.wrappers[c].view),
                depth: d.map(|i| &self.wrappers[i].view),
                viewport,
            },
            crate::renderer::TargetMips {
                color: color.mip_level,
                depth: depth.map_or(0, |d| d.mip_level),
                layered: true,
            },
        )?;
        let started = std::time::Instant::now();
        let transition = |i: usize, image: &HostImage, role| wgpu::TextureTransition {
            texture: &self.wrappers[i].texture,
            selector: Some(wgpu::wgt::TextureSelector {
                mips: image.mip_level..image.mip_level + 1,
                layers: image.array_layer..image.array_layer + 1,
            }),
            state: state_of(wgpu_layout(role, final_layout(image))),
        };
        let mut transitions = vec![transition(c, color, ImageRole::Color)];
        if let (Some(i), Some(image)) = (d, depth) {
            transitions.push(transition(i, image, ImageRole::Depth));
        }
        // The cloud shadow map ends every frame sampled-ready (SHADER_READ_ONLY_OPTIMAL,
        // `super::SHADOW_MAP_LAYOUT`), whichever pass touched it last, so a host can bind its
        // VkImage (`super::shadow_map_image`) in a known layout.
        if let Some(map) = renderer.cloud_shadows() {
            transitions.push(wgpu::TextureTransition {
                texture: map.texture,
                selector: None,
                state: wgpu::TextureUses::RESOURCE,
            });
        }
        encoder.transition_resources(std::iter::empty(), transitions.into_iter());
        let work = encoder.finish();
        let mut entry = Vec::new();
        let mut exit = Vec::new();
        for (role, image) in [(ImageRole::Color, Some(color)), (ImageRole::Depth, depth)] {
            let Some(image) = image else { continue };
            let range = subresource(role, image);
            let (from, to) = (image.layout, final_layout(image));
            if wgpu_layout(role, from) != from {
                entry.push(LayoutMove {
                    image: image.image,
                    range,
                    from,
                    to: wgpu_layout(role, from),
                });
            }
            if wgpu_layout(role, to) != to {
                exit.push(LayoutMove {
                    image: image.image,
                    range,
                    from: wgpu_layout(role, to),
                    to,
                });
            }
        }
        let before = self.global_barrier(&entry);
        let after = self.global_barrier(&exit);
        {
            // SAFETY: the host's semaphores are live (caller's contract); they are consumed by
            // the submit just below, which nothing can precede.
            let hal_queue = unsafe { self.queue.as_hal::<hv::Api>() }
                .ok_or_else(|| Error::Vulkan("the queue is not a Vulkan queue".into()))?;
            for w in waits {
                let stage = if w.stage.is_empty() {
                    vk::PipelineStageFlags::ALL_COMMANDS
                } else {
                    w.stage
                };
                hal_queue.add_wait_semaphore(w.semaphore, w.value, stage);
            }
            for s in signals {
                hal_queue.add_signal_semaphore(s.semaphore, s.value);
            }
        }
        self.last_handoff = handoff + started.elapsed();
        crate::device::gpu_scope(&self.device, || {
            self.queue.submit([before, work, after]);
        })?;
        self.wrappers[c].layout = wgpu_layout(ImageRole::Color, final_layout(color));
        if let (Some(i), Some(image)) = (d, depth) {
            self.wrappers[i].layout = wgpu_layout(ImageRole::Depth, final_layout(image));
        }
        Ok(())
    }

    /// Drops every wrapper and waits until the GPU is done with them: call it before destroying
    /// or re-creating an image handed to [`HostFrame::render`].
    pub fn release(&mut self, renderer: &mut Renderer) -> Result<()> {
        renderer.forget_target_views();
        self.wrappers.clear();
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU: {e}")))?;
        Ok(())
    }
}

fn final_layout(image: &HostImage) -> vk::ImageLayout {
    if image.final_layout == vk::ImageLayout::UNDEFINED {
        image.layout
    } else {
        image.final_layout
    }
}
