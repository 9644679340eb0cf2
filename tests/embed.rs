//! Embedding: a host engine creates its own Vulkan instance, device and allocator with raw
//! `ash`, hands them to cullgraph, and records cullgraph's frame into its own command buffer.

mod common;

use ash::vk;
use common::{boxes_camera, boxes_scene, readback_buffer, GpuTest};
use cullgraph::gpu::features::MULTIVIEW_EXTENSION;
use cullgraph::gpu::transfer::record_image_to_buffer;
use cullgraph::gpu::{
    Access, Buffer, BufferDesc, GpuContext, HostHandles, HostImage, MemoryLocation, RequiredFeatures, ShaderCompiler,
    ShaderRoot, ValidationLog, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS,
};
use cullgraph::graph::Imports;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::sync::{Arc, Mutex};

/// Serializes this file's tests. An engine's device made and destroyed at once beside
/// another test's device crashed lavapipe once in CI (SIGSEGV, not reproduced in dozens of
/// runs here); one host device at a time keeps a driver race out of what these tests check.
fn one_host_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// What the "engine" owns.
struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    physical_device: vk::PhysicalDevice,
    device: ash::Device,
    family: u32,
    queue: vk::Queue,
    debug: (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT),
    log: Box<ValidationLog>,
    /// The device extensions the engine enabled.
    extensions: Vec<&'static std::ffi::CStr>,
}

impl Host {
    /// An engine that enables only what cullgraph requires.
    fn new() -> Self {
        Self::with_extensions(REQUIRED_DEVICE_EXTENSIONS.to_vec())
    }

    fn with_extensions(extensions: Vec<&'static std::ffi::CStr>) -> Self {
        let entry = unsafe { ash::Entry::load() }.unwrap();
        let log = Box::new(ValidationLog::default());
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let exts = [ash::ext::debug_utils::NAME.as_ptr(), ash::ext::validation_features::NAME.as_ptr()];
        let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&exts)
            .push_next(&mut features);
        let instance = unsafe { entry.create_instance(&info, None) }.unwrap();
        let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let messenger = unsafe { loader.create_debug_utils_messenger(&log.messenger_create_info(), None) }.unwrap();

        let physical_device = unsafe { instance.enumerate_physical_devices() }
            .unwrap()
            .into_iter()
            .find(|&pd| {
                let props = unsafe { instance.get_physical_device_properties(pd) };
                props.device_name_as_c_str().unwrap().to_string_lossy().contains("llvmpipe")
            })
            .expect("lavapipe");
        let family = unsafe { instance.get_physical_device_queue_family_properties(physical_device) }
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
            .unwrap() as u32;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let ext_names: Vec<_> = extensions.iter().map(|e| e.as_ptr()).collect();
        let mut required = RequiredFeatures::new();
        // Listing the multiview name is the engine's word that the feature is on.
        required.v11.multiview = extensions.contains(&MULTIVIEW_EXTENSION).into();
        let mut features2 = required.chain();
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&ext_names)
            .push_next(&mut features2);
        let device = unsafe { instance.create_device(physical_device, &info, None) }.unwrap();
        let queue = unsafe { device.get_device_queue(family, 0) };
        Self { entry, instance, physical_device, device, family, queue, debug: (loader, messenger), log, extensions }
    }
}

impl Host {
    /// Shuts the engine down (its `allocator` first, then the device, whose destruction reports
    /// leaks) and fails on any validation message of its lifetime.
    fn shut_down_clean(self, allocator: Arc<Mutex<Allocator>>) {
        drop(allocator);
        let log = (*self.log).clone();
        drop(self);
        let messages = log.messages();
        assert!(messages.is_empty(), "validation: {messages:#?}");
    }

    /// The engine's own gpu-allocator on its device.
    fn allocator(&self) -> Arc<Mutex<Allocator>> {
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: self.instance.clone(),
            device: self.device.clone(),
            physical_device: self.physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .unwrap();
        Arc::new(Mutex::new(allocator))
    }

