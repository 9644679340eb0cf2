//! Records a compiled graph: creates its resources and passes once, then per frame emits each
//! pass's planned barriers (filling first-use sources from what last touched the memory),
//! a debug label and a timestamp pair, and the pass's commands.

mod imports;
mod node;
mod resources;
mod tracker;

pub use imports::{Import, Imports};
pub use node::{FrameData, PassContext, PassNode, SlotBindings};
pub use resources::{Physical, RuntimeResources};

use crate::gpu::barrier::{cmd_barriers, image_barrier, memory_barrier};
use crate::gpu::{Access, GpuContext, GpuTimer, Image, PassTiming, ShaderCompiler};
use crate::graph::plan::{CompiledGraph, MemoryPlan, Version};
use ash::vk;
use std::path::Path;
use tracker::Tracker;

/// Frames of one runtime that may execute at once (timestamp pools are ringed this many times).
pub const FRAMES_IN_FLIGHT: usize = 3;

/// A compiled graph with its resources and pass instances, ready to record frames.
pub struct GraphRuntime {
    ctx: GpuContext,
    plan: CompiledGraph,
    nodes: Vec<Box<dyn PassNode>>,
    resources: RuntimeResources,
    tracker: Tracker,
    timers: Vec<GpuTimer>,
    frame: u64,
}

