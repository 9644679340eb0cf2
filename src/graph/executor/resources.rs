//! The physical resources of a compiled graph: transients placed in shared memory blocks
//! (aliasing), history resources as two copies, outputs with memory of their own.

use crate::gpu::{Buffer, BufferDesc, GpuContext, Image, ImageDesc, MemoryBlock, MemoryLocation};
use crate::graph::compile::memory::{plan_memory, MemoryItem};
use crate::graph::plan::{CompiledGraph, MemoryPlan, ResolvedKind, ResourceClass, ResourceId, Version};
use ash::vk;
use std::collections::HashMap;

/// One Vulkan object.
pub enum Physical {
    /// An image.
    Image(Image),
    /// A buffer.
    Buffer(Buffer),
    /// An imported resource before the host has provided it for a frame.
    Unbound,
}

/// Everything a compiled graph allocates. Field order matters: resources drop before the
/// memory blocks they live in.
pub struct RuntimeResources {
    physical: Vec<Physical>,
    /// Per planned resource: the physical index of the copy written in even and odd frames.
    copies: Vec<Option<[usize; 2]>>,
    /// Per physical resource: every physical resource sharing memory with it (itself included).
    alias_sets: Vec<Vec<usize>>,
    /// The history copies (to clear before their first use).
    history: Vec<usize>,
    /// (planned resource, physical index) of every imported resource a kept pass uses.
    imported: Vec<(ResourceId, usize)>,
    /// Memory as placed with the device's real requirements.
    memory: MemoryPlan,
    _blocks: Vec<MemoryBlock>,
}