    /// What the engine hands to cullgraph.
    fn handles(&self, allocator: &Arc<Mutex<Allocator>>) -> HostHandles {
        HostHandles {
            entry: self.entry.clone(),
            instance: self.instance.clone(),
            physical_device: self.physical_device,
            device: self.device.clone(),
            queue_family_index: self.family,
            queue: self.queue,
            allocator: Some(allocator.clone()),
            debug_utils: true,
            enabled_device_extensions: self.extensions.iter().map(|e| (*e).to_owned()).collect(),
        }
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_device(None);
            self.debug.0.destroy_debug_utils_messenger(self.debug.1, None);
            self.instance.destroy_instance(None);
        }
    }
}

#[test]
fn renders_into_the_hosts_command_buffer_on_the_hosts_device() {
    let _one_at_a_time = one_host_at_a_time();
    let (w, h) = (96, 64);
    // Reference: the same frame through a context cullgraph owns.
    let reference = {
        let gpu = GpuTest::new();
        let mut r = Renderer::new(&gpu, gpu.shaders(), boxes_scene(), RenderSettings::new(w, h)).unwrap();
        r.render_to_image(&boxes_camera()).unwrap().1
    };

    let host = Host::new();
    let allocator = host.allocator();
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        let shaders =
            ShaderCompiler::new(ShaderRoot::Directory(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders").into())).unwrap();
        let mut renderer = Renderer::new(&ctx, &shaders, boxes_scene(), RenderSettings::new(w, h)).unwrap();
        let readback = readback_buffer(&ctx, "host readback", (w * h * 4) as u64);

        // The host's own command pool, command buffer, fence and submit.
        let d = &host.device;
        unsafe {
            let pool = d
                .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(host.family), None)
                .unwrap();
            let cmd = d
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
                )
                .unwrap()[0];
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            let frame = renderer.record(cmd, &boxes_camera()).unwrap();
            assert_eq!(frame, 0);
            let (output, state) = renderer.output().expect("an image output after a recorded frame");
            record_image_to_buffer(&ctx, cmd, output, state, &readback);
            d.end_command_buffer(cmd).unwrap();
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            let cmds = [cmd];
            d.queue_submit(host.queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence).unwrap();
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
        }
        let timings = renderer.completed_timings(0).unwrap();
        assert!(
            timings.iter().any(|t| t.name == "draw_late") && timings.iter().any(|t| t.name == "lighting"),
            "{timings:?}"
        );
        let pixels = readback.read_bytes().unwrap();
        assert_eq!(pixels, reference.as_raw().as_slice(), "embedded frame differs from the owned-context frame");
    }
    // cullgraph released everything it made from the host's allocator and device (leaks would
    // be reported by vkDestroyDevice).
    host.shut_down_clean(allocator);
}

#[test]
fn the_graph_lights_straight_into_an_image_the_host_owns() {
    let _one_at_a_time = one_host_at_a_time();
    lights_into_a_host_image(false);
}

#[test]
fn a_failed_record_consumes_nothing_so_the_host_can_discard_its_command_buffer() {
    let _one_at_a_time = one_host_at_a_time();
    lights_into_a_host_image(true);
}

