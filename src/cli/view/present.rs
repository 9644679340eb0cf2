//! Presenting the renderer's frames in a window: a Vulkan surface and swapchain, at most
//! [`FRAMES_IN_FLIGHT`] frames executing at once, the renderer's output blitted onto the
//! acquired image, an optional text panel copied over it, and the presented image read back on
//! request.
//!
//! The renderer records into the presenter's command buffers exactly as an engine's frame
//! would ([`Renderer::record`]); the blit leaves the output in the state the renderer last left
//! it, so that the renderer's own barriers stay right.

use super::text::TextPanel;
use ash::vk;
use cullgraph::gpu::barrier::{cmd_barriers, image_barrier, image_barrier_raw, memory_barrier};
use cullgraph::gpu::error::VkResultExt;
use cullgraph::gpu::{Access, Buffer, BufferDesc, GpuContext, MemoryLocation};
use cullgraph::render::Renderer;
use cullgraph::render::FRAMES_IN_FLIGHT;
use cullgraph::scene::Camera;
use cullgraph::{Error, Result};
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

/// How the swapchain paces frames: `--vsync` forces FIFO; otherwise mailbox or immediate where
/// the surface offers them.
pub fn choose_present_mode(offered: &[vk::PresentModeKHR], vsync: bool) -> vk::PresentModeKHR {
    if vsync {
        return vk::PresentModeKHR::FIFO;
    }
    [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
        .into_iter()
        .find(|m| offered.contains(m))
        .unwrap_or(vk::PresentModeKHR::FIFO)
}

/// The surface format to present in: 8-bit UNORM, because the renderer's output already holds
/// display-encoded (tone-mapped, sRGB-curved) values that an sRGB format would encode twice.
pub fn choose_format(offered: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let unorm = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];
    offered.iter().find(|f| unorm.contains(&f.format) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR).copied()
}

/// What one call of [`Presenter::present`] did.
#[derive(Default)]
pub struct Presented {
    /// The frame index the renderer gave the frame, when one was recorded.
    pub frame: Option<u64>,
    /// A frame recorded earlier whose figures can now be read (its commands have executed).
    pub completed: Option<u64>,
    /// The presented image as RGBA8 rows, when a screenshot was asked for.
    pub screenshot: Option<(u32, u32, Vec<u8>)>,
}

struct Slot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Signalled when the acquired image may be written.
    acquired: vk::Semaphore,
    /// The renderer's frame this slot last carried, not yet reported complete.
    frame: Option<u64>,
    /// Staging for the text panel (grown as needed).
    text: Option<Buffer>,
}

/// A window's surface and swapchain, and the command buffers frames are recorded into.
pub struct Presenter {
    ctx: GpuContext,
    surface_loader: ash::khr::surface::Instance,
    swapchain_loader: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    /// Per swapchain image: signalled when its frame's commands are done; presentation waits.
    rendered: Vec<vk::Semaphore>,
    format: vk::SurfaceFormatKHR,
    extent: vk::Extent2D,
    present_mode: vk::PresentModeKHR,
    vsync: bool,
    /// The size the window asks for; the swapchain follows it when rebuilt.
    wanted: vk::Extent2D,
    /// Rebuild the swapchain before the next frame (out of date, suboptimal or resized).
    stale: bool,
    pool: vk::CommandPool,
    slots: Vec<Slot>,
    next: usize,
}