impl RuntimeResources {
    /// Creates every resource a kept pass uses.
    pub fn new(ctx: &GpuContext, plan: &CompiledGraph) -> crate::Result<Self> {
        let n = plan.resources.len();
        // Real requirements of the transients, then the same placement the compiler estimated.
        let mut items: Vec<Option<MemoryItem>> = vec![None; n];
        let mut requirements: Vec<Option<vk::MemoryRequirements>> = vec![None; n];
        let mut classes: HashMap<(bool, u32), u32> = HashMap::new();
        for (id, r) in plan.resources.iter().enumerate() {
            let (Some(lifetime), ResourceClass::Transient) = (r.lifetime, r.class) else { continue };
            let req = match &r.kind {
                ResolvedKind::Image { .. } => Image::requirements(ctx, &image_desc(&r.name, &r.kind, false))?,
                ResolvedKind::Buffer { .. } => Buffer::requirements(ctx, &buffer_desc(&r.name, &r.kind, false))?,
            };
            let is_image = matches!(r.kind, ResolvedKind::Image { .. });
            let next = classes.len() as u32;
            let heap_class = *classes.entry((is_image, req.memory_type_bits)).or_insert(next);
            items[id] = Some(MemoryItem { size: req.size, alignment: req.alignment, lifetime, heap_class });
            requirements[id] = Some(req);
        }
        let (placements, heap_sizes) = plan_memory(&items);
        let mut heap_info: Vec<(u64, u32, bool)> = vec![(1, u32::MAX, false); heap_sizes.len()];
        for (id, p) in placements.iter().enumerate() {
            if let (Some(p), Some(req)) = (p, requirements[id]) {
                let h = &mut heap_info[p.heap];
                h.0 = h.0.max(req.alignment);
                h.1 &= req.memory_type_bits;
                h.2 = matches!(plan.resources[id].kind, ResolvedKind::Buffer { .. });
            }
        }
        let blocks = heap_sizes
            .iter()
            .zip(&heap_info)
            .enumerate()
            .map(|(i, (&size, &(align, bits, linear)))| {
                MemoryBlock::new(ctx, &format!("{} transient heap {i}", plan.name), size, align, bits, linear)
                    .map_err(|e| heap_error(plan, &placements, i, e))
            })
            .collect::<crate::Result<Vec<_>>>()?;

        let mut physical = Vec::new();
        let mut copies = vec![None; n];
        let mut history = Vec::new();
        let mut imported = Vec::new();
        let mut placed_at: Vec<Option<(usize, u64, u64)>> = Vec::new();
        for (id, r) in plan.resources.iter().enumerate() {
            // A history resource lives across frames even where no pass uses this frame's
            // version, but one that no kept pass touches at all (neither version) has no usage
            // to create it with.
            let untouched = match &r.kind {
                ResolvedKind::Image { usage, .. } => usage.is_empty(),
                ResolvedKind::Buffer { usage, .. } => usage.is_empty(),
            };
            if (r.lifetime.is_none() && r.class != ResourceClass::History) || untouched {
                continue;
            }
            match r.class {
                ResourceClass::Imported => {
                    physical.push(Physical::Unbound);
                    placed_at.push(None);
                    imported.push((id, physical.len() - 1));
                    copies[id] = Some([physical.len() - 1; 2]);
                }
                ResourceClass::Transient => {
                    let (Some(p), Some(req)) = (placements[id], requirements[id]) else { continue };
                    let block = &blocks[p.heap];
                    let res = match &r.kind {
                        ResolvedKind::Image { .. } => Physical::Image(
                            Image::new_in(ctx, &image_desc(&r.name, &r.kind, false), block, p.offset)
                                .map_err(|e| plan.error_at(id, e))?,
                        ),
                        ResolvedKind::Buffer { .. } => Physical::Buffer(
                            Buffer::new_in(ctx, &buffer_desc(&r.name, &r.kind, false), block, p.offset)
                                .map_err(|e| plan.error_at(id, e))?,
                        ),
                    };
                    physical.push(res);
                    placed_at.push(Some((p.heap, p.offset, req.size)));
                    copies[id] = Some([physical.len() - 1; 2]);
                }
                ResourceClass::Output => {
                    physical.push(create_owned(ctx, &r.name, &r.kind, false).map_err(|e| plan.error_at(id, e))?);
                    placed_at.push(None);
                    copies[id] = Some([physical.len() - 1; 2]);
                }
                ResourceClass::History => {
                    let owned = |copy: &str| {
                        create_owned(ctx, &format!("{} ({copy} frames)", r.name), &r.kind, true)
                            .map_err(|e| plan.error_at(id, e))
                    };
                    let (a, b) = (owned("even")?, owned("odd")?);
                    physical.push(a);
                    physical.push(b);
                    placed_at.push(None);
                    placed_at.push(None);
                    let (ia, ib) = (physical.len() - 2, physical.len() - 1);
                    history.extend([ia, ib]);
                    copies[id] = Some([ia, ib]);
                }
            }
        }
        // Physical resources that overlap in memory.
        let alias_sets = (0..physical.len())
            .map(|i| match placed_at[i] {
                None => vec![i],
                Some((heap, off, size)) => (0..physical.len())
                    .filter(|&j| {
                        placed_at[j].is_some_and(|(h2, o2, s2)| h2 == heap && o2 < off + size && off < o2 + s2)
                    })
                    .collect(),
            })
            .collect();
        let bytes_without_aliasing = requirements.iter().flatten().map(|r| r.size).sum();
        let memory = MemoryPlan {
            placements,
            heaps: heap_sizes.clone(),
            bytes_without_aliasing,
            bytes_with_aliasing: heap_sizes.iter().sum(),
        };
        Ok(Self { physical, copies, alias_sets, history, imported, memory, _blocks: blocks })
    }

    /// Number of physical resources.
    pub fn len(&self) -> usize {
        self.physical.len()
    }

    /// The physical index of `resource`'s `version` in frame `frame`.
    pub fn index(&self, resource: ResourceId, version: Version, frame: u64) -> Option<usize> {
        let copies = self.copies.get(resource).copied().flatten()?;
        let parity = (frame % 2) as usize;
        Some(match version {
            Version::Current => copies[parity],
            Version::Previous => copies[1 - parity],
        })
    }