/// The graph lights into the host's image; a first record without the import fails, and its
/// command buffer is either submitted as it is or (`discard_failed`) thrown away unsubmitted.
fn lights_into_a_host_image(discard_failed: bool) {
    let (w, h) = (80, 48);
    let reference = {
        let gpu = GpuTest::new();
        let mut r = Renderer::new(&gpu, gpu.shaders(), boxes_scene(), RenderSettings::new(w, h)).unwrap();
        r.render_to_image(&boxes_camera()).unwrap().1
    };
    let host = Host::new();
    let allocator = host.allocator();
    // The engine's own image and view, made with its own allocator.
    let d = host.device.clone();
    let target = HostOwnedImage::new(
        &d,
        &allocator,
        vk::Format::R8G8B8A8_UNORM,
        (w, h, 1),
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
    );
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        let mut renderer = example_renderer(&ctx, "host_target", w, h);
        let readback = readback_buffer(&ctx, "host readback", (w * h * 4) as u64);
        if !discard_failed {
            // Missing imports are an error before anything is recorded.
            ctx.submit_and_wait(|cmd| {
                let err = renderer.record(cmd, &boxes_camera()).unwrap_err().to_string();
                assert!(err.contains(":14:9: resource 'color': is imported, but the host provided nothing"), "{err}");
                cullgraph::gpu::GpuResult::Ok(())
            })
            .unwrap();
        }
        unsafe {
            let pool = d
                .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(host.family), None)
                .unwrap();
            let cmd = d
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
                )
                .unwrap()[0];
            if discard_failed {
                // Recording is all or nothing: the scene upload this command buffer would have
                // carried is not lost with it.
                let discarded = d
                    .allocate_command_buffers(
                        &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
                    )
                    .unwrap()[0];
                d.begin_command_buffer(discarded, &vk::CommandBufferBeginInfo::default()).unwrap();
                let err = renderer.record(discarded, &boxes_camera()).unwrap_err().to_string();
                assert!(err.contains(":14:9: resource 'color': is imported, but the host provided nothing"), "{err}");
                d.end_command_buffer(discarded).unwrap();
                d.free_command_buffers(pool, &[discarded]);
            }
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            let imports = Imports::new().image("color", target.host, Access::NONE, Access::TRANSFER_READ);
            assert_eq!(renderer.record_with_imports(cmd, &boxes_camera(), &imports).unwrap(), 0);
            // The engine copies its image, which cullgraph left in TRANSFER_SRC_OPTIMAL.
            copy_for_host(&d, cmd, target.image, (w, h), &readback);
            d.end_command_buffer(cmd).unwrap();
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            d.queue_submit(host.queue, &[vk::SubmitInfo::default().command_buffers(&[cmd])], fence).unwrap();
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
        }
        assert_eq!(readback.read_bytes().unwrap(), reference.as_raw().as_slice());
    }
    target.destroy(&d, &allocator);
    host.shut_down_clean(allocator);
}

/// An engine lighting straight into its swapchain's images, rotating through three of them
/// and vouching for them (`Imports::vouched`): every frame shows its own camera in the image it
/// was given, and once each image's views are kept, frames replay their recordings instead of
/// recording every pass. Without the word, no frame replays.
#[test]
fn frames_into_host_images_the_host_vouches_for_replay() {
    let _one_at_a_time = one_host_at_a_time();
    let (w, h) = (80, 48);
    let cameras: Vec<_> = (0..18)
        .map(|i| {
            let mut camera = boxes_camera();
            camera.eye.x += 0.05 * (i % 7) as f64;
            camera
        })
        .collect();
    let references: Vec<Vec<u8>> = {
        let gpu = GpuTest::new();
        let mut r = Renderer::new(&gpu, gpu.shaders(), boxes_scene(), RenderSettings::new(w, h)).unwrap();
        cameras.iter().map(|c| r.render_to_image(c).unwrap().1.into_raw()).collect()
    };
    let host = Host::new();
    let allocator = host.allocator();
    let d = host.device.clone();
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let new_swapchain = || -> Vec<HostOwnedImage> {
        (0..3).map(|_| HostOwnedImage::new(&d, &allocator, vk::Format::R8G8B8A8_UNORM, (w, h, 1), usage)).collect()
    };
    let mut swapchain = new_swapchain();
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        let readback = readback_buffer(&ctx, "host readback", (w * h * 4) as u64);
        // One frame of `camera` into `target` (in `current` access), under `generation`: the
        // image it left there.
        let frame = |renderer: &mut Renderer, target: &HostOwnedImage, camera, current, generation: Option<u64>| {
            let mut imports = Imports::new().image("color", target.host, current, Access::TRANSFER_READ);
            if let Some(generation) = generation {
                imports = imports.vouched(generation);
            }
            ctx.submit_and_wait(|cmd| -> cullgraph::Result<()> {
                renderer.record_with_imports(cmd, camera, &imports)?;
                // SAFETY: cmd is recording; the image and buffer outlive its execution.
                unsafe { copy_for_host(&d, cmd, target.image, (w, h), &readback) };
                Ok(())
            })
            .unwrap();
            readback.read_bytes().unwrap()
        };
        for vouched in [true, false] {
            let mut renderer = example_renderer(&ctx, "host_target", w, h);
            for (i, camera) in cameras.iter().enumerate() {
                // Each image was left for the copy in the frame that last drew it.
                let current = if i < 3 && vouched { Access::NONE } else { Access::TRANSFER_READ };
                let image = frame(&mut renderer, &swapchain[i % 3], camera, current, vouched.then_some(7));
                assert!(image == references[i], "vouched {vouched}, frame {i}");
            }
            let replayed = renderer.runtime().frames_replayed();
            match vouched {
                // Frames 0 to 2 make each image's views, 3 to 11 fill the six recordings with
                // them; from frame 12 on, every frame replays.
                true => assert!(replayed >= 6, "{replayed} frames replayed"),
                false => assert_eq!(replayed, 0),
            }
            if vouched {
                // The swapchain made anew (Vulkan may give the new images the old handles),
                // under a new generation: every frame shows its camera in its new image.
                for image in std::mem::take(&mut swapchain) {
                    image.destroy(&d, &allocator);
                }
                swapchain = new_swapchain();
                for (i, camera) in cameras.iter().enumerate().take(9) {
                    let current = if i < 3 { Access::NONE } else { Access::TRANSFER_READ };
                    let image = frame(&mut renderer, &swapchain[i % 3], camera, current, Some(8));
                    assert!(image == references[i], "new swapchain, frame {i}");
                }
            }
        }
    }
    for image in swapchain {
        image.destroy(&d, &allocator);
    }
    host.shut_down_clean(allocator);
}