impl GraphRuntime {
    /// Instantiates every pass of `plan` and allocates its resources. User shaders of compute
    /// passes resolve against `graph_dir` (the RON file's folder).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        plan: CompiledGraph,
        graph_dir: Option<&Path>,
    ) -> crate::Result<Self> {
        let resources = RuntimeResources::new(ctx, &plan)?;
        let nodes = plan
            .passes
            .iter()
            .map(|p| crate::passes::create_node(ctx, shaders, p, &plan, graph_dir))
            .collect::<crate::Result<Vec<_>>>()?;
        let scopes = plan.passes.len() as u32 + 1;
        let timers = (0..FRAMES_IN_FLIGHT).map(|_| GpuTimer::new(ctx, scopes)).collect::<Result<Vec<_>, _>>()?;
        Ok(Self { ctx: ctx.clone(), tracker: Tracker::new(resources.len()), plan, nodes, resources, timers, frame: 0 })
    }

    /// The plan being executed.
    pub fn plan(&self) -> &CompiledGraph {
        &self.plan
    }

    /// Transient memory as placed with the device's real requirements.
    pub fn memory(&self) -> &MemoryPlan {
        self.resources.memory()
    }

    /// Records one frame into `cmd`; returns the frame number. `imports` must hold every
    /// resource the graph declares `Imported(..)` (and a kept pass uses); they are left in the
    /// access each import asks for.
    pub fn record(&mut self, cmd: vk::CommandBuffer, inputs: &FrameData<'_>, imports: &Imports) -> crate::Result<u64> {
        let frame = self.frame;
        let device = self.ctx.device().clone();
        self.bind_imports(imports)?;
        if frame == 0 {
            self.clear_history(cmd);
        }
        let timer = &mut self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize];
        timer.reset(cmd);
        timer.begin(cmd, "frame");
        for (pass, node) in self.plan.passes.iter().zip(self.nodes.iter_mut()) {
            let mut memory = Vec::new();
            let mut images = Vec::new();
            for b in &pass.barriers {
                let Some(phys) = self.resources.index(b.resource, b.version, frame) else { continue };
                let src = b.src.unwrap_or_else(|| self.tracker.pending(self.resources.alias_set(phys)));
                match self.resources.get(phys) {
                    Physical::Image(image) => {
                        let old = if b.discard { vk::ImageLayout::UNDEFINED } else { self.tracker.state(phys).layout };
                        images.push(image_barrier(image, Access { layout: old, ..src }, b.dst));
                    }
                    Physical::Buffer(_) => memory.push(memory_barrier(src, b.dst)),
                    Physical::Unbound => {}
                }
            }
            // One global barrier carries every buffer dependency of the pass.
            let merged: Vec<vk::MemoryBarrier2> = memory
                .into_iter()
                .reduce(|a, b| {
                    a.src_stage_mask(a.src_stage_mask | b.src_stage_mask)
                        .src_access_mask(a.src_access_mask | b.src_access_mask)
                        .dst_stage_mask(a.dst_stage_mask | b.dst_stage_mask)
                        .dst_access_mask(a.dst_access_mask | b.dst_access_mask)
                })
                .into_iter()
                .collect();
            cmd_barriers(&device, cmd, &merged, &images);

            self.ctx.begin_label(cmd, &pass.name);
            timer.begin(cmd, &pass.name);
            let rec = PassContext {
                ctx: &self.ctx,
                cmd,
                frame: inputs,
                slots: SlotBindings { pass, resources: &self.resources, frame },
            };
            node.record(&rec)?;
            timer.end(cmd);
            self.ctx.end_label(cmd);
            for b in &pass.bindings {
                if let Some(phys) = self.resources.index(b.resource, b.version, frame) {
                    self.tracker.apply(phys, b.usage.access(), b.usage.writes());
                }
            }
        }
        timer.end(cmd);
        self.release_imports(cmd, imports);
        self.frame += 1;
        Ok(frame)
    }

    /// Checks the host's resources against the graph's declarations and binds them for this frame.
    fn bind_imports(&mut self, imports: &Imports) -> crate::Result<()> {
        use crate::graph::plan::ResolvedKind;
        let invalid = |m: String| crate::Error::Invalid(format!("graph '{}': {m}", self.plan.name));
        for &(id, phys) in self.resources.imported().to_vec().iter() {
            let declared = &self.plan.resources[id];
            let name = &declared.name;
            let given = imports.get(name).ok_or_else(|| {
                invalid(format!(
                    "imported resource '{name}' was not provided (provided: {})",
                    imports.names().collect::<Vec<_>>().join(", ")
                ))
            })?;
            let (resource, current) = match (given, &declared.kind) {
                (
                    Import::Image { host, current, .. },
                    ResolvedKind::Image { format, extent, mip_levels, samples, .. },
                ) => {
                    if host.format != *format
                        || host.extent != *extent
                        || host.samples != *samples
                        || host.mip_levels < *mip_levels
                    {
                        return Err(invalid(format!(
                            "imported image '{name}' is declared {format:?} {}x{} x{} samples, {mip_levels} mips; the host gave {:?} {}x{} x{} samples, {} mips",
                            extent.width,
                            extent.height,
                            samples.as_raw(),
                            host.format,
                            host.extent.width,
                            host.extent.height,
                            host.samples.as_raw(),
                            host.mip_levels
                        )));
                    }
                    (Physical::Image(Image::from_host(&self.ctx, name, host)), *current)
                }
                (Import::Buffer { buffer, size, current, .. }, ResolvedKind::Buffer { size: needed, .. }) => {
                    if size < needed {
                        return Err(invalid(format!(
                            "imported buffer '{name}' needs {needed} bytes; the host gave {size}"
                        )));
                    }
                    (Physical::Buffer(crate::gpu::Buffer::from_host(&self.ctx, name, *buffer, *size)), *current)
                }
                _ => {
                    return Err(invalid(format!(
                        "imported resource '{name}' is an image in one place and a buffer in the other"
                    )))
                }
            };
            self.resources.bind_import(phys, resource);
            self.tracker.set_external(phys, current);
        }
        Ok(())
    }

    /// Leaves every imported resource in the access its host asked for.
    fn release_imports(&mut self, cmd: vk::CommandBuffer, imports: &Imports) {
        let mut memory = Vec::new();
        let mut images = Vec::new();
        for &(id, phys) in self.resources.imported() {
            let after = match imports.get(&self.plan.resources[id].name) {
                Some(Import::Image { after, .. } | Import::Buffer { after, .. }) => *after,
                None => continue,
            };
            let state = self.tracker.state(phys);
            let src = self.tracker.pending(&[phys]);
            match self.resources.get(phys) {
                Physical::Image(image) => {
                    images.push(image_barrier(image, Access { layout: state.layout, ..src }, after))
                }
                _ => memory.push(memory_barrier(src, after)),
            }
            self.tracker.set_external(phys, after);
        }
        cmd_barriers(self.ctx.device(), cmd, &memory, &images);
        for &(_, phys) in self.resources.imported().to_vec().iter() {
            // The host's handles are only valid for this frame.
            self.resources.bind_import(phys, Physical::Unbound);
        }
    }

    /// Output `index` (see [`CompiledGraph::outputs`]) as left by the last recorded frame, with
    /// the access it was last used with.
    pub fn output_image(&self, index: usize) -> Option<(&Image, Access)> {
        let id = *self.plan.outputs.get(index)?;
        let frame = self.frame.checked_sub(1)?;
        let phys = self.resources.index(id, Version::Current, frame)?;
        let Physical::Image(image) = self.resources.get(phys) else { return None };
        let state = self.tracker.state(phys);
        Some((image, Access { stage: state.write.0 | state.read_stages, access: state.write.1, layout: state.layout }))
    }

    /// Output `index` if it is a buffer, as left by the last recorded frame.
    pub fn output_buffer(&self, index: usize) -> Option<&crate::gpu::Buffer> {
        let id = *self.plan.outputs.get(index)?;
        let phys = self.resources.index(id, Version::Current, self.frame.checked_sub(1)?)?;
        match self.resources.get(phys) {
            Physical::Buffer(b) => Some(b),
            _ => None,
        }
    }

    /// Records that the caller used output `index` with `access` after the frame (e.g. a copy),
    /// so the next frame's barriers wait for it.
    pub fn note_output_use(&mut self, index: usize, access: Access) {
        let (Some(&id), Some(frame)) = (self.plan.outputs.get(index), self.frame.checked_sub(1)) else { return };
        if let Some(phys) = self.resources.index(id, Version::Current, frame) {
            self.tracker.apply(phys, access, false);
        }
    }

    /// GPU time per pass of `frame`, once it has completed (empty if its timestamps were reused).
    pub fn timings(&self, frame: u64) -> crate::Result<Vec<PassTiming>> {
        if frame >= self.frame || self.frame - frame > FRAMES_IN_FLIGHT as u64 {
            return Ok(Vec::new());
        }
        Ok(self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize].results()?)
    }

    /// Clears both copies of every history resource to zero (reversed-Z "far", empty bits), so
    /// the first frame's `.prev` reads see defined contents.
    fn clear_history(&mut self, cmd: vk::CommandBuffer) {
        let device = self.ctx.device();
        for &phys in self.resources.history() {
            match self.resources.get(phys) {
                Physical::Image(image) => {
                    cmd_barriers(device, cmd, &[], &[image_barrier(image, Access::NONE, Access::TRANSFER_WRITE)]);
                    let range = image.subresource_range();
                    // SAFETY: image in TRANSFER_DST layout with TRANSFER_DST usage; cmd recording.
                    unsafe {
                        if image.aspect().contains(vk::ImageAspectFlags::DEPTH) {
                            let value = vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 };
                            device.cmd_clear_depth_stencil_image(
                                cmd,
                                image.handle(),
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                &value,
                                &[range],
                            );
                        } else {
                            let value = vk::ClearColorValue { float32: [0.0; 4] };
                            device.cmd_clear_color_image(
                                cmd,
                                image.handle(),
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                &value,
                                &[range],
                            );
                        }
                    }
                }
                Physical::Unbound => continue,
                Physical::Buffer(buffer) => {
                    // SAFETY: buffer with TRANSFER_DST usage; cmd recording.
                    unsafe { device.cmd_fill_buffer(cmd, buffer.handle(), 0, vk::WHOLE_SIZE, 0) };
                }
            }
            self.tracker.apply(phys, Access::TRANSFER_WRITE, true);
        }
    }
}
