//! A Rust host on ash with its own Vulkan instance, device and images, handing them to Nimbus
//! (`nimbus::vulkan`) every frame: the hand-off's CPU cost, and (with `--check`) proof that a
//! frame on the host's images creates no wgpu object.
//!
//! Two phases of `--frames` frames each on one host device, each with its own `Renderer` on the
//! adopted device, the same moving camera and the same targets' size and formats:
//! - **host images**: `HostFrame::render` on the host's `R16G16B16A16_SFLOAT` color image and
//!   `D32_SFLOAT` depth image (wrapping, checks, global barriers, final layouts, submit);
//! - **wgpu textures**: `Renderer::encode` into wgpu textures of the same device, then submit.
//!
//! `HostFrame::last_handoff_time` gives the hand-off's own part of each call (checks, wrappers,
//! final transitions, barrier buffers, semaphores); the difference between the two phases'
//! medians shows the same from outside. Each call is timed on its own and the GPU is waited
//! for outside the timed region, so frames do not pile up.
//!
//! Usage: cargo run --release --example vulkan_handoff -- [--size 1280x720] [--frames 120]
//!        [--check]

use std::ffi::CString;
use std::process::ExitCode;
use std::time::Instant;

use nimbus::demo::standard_views;
use nimbus::headless::LiveObjects;
use nimbus::renderer::{ColorTargets, Targets};
use nimbus::vulkan::ash::{self, vk};
use nimbus::vulkan::{
    adopt_device, instance_extensions, DeviceRequirements, HostDevice, HostFrame, HostImage,
    HostInstance,
};
use nimbus::{Renderer, Settings};

type Res<T> = Result<T, String>;

fn err<E: std::fmt::Display>(what: &str) -> impl FnOnce(E) -> String + '_ {
    move |e| format!("{what}: {e}")
}

struct Options {
    size: (u32, u32),
    frames: u32,
    check: bool,
}

fn parse_args() -> Res<Options> {
    let mut o = Options {
        size: (1280, 720),
        frames: 120,
        check: false,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                let v = args.next().ok_or("--size needs WxH")?;
                let (w, h) = v.split_once('x').ok_or("--size needs WxH")?;
                o.size = (
                    w.parse().map_err(err("width"))?,
                    h.parse().map_err(err("height"))?,
                );
            }
            "--frames" => {
                o.frames = args
                    .next()
                    .ok_or("--frames needs N")?
                    .parse()
                    .map_err(err("--frames"))?
            }
            "--check" => o.check = true,
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    if o.frames < 4 {
        return Err("--frames must be at least 4".into());
    }
    Ok(o)
}

/// The host's own Vulkan objects, made as an engine makes them.
struct Host {
    _entry: ash::Entry,
    instance: ash::Instance,
    device: ash::Device,
    images: Vec<(vk::Image, vk::DeviceMemory)>,
}

