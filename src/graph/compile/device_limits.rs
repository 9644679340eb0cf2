//! What the device would reject in a graph compiled for one output size and scene, found before
//! anything is created: buffers bound beyond the range a descriptor can address, images and
//! attachments beyond the device's dimensions, and attachments of one pass that do not cover
//! the same area (its render area is one attachment's size). Reported at the resource's
//! declaration, naming the pass, the slot and the limit.

use super::resolve::Resolved;
use crate::graph::error::Pos;
use crate::graph::usage::Usage;
use crate::graph::validated::ValidatedGraph;
use ash::vk;

/// The limits of the device a graph is loaded for ([`crate::graph::Environment::limits`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceLimits {
    /// The device's name, for messages.
    pub device: String,
    /// `maxStorageBufferRange`: the most bytes one storage-buffer binding addresses.
    pub max_storage_buffer_range: u64,
    /// `maxUniformBufferRange`: the most bytes one uniform-buffer binding addresses.
    pub max_uniform_buffer_range: u64,
    /// `maxImageDimension2D`.
    pub max_image_dimension_2d: u32,
    /// `maxFramebufferWidth` and `maxFramebufferHeight`: the largest render area.
    pub max_framebuffer: vk::Extent2D,
    /// Optional features the device has enabled that kinds may need, by name (the host's
    /// names: cullgraph's renderer says `post_depth_coverage`, `fragment_shader_sample_interlock`
    /// and `subgroup_compute`, for basic, vote, arithmetic and ballot subgroup operations in
    /// compute shaders).
    pub features: Vec<String>,
    /// What one workgroup of a compute shader may use.
    pub compute: ComputeLimits,
}

/// The limits on one workgroup of a compute shader, which its pipeline must keep to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ComputeLimits {
    /// `maxComputeSharedMemorySize`: bytes of `shared` memory.
    pub max_shared_memory_bytes: u32,
    /// `maxComputeWorkGroupSize`: `local_size_x/y/z`, each.
    pub max_work_group_size: [u32; 3],
    /// `maxComputeWorkGroupInvocations`: `local_size_x * local_size_y * local_size_z`.
    pub max_work_group_invocations: u32,
}

impl ComputeLimits {
    /// What every Vulkan device allows (the minimums the specification requires), for checks
    /// made without a device.
    pub const VULKAN_MINIMUM: Self =
        Self { max_shared_memory_bytes: 16384, max_work_group_size: [128, 128, 64], max_work_group_invocations: 128 };
}

impl DeviceLimits {
    /// Whether the device has the optional feature `name` enabled.
    pub fn has(&self, name: &str) -> bool {
        self.features.iter().any(|f| f == name)
    }

    /// The limits of `limits`, a device called `device` with the optional `features`.
    pub fn from_vulkan(device: &str, limits: &vk::PhysicalDeviceLimits, features: Vec<String>) -> Self {
        Self {
            device: device.to_string(),
            features,
            max_storage_buffer_range: limits.max_storage_buffer_range as u64,
            max_uniform_buffer_range: limits.max_uniform_buffer_range as u64,
            max_image_dimension_2d: limits.max_image_dimension2_d,
            max_framebuffer: vk::Extent2D {
                width: limits.max_framebuffer_width,
                height: limits.max_framebuffer_height,
            },
            compute: ComputeLimits {
                max_shared_memory_bytes: limits.max_compute_shared_memory_size,
                max_work_group_size: limits.max_compute_work_group_size,
                max_work_group_invocations: limits.max_compute_work_group_invocations,
            },
        }
    }
}

/// `(position, message)` for everything of the kept passes (`keep[p]`) the device would reject,
/// `resolved[r]` being resource `r` as compiled. Attachment areas are checked without a device
/// too; the rest needs `graph.limits`.
pub(crate) fn limit_errors(graph: &ValidatedGraph, keep: &[bool], resolved: &[Resolved]) -> Vec<(Pos, String)> {
    let mut out = Vec::new();
    let limits = graph.limits.as_ref();
    let at = |r: usize| graph.resources[r].pos;
    let name = |r: usize| graph.resources[r].name.as_str();
    if let Some(limits) = limits {
        for (r, res) in resolved.iter().enumerate() {
            let Resolved::Image { extent, .. } = res else { continue };
            let largest = extent.width.max(extent.height);
            if largest > limits.max_image_dimension_2d {
                let message = format!(
                    "image '{}' is {}x{}; {} allows at most {} in each dimension (maxImageDimension2D)",
                    name(r),
                    extent.width,
                    extent.height,
                    limits.device,
                    limits.max_image_dimension_2d
                );
                out.push((at(r), message));
            }
        }
    }
    for (pass, _) in graph.passes.iter().zip(keep).filter(|(_, k)| **k) {
        let mut attachments: Vec<(usize, &str, vk::Extent2D)> = Vec::new();
        for binding in &pass.bindings {
            let r = binding.resource;
            match (resolved.get(r), binding.usage) {
                (Some(Resolved::Buffer(bytes)), usage) => {
                    let Some(limits) = limits else { continue };
                    let (limit, what) = match usage {
                        Usage::StorageBufferRead(_)
                        | Usage::StorageBufferWrite(_)
                        | Usage::StorageBufferReadWrite(_) => {
                            (limits.max_storage_buffer_range, "maxStorageBufferRange")
                        }
                        Usage::Uniform(_) => (limits.max_uniform_buffer_range, "maxUniformBufferRange"),
                        _ => continue,
                    };
                    if *bytes > limit {
                        let message = format!(
                            "buffer '{}' is {bytes} bytes, but pass '{}' binds it as \"{}\" and {} lets one binding \
                             address at most {limit} bytes ({what}): size it down, or split it over several buffers",
                            name(r),
                            pass.name,
                            binding.written_slot,
                            limits.device
                        );
                        out.push((at(r), message));
                    }
                }
                (Some(Resolved::Image { extent, .. }), usage) if usage.is_attachment() => {
                    if let Some(limits) = limits {
                        let max = limits.max_framebuffer;
                        if extent.width > max.width || extent.height > max.height {
                            let message = format!(
                                "pass '{}' renders into '{}' ({}x{}); {} renders at most {}x{} \
                                 (maxFramebufferWidth/Height)",
                                pass.name,
                                name(r),
                                extent.width,
                                extent.height,
                                limits.device,
                                max.width,
                                max.height
                            );
                            out.push((at(r), message));
                        }
                    }
                    attachments.push((r, binding.written_slot.as_str(), *extent));
                }
                _ => {}
            }
        }
        // The render area covers the largest attachment; every other must be as large.
        let Some(&(largest, slot, area)) =
            attachments.iter().max_by_key(|(_, _, e)| (e.width as u64) * (e.height as u64))
        else {
            continue;
        };
        for &(r, smaller_slot, extent) in attachments.iter().filter(|a| a.2 != area) {
            let message = format!(
                "pass '{}' renders {}x{} (\"{slot}\" '{}'), but its \"{smaller_slot}\" '{}' is {}x{}: the \
                 attachments of one pass must be the same size",
                pass.name,
                area.width,
                area.height,
                name(largest),
                name(r),
                extent.width,
                extent.height
            );
            out.push((at(r), message));
        }
    }
    out.sort_by_key(|(pos, m)| (*pos, m.clone()));
    out.dedup();
    out
}
