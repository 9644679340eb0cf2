//! The instance records bound in ranges: one storage buffer binding addresses at most
//! `maxStorageBufferRange` bytes (2^32 - 1 on NVIDIA and AMD, a 32-bit field of the Vulkan
//! limits), and 10^8 records of 64 bytes take 6.4 GB. Shaders read them through
//! `shaders/common/instance_ranges.glsl`: range 0 at the binding the shader names, range 1 at a
//! fixed binding after the textures'. (Two ranges rather than more: a pipeline pushes at most 32
//! descriptors, `maxPushDescriptors` on lavapipe and NVIDIA, and the lighting of a visibility
//! buffer with textures and shadows already pushes 30.)

use super::cull_data::GpuCullRecord;
use super::gpu_types::GpuInstance;
use crate::gpu::{Bind, Buffer};
use ash::vk;
use std::mem::size_of;

/// Records per range (`INSTANCE_RANGE_RECORDS` in the shader): the most that fit 2^32 - 1 bytes.
pub const RANGE_RECORDS: u64 = (1 << 26) - 1;
/// Ranges the shaders declare.
pub const RANGES: u64 = 2;
/// Binding of range 1 of the instance records (`INSTANCE_RANGE_BINDING`).
pub const INSTANCE_RANGE_BINDING: u32 = 32;
/// Binding of range 1 of the previous records (`PREV_INSTANCE_RANGE_BINDING`).
pub const PREV_INSTANCE_RANGE_BINDING: u32 = 33;

const RECORD_BYTES: u64 = size_of::<GpuInstance>() as u64;
const RANGE_BYTES: u64 = RANGE_RECORDS * RECORD_BYTES;

/// The binds of `records` (instance records, or previous ones) for a shader that names range 0
/// `binding` and range 1 `range_binding`, each at most `max_range` bytes (the device's
/// `maxStorageBufferRange`; a buffer with room to grow may be larger, but no record past
/// [`most_instances`] is read). A range past the buffer's end repeats the first (never read:
/// no instance id reaches it).
pub fn binds(records: &Buffer, binding: u32, range_binding: u32, max_range: u64) -> [Bind; RANGES as usize] {
    let size = records.size();
    let widest = RANGE_BYTES.min(max_range);
    std::array::from_fn(|k| {
        let number = if k == 0 { binding } else { range_binding };
        let offset = k as u64 * RANGE_BYTES;
        match offset < size {
            true => Bind::BufferRange(number, records.handle(), offset, (size - offset).min(widest)),
            false => Bind::BufferRange(number, records.handle(), 0, size.min(widest)),
        }
    })
}

/// The most instances a device renders, from its `maxStorageBufferRange`: the cull records
/// (32 bytes each) are bound whole, the instance records in [`RANGES`] ranges of [`RANGE_RECORDS`]
/// where the device binds that much, else in one. 134 217 726 instances where the range is
/// 2^32 - 1, as on NVIDIA and AMD.
pub fn most_instances(max_storage_buffer_range: u64) -> u64 {
    let records = match max_storage_buffer_range >= RANGE_BYTES {
        true => RANGES * RANGE_RECORDS,
        false => max_storage_buffer_range / RECORD_BYTES,
    };
    records.min(max_storage_buffer_range / size_of::<GpuCullRecord>() as u64)
}

/// Refuses more instances than [`most_instances`] allows on this device.
pub(crate) fn check_instance_count(instances: u64, limits: &vk::PhysicalDeviceLimits) -> crate::Result<()> {
    let range = limits.max_storage_buffer_range as u64;
    let most = most_instances(range);
    match instances > most {
        true => Err(crate::Error::Invalid(format!(
            "the scene has {instances} instances; this device renders at most {most}: its storage buffer bindings \
             address at most {range} bytes (maxStorageBufferRange), and the cull records (32 bytes per instance) \
             are bound whole"
        ))),
        false => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_gib_bindings_render_more_than_10_to_the_8_instances() {
        assert_eq!(most_instances(u32::MAX as u64), (1 << 27) - 2);
        // The Vulkan minimum: the records in one binding.
        assert_eq!(most_instances(1 << 27), (1 << 27) / 64);
    }

    #[test]
    fn more_instances_than_the_bindings_address_are_refused_naming_the_limit() {
        let limits = vk::PhysicalDeviceLimits { max_storage_buffer_range: 1 << 27, ..Default::default() };
        assert!(check_instance_count(2_097_152, &limits).is_ok());
        let err = check_instance_count(2_097_153, &limits).unwrap_err().to_string();
        assert!(err.contains("2097153 instances") && err.contains("at most 2097152"), "{err}");
        assert!(err.contains("maxStorageBufferRange"), "{err}");
    }
}
