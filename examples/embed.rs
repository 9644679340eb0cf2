//! Embedding cullgraph in an engine that owns the Vulkan instance, device, queue and allocator.
//!
//! The "engine" below creates everything with raw `ash`, enabling what cullgraph needs
//! ([`REQUIRED_DEVICE_EXTENSIONS`], the [`OPTIONAL_DEVICE_EXTENSIONS`] the device has, and
//! [`RequiredFeatures`]), hands the handles over with the list of what it enabled, and records
//! cullgraph's frame into its own command buffer, which it submits itself. cullgraph never
//! submits or waits here; the output image is left in the layout and access that
//! `Renderer::output()` reports, for the engine to transition, sample or copy.
//!
//! The world changes every frame, as a game's does: some buildings move, one is added and one
//! removed, and the renderer takes only those changes (`Renderer::sync`).
//!
//! `cargo run --release --example embed`

use ash::vk;
use cullgraph::prelude::*;
use std::ffi::CStr;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // --- the engine's own Vulkan setup ---
    let entry = unsafe { ash::Entry::load()? };
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let instance = unsafe { entry.create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None)? };
    let physical_device =
        unsafe { instance.enumerate_physical_devices()? }.into_iter().next().ok_or("no Vulkan device")?;
    let family = unsafe { instance.get_physical_device_queue_family_properties(physical_device) }
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .ok_or("no graphics+compute queue")? as u32;
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    // What cullgraph needs, and the optional extensions this device has (the MSAA graphs'
    // compressed G-buffer needs VK_EXT_post_depth_coverage).
    let available = unsafe { instance.enumerate_device_extension_properties(physical_device)? };
    let has = |want: &CStr| available.iter().any(|e| e.extension_name_as_c_str() == Ok(want));
    let enabled: Vec<&CStr> = REQUIRED_DEVICE_EXTENSIONS
        .iter()
        .chain(OPTIONAL_DEVICE_EXTENSIONS.iter().filter(|e| has(e)))
        .copied()
        .collect();
    let extensions: Vec<_> = enabled.iter().map(|e| e.as_ptr()).collect();
    let mut features = RequiredFeatures::new();
    let mut features2 = features.chain();
    let device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .push_next(&mut features2);
    let device = unsafe { instance.create_device(physical_device, &device_info, None)? };
    let queue = unsafe { device.get_device_queue(family, 0) };

    // --- hand it to cullgraph ---
    {
        let ctx = GpuContext::from_host(HostHandles {
            entry: entry.clone(),
            instance: instance.clone(),
            physical_device,
            device: device.clone(),
            queue_family_index: family,
            queue,
            allocator: None, // or Some(the engine's Arc<Mutex<gpu_allocator::vulkan::Allocator>>)
            debug_utils: false,
            enabled_device_extensions: enabled.iter().map(|e| (*e).to_owned()).collect(),
        })?;
        let scene = SceneSource::Builtin("city".into()).load(&LoadOptions::default())?;
        let settings = RenderSettings::new(640, 360);
        let camera = scene.default_camera(640.0 / 360.0);
        let (mut world, mut handles) = World::new(scene)?;
        let shaders = ShaderCompiler::new(ShaderRoot::Embedded)?;
        let spec = cullgraph::render::GraphSpec::default_graph();
        let mut renderer = Renderer::from_world(&ctx, &shaders, &world, settings, &spec)?;

        // --- the engine's frames: its command buffer, its submit ---
        unsafe {
            let pool =
                device.create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(family), None)?;
            let cmd = device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
            )?[0];
            let fence = device.create_fence(&vk::FenceCreateInfo::default(), None)?;
            for step in 0..4u32 {
                // The game's update: every 50th building rises a little, one more is built
                // beside the first, and the oldest added one is torn down.
                let moved: Vec<_> = handles
                    .iter()
                    .step_by(50)
                    .map(|&h| {
                        let mut t = world.instance(h).map(|i| i.transform)?;
                        t.translation.y += 0.5;
                        Ok((h, t))
                    })
                    .collect::<Result<_, cullgraph::scene::world::WorldError>>()?;
                world.set_transforms(&moved)?;
                let mut built: Instance = *world.instance(handles[0])?;
                built.transform.translation.x += 3.0 * (step + 1) as f64;
                handles.push(world.insert(built)?);
                if step > 1 {
                    world.remove(handles.remove(1))?;
                }
                let update = renderer.sync(&shaders, &world)?;
                // This world has one renderer: what it applied is no longer needed.
                world.trim_journal(renderer.synced_version().unwrap_or(0));

                device.reset_fences(&[fence])?;
                device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
                let frame = renderer.record(cmd, &camera)?;
                device.end_command_buffer(cmd)?;
                device.queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&[cmd])], fence)?;
                device.wait_for_fences(&[fence], true, u64::MAX)?;
                let total = renderer.completed_timings(frame)?.iter().find(|t| t.name == "frame").map_or(0.0, |t| t.ms);
                println!(
                    "frame {frame}: {} instances changed, {} bytes uploaded, {:.3} ms CPU to sync, GPU {total:.3} ms",
                    update.instances_changed, update.bytes_uploaded, update.cpu_ms
                );
            }
            device.destroy_fence(fence, None);
            device.destroy_command_pool(pool, None);
        }
    } // cullgraph's resources are released here, before the engine destroys its device.

    unsafe {
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    Ok(())
}