/// Records the engine's copy of its color image `image` (`size`, left in TRANSFER_SRC_OPTIMAL
/// by the frame) into `readback`, and makes the copy visible to the host.
///
/// # Safety
/// `cmd` is recording; the image and the buffer outlive its execution.
unsafe fn copy_for_host(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    size: (u32, u32),
    readback: &Buffer,
) {
    let region = vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
        )
        .image_extent(vk::Extent3D { width: size.0, height: size.1, depth: 1 });
    let to_host = vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ);
    unsafe {
        d.cmd_copy_image_to_buffer(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, readback.handle(), &[region]);
        d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[to_host]));
    }
}

/// The boxes through `graph/examples/NAME.ron` at `w`x`h`, on the host's context.
fn example_renderer(ctx: &GpuContext, name: &str, w: u32, h: u32) -> Renderer {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let shaders = ShaderCompiler::new(ShaderRoot::Directory(root.join("shaders"))).unwrap();
    let spec = GraphSpec::from_file(&root.join(format!("graph/examples/{name}.ron"))).unwrap();
    Renderer::with_graph(ctx, &shaders, boxes_scene(), RenderSettings::new(w, h), &spec).unwrap()
}

/// An image the "engine" makes with its own allocator, and its view of every mip and aspect.
struct HostOwnedImage {
    image: vk::Image,
    view: vk::ImageView,
    memory: gpu_allocator::vulkan::Allocation,
    host: HostImage,
}

impl HostOwnedImage {
    fn new(
        d: &ash::Device,
        allocator: &Arc<Mutex<Allocator>>,
        format: vk::Format,
        (w, h, mips): (u32, u32, u32),
        usage: vk::ImageUsageFlags,
    ) -> Self {
        let image = unsafe {
            d.create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(format)
                    .extent(vk::Extent3D { width: w, height: h, depth: 1 })
                    .mip_levels(mips)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .usage(usage)
                    .initial_layout(vk::ImageLayout::UNDEFINED),
                None,
            )
            .unwrap()
        };
        let requirements = unsafe { d.get_image_memory_requirements(image) };
        let memory = allocator
            .lock()
            .unwrap()
            .allocate(&gpu_allocator::vulkan::AllocationCreateDesc {
                name: "host image",
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: gpu_allocator::vulkan::AllocationScheme::GpuAllocatorManaged,
            })
            .unwrap();
        unsafe { d.bind_image_memory(image, memory.memory(), memory.offset()).unwrap() };
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(cullgraph::gpu::image::aspect_of(format))
            .level_count(mips)
            .layer_count(1);
        let info = vk::ImageViewCreateInfo::default().image(image).view_type(vk::ImageViewType::TYPE_2D).format(format);
        let view = unsafe { d.create_image_view(&info.subresource_range(range), None).unwrap() };
        let host = HostImage {
            image,
            view,
            format,
            extent: vk::Extent2D { width: w, height: h },
            mip_levels: mips,
            samples: vk::SampleCountFlags::TYPE_1,
            layer: 0,
        };
        Self { image, view, memory, host }
    }

    fn destroy(self, d: &ash::Device, allocator: &Arc<Mutex<Allocator>>) {
        unsafe {
            d.destroy_image_view(self.view, None);
            d.destroy_image(self.image, None);
        }
        allocator.lock().unwrap().free(self.memory).unwrap();
    }
}