    /// Device bytes each planned resource occupies (both copies of a history resource; 0 for
    /// imported and unused ones), as the device reports its memory requirements.
    pub fn bytes_per_resource(&self, ctx: &GpuContext) -> Vec<u64> {
        self.copies
            .iter()
            .map(|copies| {
                let Some(copies) = copies else { return 0 };
                let distinct: &[usize] = if copies[0] == copies[1] { &copies[..1] } else { &copies[..] };
                distinct
                    .iter()
                    .map(|&phys| match &self.physical[phys] {
                        // SAFETY: valid device and live image/buffer handles.
                        Physical::Image(i) => unsafe { ctx.device().get_image_memory_requirements(i.handle()) }.size,
                        Physical::Buffer(b) => b.size(),
                        Physical::Unbound => 0,
                    })
                    .sum()
            })
            .collect()
    }

    /// The object at a physical index.
    pub fn get(&self, phys: usize) -> &Physical {
        &self.physical[phys]
    }

    /// Physical resources sharing memory with `phys`.
    pub fn alias_set(&self, phys: usize) -> &[usize] {
        &self.alias_sets[phys]
    }

    /// History copies (cleared before the first frame).
    pub fn history(&self) -> &[usize] {
        &self.history
    }

    /// The buffer holding planned resource `id` in `frame` (for a history resource, the copy
    /// that frame writes), if it is a buffer this graph created.
    pub fn buffer(&self, id: ResourceId, frame: u64) -> Option<&Buffer> {
        match self.get(self.index(id, Version::Current, frame)?) {
            Physical::Buffer(b) => Some(b),
            _ => None,
        }
    }

    /// (planned resource, physical index) of the imported resources.
    pub fn imported(&self) -> &[(ResourceId, usize)] {
        &self.imported
    }

    /// Puts the host's resource for this frame in an imported slot; returns the one it replaces.
    pub fn bind_import(&mut self, phys: usize, resource: Physical) -> Physical {
        std::mem::replace(&mut self.physical[phys], resource)
    }

    /// Transient memory as actually placed.
    pub fn memory(&self) -> &MemoryPlan {
        &self.memory
    }
}

fn image_desc<'a>(name: &'a str, kind: &ResolvedKind, extra_transfer: bool) -> ImageDesc<'a> {
    let ResolvedKind::Image { format, extent, mip_levels, samples, usage } = kind else { unreachable!("image kind") };
    let mut usage = *usage;
    if extra_transfer {
        usage |= vk::ImageUsageFlags::TRANSFER_DST;
    }
    ImageDesc { name, format: *format, extent: *extent, mip_levels: *mip_levels, samples: *samples, usage }
}

fn buffer_desc<'a>(name: &'a str, kind: &ResolvedKind, extra_transfer: bool) -> BufferDesc<'a> {
    let ResolvedKind::Buffer { size, usage } = kind else { unreachable!("buffer kind") };
    // Any buffer may be copied out: counters, captured draw lists, host readbacks.
    let mut usage = *usage | vk::BufferUsageFlags::TRANSFER_SRC;
    if extra_transfer {
        usage |= vk::BufferUsageFlags::TRANSFER_DST;
    }
    BufferDesc { name, size: *size, usage, location: MemoryLocation::GpuOnly }
}

/// The failure to create transient heap `heap`, naming the resources placed in it and where
/// they are declared.
fn heap_error(
    plan: &CompiledGraph,
    placements: &[Option<crate::graph::plan::Placement>],
    heap: usize,
    error: crate::gpu::GpuError,
) -> crate::Error {
    let held: Vec<String> = placements
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_some_and(|p| p.heap == heap))
        .map(|(id, _)| plan.declaration(id))
        .collect();
    crate::Error::Invalid(format!("the memory shared by {}: {error}", held.join("; ")))
}

fn create_owned(ctx: &GpuContext, name: &str, kind: &ResolvedKind, cleared: bool) -> crate::Result<Physical> {
    Ok(match kind {
        ResolvedKind::Image { .. } => {
            let mut desc = image_desc(name, kind, cleared);
            // Outputs are read back or copied by the host.
            desc.usage |= vk::ImageUsageFlags::TRANSFER_SRC;
            Physical::Image(Image::new(ctx, &desc)?)
        }
        ResolvedKind::Buffer { .. } => {
            let mut desc = buffer_desc(name, kind, cleared);
            desc.usage |= vk::BufferUsageFlags::TRANSFER_SRC;
            Physical::Buffer(Buffer::new(ctx, &desc)?)
        }
    })
}
