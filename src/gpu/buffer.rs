//! Buffers backed by `gpu-allocator`.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::memory::MemoryBlock;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Largest buffer cullgraph will try to allocate; beyond it a request is an error, not an attempt.
pub const MAX_BUFFER_BYTES: u64 = 1 << 36;

/// What a buffer is for.
#[derive(Clone, Debug)]
pub struct BufferDesc<'a> {
    /// Debug name (shows in validation messages and allocation errors).
    pub name: &'a str,
    /// Size in bytes; 0 is allowed and allocates a minimal buffer.
    pub size: u64,
    /// Vulkan usage flags.
    pub usage: vk::BufferUsageFlags,
    /// GPU-only, upload (CPU to GPU) or readback (GPU to CPU).
    pub location: MemoryLocation,
}

/// A Vulkan buffer with its memory; freed on drop.
///
/// Dropping a buffer the GPU still uses is the caller's error: keep it alive until the work is done.
pub struct Buffer {
    shared: Arc<DeviceShared>,
    handle: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
    name: String,
    /// Owned by a host engine: never destroyed here.
    external: bool,
    /// Created with a device address ([`Buffer::device_address`]).
    addressable: bool,
}

impl Buffer {
    /// Wraps a host engine's buffer of `size` bytes without taking ownership.
    pub fn from_host(ctx: &GpuContext, name: &str, buffer: vk::Buffer, size: u64) -> Self {
        Self {
            shared: ctx.shared.clone(),
            handle: buffer,
            allocation: None,
            size,
            name: name.into(),
            external: true,
            addressable: false,
        }
    }

    /// The buffer's device address, for shaders that reach it through a pointer; `None` where
    /// the device gives storage buffers no addresses, or for a buffer that is not one.
    pub fn device_address(&self) -> Option<u64> {
        if !self.addressable {
            return None;
        }
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.handle);
        // SAFETY: a live buffer of this device, created with SHADER_DEVICE_ADDRESS.
        Some(unsafe { self.shared.device.get_buffer_device_address(&info) })
    }

    /// Creates a buffer and binds fresh memory to it.
    pub fn new(ctx: &GpuContext, desc: &BufferDesc<'_>) -> GpuResult<Self> {
        if desc.size > MAX_BUFFER_BYTES {
            return Err(GpuError::InvalidResource {
                name: desc.name.into(),
                reason: format!("{} bytes exceeds the {} byte limit", desc.size, MAX_BUFFER_BYTES),
            });
        }
        let shared = ctx.shared.clone();
        let device = &shared.device;
        // Vulkan forbids size 0; an empty scene array still needs a bindable buffer.
        let alloc_size = desc.size.max(16);
        let usage = with_address(ctx, desc.usage);
        let info =
            vk::BufferCreateInfo::default().size(alloc_size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let handle = unsafe { device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: handle was just created.
        let requirements = unsafe { device.get_buffer_memory_requirements(handle) };
        let allocation = shared.allocator().allocate(&AllocationCreateDesc {
            name: desc.name,
            requirements,
            location: desc.location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: not bound, not used.
                unsafe { device.destroy_buffer(handle, None) };
                return Err(GpuError::Allocation { name: desc.name.into(), source });
            }
        };
        // SAFETY: memory comes from a compatible allocation of sufficient size.
        let bound = unsafe { device.bind_buffer_memory(handle, allocation.memory(), allocation.offset()) };
        let buffer = Self {
            shared: shared.clone(),
            handle,
            allocation: Some(allocation),
            size: desc.size,
            name: desc.name.into(),
            external: false,
            addressable: with_address(ctx, desc.usage).contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS),
        };
        bound.vk("vkBindBufferMemory")?;
        Ok(buffer)
    }

    /// Creates a device-local buffer inside `block` at `offset` (memory shared with resources
    /// whose lifetimes do not overlap). The block must outlive the buffer.
    pub fn new_in(ctx: &GpuContext, desc: &BufferDesc<'_>, block: &MemoryBlock, offset: u64) -> GpuResult<Self> {
        check_size(desc)?;
        let info = create_info(desc).usage(with_address(ctx, desc.usage));
        // SAFETY: valid device and create info.
        let handle = unsafe { ctx.device().create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let buffer = Self {
            shared: ctx.shared.clone(),
            handle,
            allocation: None,
            size: desc.size,
            name: desc.name.into(),
            external: false,
            addressable: with_address(ctx, desc.usage).contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS),
        };
        // SAFETY: the caller placed the buffer where its requirements fit.
        unsafe { ctx.device().bind_buffer_memory(handle, block.memory(), block.offset() + offset) }
            .vk("vkBindBufferMemory")?;
        Ok(buffer)
    }

    /// What a buffer of `desc` needs from memory, without creating one (Vulkan 1.3 maintenance4).
    pub fn requirements(ctx: &GpuContext, desc: &BufferDesc<'_>) -> GpuResult<vk::MemoryRequirements> {
        check_size(desc)?;
        let info = create_info(desc).usage(with_address(ctx, desc.usage));
        let query = vk::DeviceBufferMemoryRequirements::default().create_info(&info);
        let mut out = vk::MemoryRequirements2::default();
        // SAFETY: valid create info.
        unsafe { ctx.device().get_device_buffer_memory_requirements(&query, &mut out) };
        Ok(out.memory_requirements)
    }

    /// A host-visible buffer filled with `data` (for small, per-frame or upload data).
    pub fn with_data(ctx: &GpuContext, name: &str, usage: vk::BufferUsageFlags, data: &[u8]) -> GpuResult<Self> {
        let mut buffer =
            Self::new(ctx, &BufferDesc { name, size: data.len() as u64, usage, location: MemoryLocation::CpuToGpu })?;
        buffer.write_bytes(0, data)?;
        Ok(buffer)
    }

    /// The Vulkan handle.
    pub fn handle(&self) -> vk::Buffer {
        self.handle
    }

    /// Size in bytes as requested.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Debug name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Copies `data` into a host-visible buffer at `offset`.
    pub fn write_bytes(&mut self, offset: u64, data: &[u8]) -> GpuResult<()> {
        let name = self.name.clone();
        let end = offset.checked_add(data.len() as u64).filter(|&e| e <= self.size);
        let mapped = self.allocation.as_mut().and_then(|a| a.mapped_slice_mut());
        match (mapped, end) {
            (Some(slice), Some(end)) => {
                slice[offset as usize..end as usize].copy_from_slice(data);
                Ok(())
            }
            (None, _) => Err(GpuError::InvalidResource { name, reason: "buffer is not host-visible".into() }),
            (_, None) => Err(GpuError::InvalidResource {
                name,
                reason: format!("write of {} bytes at {offset} overruns {} bytes", data.len(), self.size),
            }),
        }
    }

    /// The memory of a host-visible buffer, to write in place.
    pub fn mapped_mut(&mut self) -> GpuResult<&mut [u8]> {
        let size = self.size as usize;
        match self.allocation.as_mut().and_then(|a| a.mapped_slice_mut()) {
            Some(slice) => Ok(&mut slice[..size]),
            None => {
                Err(GpuError::InvalidResource { name: self.name.clone(), reason: "buffer is not host-visible".into() })
            }
        }
    }

    /// The contents of a host-visible buffer (after the GPU work writing it has completed).
    pub fn read_bytes(&self) -> GpuResult<&[u8]> {
        match self.allocation.as_ref().and_then(|a| a.mapped_slice()) {
            Some(slice) => Ok(&slice[..self.size as usize]),
            None => {
                Err(GpuError::InvalidResource { name: self.name.clone(), reason: "buffer is not host-visible".into() })
            }
        }
    }

    /// Descriptor info covering the whole buffer.
    pub fn descriptor(&self) -> vk::DescriptorBufferInfo {
        vk::DescriptorBufferInfo::default().buffer(self.handle).offset(0).range(vk::WHOLE_SIZE)
    }
}