/// `graph/examples/host_depth_and_pyramid.ron`: the engine owns the depth (with stencil) and
/// the Hi-Z pyramid; the graph draws into the one, samples its depth aspect and builds the other
/// mip by mip.
#[test]
fn the_host_can_own_a_depth_stencil_image_and_a_mipmapped_pyramid() {
    let _one_at_a_time = one_host_at_a_time();
    use cullgraph::cull::hiz::{level_offset, level_size, stored_mip_count, stored_size, HiZPyramid};
    use glam::UVec2;
    // 203x131: a pyramid of 7 mips, levels above the 64-pixel tiles included.
    let (w, h) = (203u32, 131u32);
    let base = UVec2::new(w, h);
    let (pyramid, mips) = (stored_size(base), stored_mip_count(base));
    let host = Host::new();
    let allocator = host.allocator();
    let d = host.device.clone();
    let depth = HostOwnedImage::new(
        &d,
        &allocator,
        vk::Format::D32_SFLOAT_S8_UINT,
        (w, h, 1),
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC,
    );
    let hiz = HostOwnedImage::new(
        &d,
        &allocator,
        vk::Format::R32_SFLOAT,
        (pyramid.x, pyramid.y, mips),
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
    );
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        let mut renderer = example_renderer(&ctx, "host_depth_and_pyramid", w, h);
        let readback = |name: &str, texels: u32| readback_buffer(&ctx, name, u64::from(texels) * 4);
        let (depth_out, hiz_out) = (readback("depth", w * h), readback("hiz", level_offset(pyramid, mips)));
        let mut camera = boxes_camera();
        let mut current = Access::NONE;
        // Three frames in one command buffer (as many as may be in flight: the views made for
        // the host's mips and depth aspect must outlive the frames that use them), then two more
        // one by one, the camera moving; the host reads back the last frame's depth and pyramid.
        for batch in [3, 1, 1] {
            ctx.submit_and_wait(|cmd| {
                for _ in 0..batch {
                    camera.eye.x -= 0.2;
                    let imports = Imports::new().image("depth", depth.host, current, Access::TRANSFER_READ).image(
                        "hiz",
                        hiz.host,
                        current,
                        Access::TRANSFER_READ,
                    );
                    renderer.record_with_imports(cmd, &camera, &imports)?;
                    current = Access::TRANSFER_READ;
                }
                let depth_region = vk::BufferImageCopy::default()
                    .image_subresource(
                        vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::DEPTH).layer_count(1),
                    )
                    .image_extent(vk::Extent3D { width: w, height: h, depth: 1 });
                let hiz_regions: Vec<_> = (0..mips)
                    .map(|k| {
                        let size = level_size(pyramid, k);
                        vk::BufferImageCopy::default()
                            .buffer_offset(u64::from(level_offset(pyramid, k)) * 4)
                            .image_subresource(
                                vk::ImageSubresourceLayers::default()
                                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                                    .mip_level(k)
                                    .layer_count(1),
                            )
                            .image_extent(vk::Extent3D { width: size.x, height: size.y, depth: 1 })
                    })
                    .collect();
                let layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
                unsafe {
                    d.cmd_copy_image_to_buffer(cmd, depth.image, layout, depth_out.handle(), &[depth_region]);
                    d.cmd_copy_image_to_buffer(cmd, hiz.image, layout, hiz_out.handle(), &hiz_regions);
                    let to_host = vk::MemoryBarrier2::default()
                        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
                        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                        .dst_access_mask(vk::AccessFlags2::HOST_READ);
                    d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[to_host]));
                }
                Ok::<(), cullgraph::Error>(())
            })
            .unwrap();
        }
        let floats = |b: &Buffer| -> Vec<f32> { bytemuck::cast_slice(b.read_bytes().unwrap()).to_vec() };
        let depth_texels = floats(&depth_out);
        assert!(depth_texels.iter().filter(|&&z| z > 0.0).count() > (w * h) as usize / 4, "the boxes cover the view");
        let oracle = HiZPyramid::from_depth(w, h, &depth_texels);
        let gpu = floats(&hiz_out);
        for k in 0..mips {
            let level = oracle.stored_level(k);
            let start = level_offset(pyramid, k) as usize;
            let got = &gpu[start..start + level.texels.len()];
            let wrong = level.texels.iter().zip(got).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
            assert_eq!(wrong, 0, "mip {k} ({}x{}): {wrong} texels differ from the oracle", level.width, level.height);
        }
    }
    depth.destroy(&d, &allocator);
    hiz.destroy(&d, &allocator);
    host.shut_down_clean(allocator);
}