impl Presenter {
    /// Creates a surface for the window and a swapchain of `width` x `height` (the window's
    /// size). Fails plainly when the device cannot present to this window.
    pub fn new(
        ctx: &GpuContext,
        display: RawDisplayHandle,
        window: RawWindowHandle,
        (width, height): (u32, u32),
        vsync: bool,
    ) -> Result<Self> {
        let surface_loader = ash::khr::surface::Instance::new(ctx.entry(), ctx.instance());
        // SAFETY: the handles come from a live window that outlives the presenter (the caller
        // drops the presenter first).
        let surface = unsafe { ash_window::create_surface(ctx.entry(), ctx.instance(), display, window, None) }
            .vk("vkCreateSurfaceKHR")?;
        // SAFETY: valid handles.
        let supported = unsafe {
            surface_loader.get_physical_device_surface_support(ctx.physical_device(), ctx.queue_family(), surface)
        };
        if !supported.unwrap_or(false) {
            // SAFETY: nothing else uses the surface yet.
            unsafe { surface_loader.destroy_surface(surface, None) };
            return Err(Error::Invalid(format!(
                "{} cannot present to this window (its queue family {} has no presentation support); choose another device with --device",
                ctx.caps().name,
                ctx.queue_family()
            )));
        }
        let swapchain_loader = ash::khr::swapchain::Device::new(ctx.instance(), ctx.device());
        let device = ctx.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family())
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: plain object creation; destroyed in Drop.
        let pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut presenter = Self {
            ctx: ctx.clone(),
            surface_loader,
            swapchain_loader,
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            rendered: Vec::new(),
            format: vk::SurfaceFormatKHR::default(),
            extent: vk::Extent2D::default(),
            present_mode: vk::PresentModeKHR::FIFO,
            vsync,
            wanted: vk::Extent2D { width, height },
            stale: true,
            pool,
            slots: Vec::new(),
            next: 0,
        };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(FRAMES_IN_FLIGHT as u32);
        // SAFETY: the pool was created above.
        let buffers = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?;
        for cmd in buffers {
            let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            // SAFETY: plain object creation; destroyed in Drop.
            let fence = unsafe { device.create_fence(&signalled, None) }.vk("vkCreateFence")?;
            let acquired = unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .vk("vkCreateSemaphore")?;
            presenter.slots.push(Slot { cmd, fence, acquired, frame: None, text: None });
        }
        presenter.rebuild()?;
        Ok(presenter)
    }

    /// The swapchain's size now.
    pub fn extent(&self) -> (u32, u32) {
        (self.extent.width, self.extent.height)
    }

    /// The present mode in use.
    pub fn present_mode(&self) -> vk::PresentModeKHR {
        self.present_mode
    }

    /// The window now has this size (0 when minimised): the swapchain follows before the next
    /// frame.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.wanted = vk::Extent2D { width, height };
        self.stale = true;
    }

    /// Rebuilds the swapchain now if it must be (resized, out of date), so that
    /// [`Presenter::extent`] is the size the next frame is presented at.
    pub fn prepare(&mut self) -> Result<()> {
        if self.stale {
            self.rebuild()?;
        }
        Ok(())
    }

    /// Whether a frame can be presented (a minimised window has no area).
    pub fn can_present(&self) -> bool {
        self.wanted.width > 0 && self.wanted.height > 0
    }

    /// Waits for every frame still executing; returns the frames whose figures can now be
    /// read, oldest first.
    pub fn finish(&mut self) -> Result<Vec<u64>> {
        let mut done = Vec::new();
        for k in 0..self.slots.len() {
            let at = (self.next + k) % self.slots.len();
            let slot = &mut self.slots[at];
            // SAFETY: the fence belongs to this device.
            unsafe { self.ctx.device().wait_for_fences(&[slot.fence], true, u64::MAX) }.vk("vkWaitForFences")?;
            done.extend(slot.frame.take());
        }
        Ok(done)
    }

    /// Records `camera`'s frame through `renderer`, draws `panel` (if any) over it at its
    /// position and presents it. A swapchain out of date is rebuilt and the frame skipped; a
    /// frame that fails to record presents the previous contents' replacement (a cleared
    /// image) and returns the error, with the frames in flight left consistent.
    pub fn present(
        &mut self,
        renderer: &mut Renderer,
        camera: &Camera,
        panels: &[&TextPanel],
        screenshot: bool,
    ) -> Result<Presented> {
        let mut out = Presented::default();
        // A handle on the context (an Arc), so that the device outlives the borrows of `self`
        // below without copying its function table every frame.
        let ctx = self.ctx.clone();
        let device = ctx.device();
        let at = self.next;
        // SAFETY: the fence belongs to this device.
        unsafe { device.wait_for_fences(&[self.slots[at].fence], true, u64::MAX) }.vk("vkWaitForFences")?;
        out.completed = self.slots[at].frame.take();
        if self.stale {
            self.rebuild()?;
        }
        if self.swapchain == vk::SwapchainKHR::null() {
            return Ok(out);
        }
        // SAFETY: the semaphore is unsignalled: its last wait (the slot's last submission) has
        // executed, as the fence above says.
        let acquired = unsafe {
            self.swapchain_loader.acquire_next_image(
                self.swapchain,
                u64::MAX,
                self.slots[at].acquired,
                vk::Fence::null(),
            )
        };
        let index = match acquired {
            Ok((index, suboptimal)) => {
                self.stale |= suboptimal;
                index
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(out);
            }
            Err(result) => return Err(cullgraph::gpu::GpuError::Vk { call: "vkAcquireNextImageKHR", result }.into()),
        };
        let target = self.images[index as usize];
        let slot = &mut self.slots[at];
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the slot's last submission has executed (fence above).
        unsafe {
            device.reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty()).vk("vkResetCommandBuffer")?;
            device.begin_command_buffer(slot.cmd, &begin).vk("vkBeginCommandBuffer")?;
        }
        let recorded = renderer.record(slot.cmd, camera);
        if recorded.is_err() {
            // Whatever the failed record left in the command buffer is dropped: the image is
            // cleared and presented instead, so that the acquired image goes back.
            // SAFETY: the command buffer is recording, not pending.
            unsafe {
                device
                    .reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty())
                    .vk("vkResetCommandBuffer")?;
                device.begin_command_buffer(slot.cmd, &begin).vk("vkBeginCommandBuffer")?;
            }
        }
        let range =
            vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1);
        let transfer_dst = Access::TRANSFER_WRITE;
        let undefined = Access { stage: vk::PipelineStageFlags2::ALL_TRANSFER, ..Access::NONE };
        cmd_barriers(device, slot.cmd, &[], &[image_barrier_raw(target, range, undefined, transfer_dst)]);
        match (&recorded, renderer.output()) {
            (Ok(_), Some((output, state))) => {
                cmd_barriers(device, slot.cmd, &[], &[image_barrier(output, state, Access::TRANSFER_READ)]);
                let src = output.extent();
                let blit = vk::ImageBlit::default()
                    .src_subresource(color_layers())
                    .src_offsets([vk::Offset3D::default(), far_corner(src)])
                    .dst_subresource(color_layers())
                    .dst_offsets([vk::Offset3D::default(), far_corner(self.extent)]);
                let filter = if src == self.extent { vk::Filter::NEAREST } else { vk::Filter::LINEAR };
                // SAFETY: both images are in the layouts named, on this device.
                unsafe {
                    device.cmd_blit_image(
                        slot.cmd,
                        output.handle(),
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        target,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[blit],
                        filter,
                    )
                };
                // Back to the state the renderer last left it in, for its next frame's barriers.
                cmd_barriers(device, slot.cmd, &[], &[image_barrier(output, Access::TRANSFER_READ, state)]);
            }
            _ => {
                let clear = vk::ClearColorValue { float32: [0.05, 0.05, 0.07, 1.0] };
                // SAFETY: the image is in TRANSFER_DST layout.
                unsafe {
                    device.cmd_clear_color_image(
                        slot.cmd,
                        target,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &clear,
                        &[range],
                    )
                };
            }
        }
        let bgra = self.format.format == vk::Format::B8G8R8A8_UNORM;
        let mut staged = Vec::new();
        for panel in panels {
            staged.extend(panel.rgba_bytes(bgra).map(|bytes| (*panel, bytes)));
        }
        if !staged.is_empty() {
            let size: u64 = staged.iter().map(|(_, b)| b.len() as u64).sum();
            if slot.text.as_ref().is_none_or(|b| b.size() < size) {
                slot.text = Some(Buffer::new(
                    &self.ctx,
                    &BufferDesc {
                        name: "view text panel",
                        size,
                        usage: vk::BufferUsageFlags::TRANSFER_SRC,
                        location: MemoryLocation::CpuToGpu,
                    },
                )?);
            }
            let buffer = slot.text.as_mut().expect("made above");
            let mut offset = 0;
            let mut regions = Vec::new();
            for (panel, bytes) in &staged {
                buffer.write_bytes(offset, bytes)?;
                if let Some(region) = panel.copy_region(offset, self.extent.width, self.extent.height) {
                    regions.push(region);
                }
                offset += bytes.len() as u64;
            }
            // The panels are copied over the blit: a write after a write.
            cmd_barriers(device, slot.cmd, &[], &[image_barrier_raw(target, range, transfer_dst, transfer_dst)]);
            if !regions.is_empty() {
                // SAFETY: the image is in TRANSFER_DST layout; the regions lie inside it and
                // inside the staging buffer.
                unsafe {
                    device.cmd_copy_buffer_to_image(
                        slot.cmd,
                        buffer.handle(),
                        target,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &regions,
                    )
                };
            }
        }
        let present_src = Access {
            stage: vk::PipelineStageFlags2::NONE,
            access: vk::AccessFlags2::NONE,
            layout: vk::ImageLayout::PRESENT_SRC_KHR,
        };
        let shot = screenshot.then(|| record_readback(&self.ctx, self.extent, slot.cmd, target, range)).transpose()?;
        let last = if shot.is_some() { Access::TRANSFER_READ } else { transfer_dst };
        cmd_barriers(device, slot.cmd, &[], &[image_barrier_raw(target, range, last, present_src)]);
        // SAFETY: the command buffer is recording.
        unsafe { device.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer")?;
        // SAFETY: the fence is signalled and no submission uses it (waited on above).
        unsafe { device.reset_fences(&[slot.fence]) }.vk("vkResetFences")?;
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(slot.acquired)
            .stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.rendered[index as usize])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let info = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals);
        self.ctx.submit(&info, slot.fence)?;
        slot.frame = recorded.as_ref().ok().copied();
        out.frame = slot.frame;
        self.next = (self.next + 1) % self.slots.len();

        let swapchains = [self.swapchain];
        let indices = [index];
        let wait = [self.rendered[index as usize]];
        let present =
            vk::PresentInfoKHR::default().wait_semaphores(&wait).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: the image was acquired above and its commands signal `wait`.
        let presented = self.ctx.with_queue(|queue| unsafe { self.swapchain_loader.queue_present(queue, &present) });
        match presented {
            Ok(suboptimal) => self.stale |= suboptimal,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(result) => return Err(cullgraph::gpu::GpuError::Vk { call: "vkQueuePresentKHR", result }.into()),
        }
        if let Some(buffer) = shot {
            let fence = self.slots[at].fence;
            // SAFETY: the fence belongs to this device.
            unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")?;
            let mut bytes = buffer.read_bytes()?.to_vec();
            if bgra {
                bytes.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
            }
            out.screenshot = Some((self.extent.width, self.extent.height, bytes));
        }
        recorded?;
        Ok(out)
    }

    /// Builds the swapchain anew for the window's size, after every frame in flight executed.
    /// A window without area leaves no swapchain until it has one again.
    fn rebuild(&mut self) -> Result<()> {
        self.finish_gpu()?;
        let pd = self.ctx.physical_device();
        // SAFETY: valid handles.
        let (caps, formats, modes) = unsafe {
            (
                self.surface_loader
                    .get_physical_device_surface_capabilities(pd, self.surface)
                    .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?,
                self.surface_loader
                    .get_physical_device_surface_formats(pd, self.surface)
                    .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?,
                self.surface_loader
                    .get_physical_device_surface_present_modes(pd, self.surface)
                    .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?,
            )
        };
        let format = choose_format(&formats).ok_or_else(|| {
            Error::Invalid(format!("the window offers no 8-bit UNORM sRGB-nonlinear format (it offers {formats:?})"))
        })?;
        let needed = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
        if !caps.supported_usage_flags.contains(needed) {
            return Err(Error::Invalid(format!(
                "the window's images cannot be copied to and from (usage {:?})",
                caps.supported_usage_flags
            )));
        }
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: self.wanted.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: self.wanted.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        self.destroy_swapchain();
        self.stale = false;
        if extent.width == 0 || extent.height == 0 || !self.can_present() {
            return Ok(());
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let present_mode = choose_present_mode(&modes, self.vsync);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(needed)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite_alpha(caps.supported_composite_alpha))
            .present_mode(present_mode)
            .clipped(true);
        // SAFETY: valid surface; the old swapchain was destroyed above.
        self.swapchain = unsafe { self.swapchain_loader.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        // SAFETY: the swapchain was just created.
        self.images =
            unsafe { self.swapchain_loader.get_swapchain_images(self.swapchain) }.vk("vkGetSwapchainImagesKHR")?;
        for _ in &self.images {
            // SAFETY: plain object creation; destroyed with the swapchain.
            let semaphore = unsafe { self.ctx.device().create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .vk("vkCreateSemaphore")?;
            self.rendered.push(semaphore);
        }
        self.format = format;
        self.extent = extent;
        self.present_mode = present_mode;
        Ok(())
    }

    /// Waits for every submitted frame; their figures stay to be reported by `present`.
    fn finish_gpu(&self) -> Result<()> {
        let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.fence).collect();
        if fences.is_empty() {
            return Ok(());
        }
        // SAFETY: the fences belong to this device.
        unsafe { self.ctx.device().wait_for_fences(&fences, true, u64::MAX) }.vk("vkWaitForFences")?;
        // Presentation may still read the images (and wait on `rendered`).
        self.ctx.wait_idle()?;
        Ok(())
    }

    fn destroy_swapchain(&mut self) {
        let device = self.ctx.device();
        // SAFETY: the queue is idle (finish_gpu), so nothing uses the semaphores or images.
        unsafe {
            for semaphore in self.rendered.drain(..) {
                device.destroy_semaphore(semaphore, None);
            }
            if self.swapchain != vk::SwapchainKHR::null() {
                self.swapchain_loader.destroy_swapchain(self.swapchain, None);
            }
        }
        self.swapchain = vk::SwapchainKHR::null();
        self.images.clear();
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        let _ = self.finish_gpu();
        self.destroy_swapchain();
        let device = self.ctx.device();
        // SAFETY: the queue is idle; these objects belong to this presenter.
        unsafe {
            for slot in self.slots.drain(..) {
                device.destroy_fence(slot.fence, None);
                device.destroy_semaphore(slot.acquired, None);
            }
            device.destroy_command_pool(self.pool, None);
            self.surface_loader.destroy_surface(self.surface, None);
        }
    }
}