fn check_size(desc: &BufferDesc<'_>) -> GpuResult<()> {
    if desc.size > MAX_BUFFER_BYTES {
        return Err(GpuError::InvalidResource {
            name: desc.name.into(),
            reason: format!("{} bytes exceeds the {} byte limit", desc.size, MAX_BUFFER_BYTES),
        });
    }
    Ok(())
}

/// `usage`, with device addresses for a storage buffer where the device gives them
/// ([`crate::gpu::DeviceCaps::buffer_addresses`]).
fn with_address(ctx: &GpuContext, usage: vk::BufferUsageFlags) -> vk::BufferUsageFlags {
    if ctx.caps().buffer_addresses && usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER) {
        usage | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
    } else {
        usage
    }
}

fn create_info<'a>(desc: &BufferDesc<'_>) -> vk::BufferCreateInfo<'a> {
    // Vulkan forbids size 0; an empty scene array still needs a bindable buffer.
    vk::BufferCreateInfo::default().size(desc.size.max(16)).usage(desc.usage).sharing_mode(vk::SharingMode::EXCLUSIVE)
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if self.external {
            return;
        }
        if let Some(allocation) = self.allocation.take() {
            // Freeing only fails for foreign allocations, which cannot happen here.
            let _ = self.shared.allocator().free(allocation);
        }
        // SAFETY: the caller guarantees the GPU no longer uses the buffer.
        unsafe { self.shared.device.destroy_buffer(self.handle, None) };
    }
}

impl std::fmt::Debug for Buffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffer").field("name", &self.name).field("size", &self.size).finish()
    }
}