#[test]
fn the_compressed_g_buffer_runs_on_a_host_device_only_where_the_host_enabled_post_depth_coverage() {
    let _one_at_a_time = one_host_at_a_time();
    let (w, h) = (64, 48);
    let spec = GraphSpec::builtin("msaa_compressed").unwrap().with_overrides([("msaa".to_string(), "4".to_string())]);
    let render = |ctx: &GpuContext| -> cullgraph::Result<Vec<u8>> {
        let shaders =
            ShaderCompiler::new(ShaderRoot::Directory(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders").into())).unwrap();
        let mut r = Renderer::with_graph(ctx, &shaders, boxes_scene(), RenderSettings::new(w, h), &spec)?;
        Ok(r.render_to_image(&boxes_camera())?.1.into_raw())
    };
    let reference = render(&GpuTest::new()).unwrap();

    // Lavapipe supports the extension, but this engine did not enable it: the pass refuses to
    // be built, naming what is missing, instead of using an extension the device lacks.
    let host = Host::new();
    let allocator = host.allocator();
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        assert!(!ctx.caps().post_depth_coverage);
        let err = render(&ctx).unwrap_err().to_string();
        assert!(err.contains("pass 'gbuffer'") && err.contains("VK_EXT_post_depth_coverage"), "{err}");
    }
    host.shut_down_clean(allocator);

    // An engine that enabled it gets the frame the owned context renders.
    let host = Host::with_extensions([REQUIRED_DEVICE_EXTENSIONS, OPTIONAL_DEVICE_EXTENSIONS].concat());
    let allocator = host.allocator();
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        assert!(ctx.caps().post_depth_coverage);
        assert_eq!(render(&ctx).unwrap(), reference, "embedded MSAA frame differs from the owned-context frame");
    }
    host.shut_down_clean(allocator);
}