impl Drop for Host {
    fn drop(&mut self) {
        // SAFETY: everything Nimbus made on the device is gone (dropped before the host), and
        // the GPU is idle.
        unsafe {
            let _ = self.device.device_wait_idle();
            for (image, memory) in self.images.drain(..) {
                self.device.destroy_image(image, None);
                self.device.free_memory(memory, None);
            }
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}

/// The host's GPU objects an image is made with.
struct Gpu<'a> {
    instance: &'a ash::Instance,
    physical: vk::PhysicalDevice,
    device: &'a ash::Device,
    queue: vk::Queue,
}

/// An image of the host's with its memory, in `layout` (cleared first).
///
/// Safety: a live device; `queue` is its queue of family 0.
unsafe fn host_image(
    gpu: &Gpu,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    size: (u32, u32),
    layout: vk::ImageLayout,
) -> Res<(vk::Image, vk::DeviceMemory)> {
    let Gpu {
        instance,
        physical,
        device,
        queue,
    } = *gpu;
    let depth = format == vk::Format::D32_SFLOAT;
    let info = vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: size.0,
            height: size.1,
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(usage | vk::ImageUsageFlags::TRANSFER_DST);
    // SAFETY: valid create info on a live device (the caller's contract), and below likewise.
    unsafe {
        let image = device
            .create_image(&info, None)
            .map_err(err("vkCreateImage"))?;
        let req = device.get_image_memory_requirements(image);
        let props = instance.get_physical_device_memory_properties(physical);
        let index = (0..props.memory_type_count)
            .find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && props.memory_types[i as usize]
                        .property_flags
                        .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
            })
            .ok_or("no device-local memory type")?;
        let memory = device
            .allocate_memory(
                &vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(index),
                None,
            )
            .map_err(err("vkAllocateMemory"))?;
        device
            .bind_image_memory(image, memory, 0)
            .map_err(err("vkBindImageMemory"))?;
        let pool = device
            .create_command_pool(
                &vk::CommandPoolCreateInfo::default().queue_family_index(0),
                None,
            )
            .map_err(err("vkCreateCommandPool"))?;
        let cb = device
            .allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )
            .map_err(err("vkAllocateCommandBuffers"))?[0];
        device
            .begin_command_buffer(cb, &vk::CommandBufferBeginInfo::default())
            .map_err(err("vkBeginCommandBuffer"))?;
        let aspect = if depth {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        };
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(aspect)
            .level_count(1)
            .layer_count(1);
        let to_dst = vk::ImageMemoryBarrier::default()
            .image(image)
            .subresource_range(range)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE);
        device.cmd_pipeline_barrier(
            cb,
            vk::PipelineStageFlags::TOP_OF_PIPE,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_dst],
        );
        if depth {
            let clear = vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            };
            device.cmd_clear_depth_stencil_image(
                cb,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &clear,
                &[range],
            );
        } else {
            let clear = vk::ClearColorValue {
                float32: [0.2, 0.35, 0.7, 1.0],
            };
            device.cmd_clear_color_image(
                cb,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &clear,
                &[range],
            );
        }
        let to_layout = vk::ImageMemoryBarrier::default()
            .image(image)
            .subresource_range(range)
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .new_layout(layout)
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE);
        device.cmd_pipeline_barrier(
            cb,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::ALL_COMMANDS,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_layout],
        );
        device
            .end_command_buffer(cb)
            .map_err(err("vkEndCommandBuffer"))?;
        let cbs = [cb];
        device
            .queue_submit(
                queue,
                &[vk::SubmitInfo::default().command_buffers(&cbs)],
                vk::Fence::null(),
            )
            .map_err(err("vkQueueSubmit"))?;
        device
            .queue_wait_idle(queue)
            .map_err(err("vkQueueWaitIdle"))?;
        device.destroy_command_pool(pool, None);
        Ok((image, memory))
    }
}

struct Stats(Vec<f64>);

impl Stats {
    fn mean(&self) -> f64 {
        self.0.iter().sum::<f64>() / self.0.len() as f64
    }
    fn median(&self) -> f64 {
        let mut v = self.0.clone();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }
}