/// Records a copy of the swapchain image (in TRANSFER_DST layout, left in TRANSFER_SRC)
/// into a new host buffer.
fn record_readback(
    ctx: &GpuContext,
    extent: vk::Extent2D,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
) -> Result<Buffer> {
    let device = ctx.device();
    let (w, h) = (extent.width, extent.height);
    let buffer = Buffer::new(
        ctx,
        &BufferDesc {
            name: "view screenshot",
            size: w as u64 * h as u64 * 4,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        },
    )?;
    cmd_barriers(device, cmd, &[], &[image_barrier_raw(image, range, Access::TRANSFER_WRITE, Access::TRANSFER_READ)]);
    let region = vk::BufferImageCopy::default().image_subresource(color_layers()).image_extent(vk::Extent3D {
        width: w,
        height: h,
        depth: 1,
    });
    // SAFETY: the image is in TRANSFER_SRC layout and the buffer holds all of it.
    unsafe {
        device.cmd_copy_image_to_buffer(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer.handle(), &[region])
    };
    cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
    Ok(buffer)
}

fn color_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn far_corner(extent: vk::Extent2D) -> vk::Offset3D {
    vk::Offset3D { x: extent.width as i32, y: extent.height as i32, z: 1 }
}

/// Opaque where the compositor allows it; the frame's alpha means nothing to a window.
fn composite_alpha(supported: vk::CompositeAlphaFlagsKHR) -> vk::CompositeAlphaFlagsKHR {
    [vk::CompositeAlphaFlagsKHR::OPAQUE, vk::CompositeAlphaFlagsKHR::INHERIT]
        .into_iter()
        .find(|a| supported.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vsync_forces_fifo_and_otherwise_the_fastest_mode_offered_wins() {
        let all = [vk::PresentModeKHR::FIFO, vk::PresentModeKHR::IMMEDIATE, vk::PresentModeKHR::MAILBOX];
        assert_eq!(choose_present_mode(&all, true), vk::PresentModeKHR::FIFO);
        assert_eq!(choose_present_mode(&all, false), vk::PresentModeKHR::MAILBOX);
        assert_eq!(
            choose_present_mode(&[vk::PresentModeKHR::FIFO, vk::PresentModeKHR::IMMEDIATE], false),
            vk::PresentModeKHR::IMMEDIATE
        );
        assert_eq!(choose_present_mode(&[vk::PresentModeKHR::FIFO], false), vk::PresentModeKHR::FIFO);
    }

    #[test]
    fn only_a_unorm_srgb_nonlinear_format_is_chosen() {
        let f = |format, color_space| vk::SurfaceFormatKHR { format, color_space };
        let srgb = vk::ColorSpaceKHR::SRGB_NONLINEAR;
        let offered = [f(vk::Format::B8G8R8A8_SRGB, srgb), f(vk::Format::B8G8R8A8_UNORM, srgb)];
        assert_eq!(choose_format(&offered).map(|f| f.format), Some(vk::Format::B8G8R8A8_UNORM));
        assert_eq!(choose_format(&offered[..1]), None);
    }
}