#[test]
fn the_multiview_measurement_is_skipped_on_a_host_device_without_multiview() {
    let _one_at_a_time = one_host_at_a_time();
    use cullgraph::bench::multiview::{self, MultiviewBench};
    let scene = cullgraph::scene::SceneSource::Builtin("city".into())
        .load(&cullgraph::scene::source::LoadOptions { instances: Some(100), ..Default::default() })
        .unwrap();
    let head = cullgraph::bench::views::camera(&scene, 0, 1);
    let bench = MultiviewBench { width: 64, height: 48, warmup: 0, frames: 1 };
    let shaders =
        ShaderCompiler::new(ShaderRoot::Directory(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders").into())).unwrap();
    for enabled in [false, true] {
        let extensions = match enabled {
            true => [REQUIRED_DEVICE_EXTENSIONS, &[MULTIVIEW_EXTENSION]].concat(),
            false => REQUIRED_DEVICE_EXTENSIONS.to_vec(),
        };
        let host = Host::with_extensions(extensions);
        let allocator = host.allocator();
        {
            let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
            // Lavapipe supports multiview; only a host that enabled it has it.
            assert_eq!(ctx.caps().multiview, enabled);
            let report = multiview::run(&ctx, &shaders, &scene, &head, &bench, &|_| {}).unwrap();
            assert_eq!((report.multiview, report.multiview_union_ms.is_some()), (enabled, enabled));
            assert!(report.drawn.iter().all(|&d| d > 0 && d <= report.union), "{report:?}");
            assert_eq!(report.markdown().contains("Multiview is not on"), !enabled);
        }
        host.shut_down_clean(allocator);
    }
}

#[test]
fn a_host_that_did_not_enable_a_required_extension_is_refused_naming_it() {
    let _one_at_a_time = one_host_at_a_time();
    let host = Host::new();
    let allocator = host.allocator();
    let mut handles = host.handles(&allocator);
    handles.enabled_device_extensions.clear();
    let err = GpuContext::from_host(handles).err().expect("refused").to_string();
    assert!(err.contains("VK_KHR_push_descriptor") && err.contains("not among the host's enabled extensions"), "{err}");
    drop(allocator);
}

#[test]
fn the_host_hands_buffers_in_and_reads_back_what_the_graph_wrote_into_them() {
    let _one_at_a_time = one_host_at_a_time();
    let (w, h) = (48u32, 32u32);
    let gpu = GpuTest::new();
    let ctx: &GpuContext = &gpu;
    let shaders = gpu.shaders();
    // The default frame, then a user pass that scales the lit image by the host's factor and
    // counts the pixels it wrote into the host's buffer.
    let tmp = tempfile::tempdir().unwrap();
    let examples = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples");
    let graph = std::fs::read_to_string(format!("{examples}/tint.ron"))
        .unwrap()
        .replace(
            "\"tinted\": Image(format: R8G8B8A8_UNORM),",
            "\"tinted\": Image(format: R8G8B8A8_UNORM),\n        \"factor\": Imported(Buffer(size: 16)),\n        \"probe\": Imported(Buffer(size: 16)),",
        )
        .replace("reads: {\"src\": \"color\"},", "reads: {\"src\": \"color\", \"2\": \"factor\"},")
        .replace("writes: {\"1\": \"tinted\"},", "writes: {\"1\": \"tinted\", \"3\": \"probe\"},");
    std::fs::write(tmp.path().join("tint.ron"), &graph).unwrap();
    std::fs::write(
        tmp.path().join("tint.comp"),
        r#"#version 460
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D dst;
layout(set = 0, binding = 2) readonly buffer Factor { vec4 factor; };
layout(set = 0, binding = 3) buffer Probe { uint pixels; };
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    vec4 c = texelFetch(src, p, 0);
    imageStore(dst, p, vec4(c.rgb * factor.rgb, c.a));
    atomicAdd(pixels, 1u);
}
"#,
    )
    .unwrap();
    let spec = GraphSpec::from_file(&tmp.path().join("tint.ron")).unwrap();
    let mut renderer = Renderer::with_graph(ctx, shaders, boxes_scene(), RenderSettings::new(w, h), &spec).unwrap();
    let host_buffer = |name, location| {
        Buffer::new(ctx, &BufferDesc { name, size: 16, usage: vk::BufferUsageFlags::STORAGE_BUFFER, location }).unwrap()
    };
    let mut factor = host_buffer("host factor", MemoryLocation::CpuToGpu);
    factor.write_bytes(0, bytemuck::cast_slice(&[0.5f32, 0.0, 1.0, 1.0])).unwrap();
    let mut probe = host_buffer("host probe", MemoryLocation::GpuToCpu);
    probe.write_bytes(0, &[0u8; 16]).unwrap();
    let readback = readback_buffer(ctx, "readback", (w * h * 4) as u64);
    ctx.submit_and_wait(|cmd| {
        let imports = Imports::new().buffer("factor", factor.handle(), 16, Access::NONE, Access::COMPUTE_READ).buffer(
            "probe",
            probe.handle(),
            16,
            Access::NONE,
            Access::HOST_READ,
        );
        renderer.record_with_imports(cmd, &boxes_camera(), &imports)?;
        let (output, state) = renderer.output().expect("an image output");
        record_image_to_buffer(ctx, cmd, output, state, &readback);
        Ok::<(), cullgraph::Error>(())
    })
    .unwrap();
    let pixels = u32::from_le_bytes(probe.read_bytes().unwrap()[..4].try_into().unwrap());
    assert_eq!(pixels, w * h, "the pass counted every pixel into the host's buffer");
    // Against the untinted frame: red halved, green gone, blue kept (8-bit rounding aside).
    let plain = Renderer::new(ctx, shaders, boxes_scene(), RenderSettings::new(w, h))
        .unwrap()
        .render_to_image(&boxes_camera())
        .unwrap()
        .1;
    let tinted = readback.read_bytes().unwrap();
    for (p, q) in plain.as_raw().chunks(4).zip(tinted.chunks(4)) {
        assert!(q[0].abs_diff(p[0] / 2) <= 1 && q[1] <= 1 && q[2].abs_diff(p[2]) <= 1, "{p:?} -> {q:?}");
    }
    assert!(plain.as_raw().chunks(4).any(|p| p[0] > 40 && p[1] > 40), "the frame has colour to scale");
}

/// A world renderer on the host's device: the red cube moved between two host-recorded frames
/// shows where it moved to, exactly as an owned-context renderer of the moved world draws it.
#[test]
fn a_moved_object_shows_in_the_hosts_next_frame() {
    let _one_at_a_time = one_host_at_a_time();
    use cullgraph::scene::world::World;
    let (w, h) = (96, 64);
    let moved =
        cullgraph::scene::Transform { linear: glam::Mat3::IDENTITY, translation: glam::DVec3::new(-1.5, 0.5, -2.5) };
    let spec = GraphSpec::default_graph();
    let (reference_before, reference_after) = {
        let gpu = GpuTest::new();
        let (mut world, handles) = World::new(boxes_scene()).unwrap();
        let mut r = Renderer::from_world(&gpu, gpu.shaders(), &world, RenderSettings::new(w, h), &spec).unwrap();
        let before = r.render_to_image(&boxes_camera()).unwrap().1;
        world.set_transform(handles[1], moved).unwrap();
        let (fresh_world, _) = World::new(world.scene().clone()).unwrap();
        let mut fresh =
            Renderer::from_world(&gpu, gpu.shaders(), &fresh_world, RenderSettings::new(w, h), &spec).unwrap();
        (before, fresh.render_to_image(&boxes_camera()).unwrap().1)
    };
    assert_ne!(reference_before, reference_after, "the move shows");

    let host = Host::new();
    let allocator = host.allocator();
    {
        let ctx = GpuContext::from_host(host.handles(&allocator)).unwrap();
        let shaders =
            ShaderCompiler::new(ShaderRoot::Directory(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders").into())).unwrap();
        let (mut world, handles) = World::new(boxes_scene()).unwrap();
        let mut renderer = Renderer::from_world(&ctx, &shaders, &world, RenderSettings::new(w, h), &spec).unwrap();
        let readback = readback_buffer(&ctx, "host readback", (w * h * 4) as u64);
        let d = &host.device;
        let frame = |renderer: &mut Renderer| unsafe {
            let pool = d
                .create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(host.family), None)
                .unwrap();
            let cmd = d
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
                )
                .unwrap()[0];
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            renderer.record(cmd, &boxes_camera()).unwrap();
            let (output, state) = renderer.output().unwrap();
            record_image_to_buffer(&ctx, cmd, output, state, &readback);
            d.end_command_buffer(cmd).unwrap();
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            d.queue_submit(host.queue, &[vk::SubmitInfo::default().command_buffers(&[cmd])], fence).unwrap();
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
            readback.read_bytes().unwrap().to_vec()
        };
        assert_eq!(frame(&mut renderer), reference_before.as_raw().as_slice());
        world.set_transform(handles[1], moved).unwrap();
        let update = renderer.sync(&shaders, &world).unwrap();
        assert_eq!((update.instances_changed, update.relayout), (1, false));
        assert_eq!(frame(&mut renderer), reference_after.as_raw().as_slice(), "the host's frame after the move");
    }
    host.shut_down_clean(allocator);
}