fn run(o: &Options) -> Res<()> {
    // SAFETY: loads the system's Vulkan loader.
    let entry = unsafe { ash::Entry::load() }.map_err(err("loading libvulkan"))?;
    let extensions = instance_extensions(&entry).map_err(err("instance extensions"))?;
    let ext_ptrs: Vec<_> = extensions.iter().map(|e| e.as_ptr()).collect();
    let api_version = vk::API_VERSION_1_3;
    let app = vk::ApplicationInfo::default().api_version(api_version);
    // SAFETY: valid create infos, and every call below on the objects made here.
    let instance = unsafe {
        entry.create_instance(
            &vk::InstanceCreateInfo::default()
                .application_info(&app)
                .enabled_extension_names(&ext_ptrs),
            None,
        )
    }
    .map_err(err("vkCreateInstance"))?;
    let physical = unsafe { instance.enumerate_physical_devices() }
        .map_err(err("vkEnumeratePhysicalDevices"))?
        .first()
        .copied()
        .ok_or("no Vulkan physical device")?;
    let host_instance = HostInstance {
        entry: entry.clone(),
        instance: instance.handle(),
        api_version,
        extensions: extensions.iter().map(|e| CString::from(*e)).collect(),
    };
    let mut req = unsafe { DeviceRequirements::new(&host_instance, physical) }
        .map_err(err("requirements"))?;
    // The host's own chain, as an engine has it: Vulkan 1.2 features of its own, into which
    // Nimbus merges its promoted bits.
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features2 = vk::PhysicalDeviceFeatures2 {
        p_next: (&raw mut v12).cast(),
        ..Default::default()
    };
    unsafe { req.merge_features(&raw mut features2) }.map_err(err("merge features"))?;
    let dev_ext_ptrs: Vec<_> = req.extensions().iter().map(|e| e.as_ptr()).collect();
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(req.queue_family())
        .queue_priorities(&priorities)];
    let mut device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&dev_ext_ptrs);
    device_info.p_next = (&raw const features2).cast();
    let device = unsafe { instance.create_device(physical, &device_info, None) }
        .map_err(err("vkCreateDevice"))?;
    let queue = unsafe { device.get_device_queue(req.queue_family(), 0) };
    let mut host = Host {
        _entry: entry,
        instance: instance.clone(),
        device: device.clone(),
        images: Vec::new(),
    };
    let size = o.size;
    let color_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT
        | vk::ImageUsageFlags::SAMPLED
        | vk::ImageUsageFlags::TRANSFER_SRC;
    let depth_usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
    let color_layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
    let depth_layout = vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    for (format, usage, layout) in [
        (vk::Format::R16G16B16A16_SFLOAT, color_usage, color_layout),
        (vk::Format::D32_SFLOAT, depth_usage, depth_layout),
    ] {
        let gpu = Gpu {
            instance: &instance,
            physical,
            device: &device,
            queue,
        };
        let image = unsafe { host_image(&gpu, format, usage, size, layout) }?;
        host.images.push(image);
    }
    let image = |i: usize, format, usage, layout| HostImage {
        image: host.images[i].0,
        format,
        width: size.0,
        height: size.1,
        mip_levels: 1,
        array_layers: 1,
        mip_level: 0,
        array_layer: 0,
        usage: usage | vk::ImageUsageFlags::TRANSFER_DST,
        layout,
        final_layout: vk::ImageLayout::UNDEFINED,
    };
    let color = image(
        0,
        vk::Format::R16G16B16A16_SFLOAT,
        color_usage,
        color_layout,
    );
    let depth = image(1, vk::Format::D32_SFLOAT, depth_usage, depth_layout);

    let host_device = HostDevice {
        instance: host_instance,
        physical_device: physical,
        device: device.handle(),
        extensions: req.extensions().iter().map(|e| CString::from(*e)).collect(),
        enabled_features: &raw const features2,
        queue,
        queue_family_index: req.queue_family(),
        queue_index: 0,
        queue_lock: None,
    };
    let adopted = unsafe { adopt_device(&host_device) }.map_err(err("adopt_device"))?;
    drop(req);
    let view = &standard_views()[0];
    let frame_at = |i: u32| {
        let mut f = view.frame(size.0, size.1, i as f64 / 30.0);
        // A slowly turning camera: reprojection works every frame, as in a game.
        f.camera.view = glam::Mat4::from_rotation_y(i as f32 * 0.002) * f.camera.view;
        f
    };
    let wait = |d: &nimbus::wgpu::Device| d.poll(nimbus::wgpu::PollType::wait_indefinitely());

    // Phase 1: the host's images through HostFrame.
    let mut renderer = Renderer::new(&adopted.device, &adopted.queue, Settings::default())
        .map_err(err("Renderer::new"))?;
    let mut frame = HostFrame::new(&adopted).map_err(err("HostFrame::new"))?;
    let mut host_times = Stats(Vec::new());
    let mut handoff_times = Stats(Vec::new());
    let mut settled: Option<(LiveObjects, u64, u64)> = None;
    for i in 0..o.frames {
        let inputs = frame_at(i);
        let t = Instant::now();
        unsafe {
            frame.render(
                &mut renderer,
                nimbus::ViewId::DEFAULT,
                &inputs,
                (&color, Some(&depth), None),
                &[],
                &[],
            )
        }
        .map_err(err("HostFrame::render"))?;
        let dt = t.elapsed().as_secs_f64() * 1e6;
        wait(&adopted.device).map_err(err("poll"))?;
        if i >= 2 {
            host_times.0.push(dt);
            handoff_times
                .0
                .push(frame.last_handoff_time().as_secs_f64() * 1e6);
        }
        // From the third frame on (the first two make the wrappers and bind groups), nothing
        // may be created.
        if i == 2 {
            settled = Some((
                LiveObjects::of(&adopted.device),
                frame.wraps_created(),
                renderer.bind_groups_created(),
            ));
        }
    }
    let after = (
        LiveObjects::of(&adopted.device),
        frame.wraps_created(),
        renderer.bind_groups_created(),
    );
    frame.release(&mut renderer).map_err(err("release"))?;
    drop(frame);
    drop(renderer);

    // Phase 2: the same frames into wgpu textures of the same device.
    let mut renderer = Renderer::new(&adopted.device, &adopted.queue, Settings::default())
        .map_err(err("Renderer::new"))?;
    let color_tex = nimbus::device::texture_2d(
        &adopted.device,
        "color",
        size,
        nimbus::wgpu::TextureFormat::Rgba16Float,
        nimbus::wgpu::TextureUsages::RENDER_ATTACHMENT
            | nimbus::wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let depth_tex = nimbus::device::texture_2d(
        &adopted.device,
        "depth",
        size,
        nimbus::wgpu::TextureFormat::Depth32Float,
        nimbus::wgpu::TextureUsages::RENDER_ATTACHMENT
            | nimbus::wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let color_view = color_tex.create_view(&Default::default());
    let depth_view = depth_tex.create_view(&Default::default());
    let mut wgpu_times = Stats(Vec::new());
    for i in 0..o.frames {
        let inputs = frame_at(i);
        let t = Instant::now();
        renderer.prepare(&inputs).map_err(err("prepare"))?;
        let mut encoder = adopted.device.create_command_encoder(&Default::default());
        renderer
            .encode(
                &mut encoder,
                &Targets {
                    color: ColorTargets::InPlace(&color_view),
                    depth: Some(&depth_view),
                    viewport: None,
                },
            )
            .map_err(err("encode"))?;
        adopted.queue.submit([encoder.finish()]);
        let dt = t.elapsed().as_secs_f64() * 1e6;
        wait(&adopted.device).map_err(err("poll"))?;
        if i >= 2 {
            wgpu_times.0.push(dt);
        }
    }
    drop(renderer);
    drop((color_view, depth_view, color_tex, depth_tex));
    drop(adopted);

    println!(
        "{}x{}, {} frames per phase (the first two left out), CPU time per frame call:",
        size.0, size.1, o.frames
    );
    println!(
        "  host images (HostFrame::render): mean {:.0} us, median {:.0} us",
        host_times.mean(),
        host_times.median()
    );
    println!(
        "  of which the hand-off itself (checks, wrappers, final transitions, barriers): \
         mean {:.1} us, median {:.1} us",
        handoff_times.mean(),
        handoff_times.median()
    );
    println!(
        "  wgpu textures (encode + submit): mean {:.0} us, median {:.0} us",
        wgpu_times.mean(),
        wgpu_times.median()
    );
    println!(
        "  difference of the two medians: {:.0} us",
        host_times.median() - wgpu_times.median()
    );
    let (before, wraps, binds) = settled.expect("at least 4 frames");
    println!(
        "  objects from frame 3 to the end: live {:?} -> {:?}, wrappers made {wraps} -> {}, bind groups made {binds} -> {}",
        before.counts(),
        after.0.counts(),
        after.1,
        after.2
    );
    drop(host);
    if o.check {
        if before.counts() != after.0.counts() || wraps != after.1 || binds != after.2 || wraps != 2
        {
            return Err("a frame on the host's images created objects".into());
        }
        println!("check: no object created per frame on the host's images");
    }
    Ok(())
}

fn main() -> ExitCode {
    let result = parse_args().and_then(|o| run(&o));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vulkan_handoff: {e}");
            ExitCode::FAILURE
        }
    }
}
