//! Compute and graphics pipelines whose layouts come from shader reflection, bound with push
//! descriptors (set 0) so passes need no descriptor pools.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::reflect::{self, ShaderInterface};
use super::shader::Spirv;
use ash::vk;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, Weak};

/// One resource bound to a binding of set 0 for the next dispatch or draw.
#[derive(Clone, Copy, Debug)]
pub enum Bind {
    /// A storage or uniform buffer (whole range).
    Buffer(u32, vk::Buffer),
    /// A range of a storage or uniform buffer: binding, buffer, offset, bytes.
    BufferRange(u32, vk::Buffer, u64, u64),
    /// A storage image view in `GENERAL` layout.
    StorageImage(u32, vk::ImageView),
    /// A sampled image with its sampler, in the given layout.
    Sampled(u32, vk::ImageView, vk::Sampler, vk::ImageLayout),
    /// A sampled image with its sampler at an element of an array binding (binding, element).
    SampledAt(u32, u32, vk::ImageView, vk::Sampler, vk::ImageLayout),
}

/// Sets the dynamic viewport (depth range 0..1) and scissor of a [`Pipeline::graphics`] draw to the
/// whole of `extent`.
pub fn cmd_set_full_viewport(device: &ash::Device, cmd: vk::CommandBuffer, extent: vk::Extent2D) {
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let scissor = vk::Rect2D { offset: vk::Offset2D::default(), extent };
    // SAFETY: the caller's command buffer is recording.
    unsafe {
        device.cmd_set_viewport(cmd, 0, &[viewport]);
        device.cmd_set_scissor(cmd, 0, &[scissor]);
    }
}

/// One vertex attribute of a graphics pipeline: the shader's input `location`, read from vertex
/// buffer `binding` at `offset` bytes into each vertex's element as `format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexAttribute {
    /// The vertex shader's input location.
    pub location: u32,
    /// The vertex buffer binding it is read from.
    pub binding: u32,
    /// Its format.
    pub format: vk::Format,
    /// Its byte offset in the binding's element.
    pub offset: u32,
}

/// Fixed-function state of a graphics pipeline (dynamic rendering; viewport, scissor and cull
/// mode are dynamic state, counter-clockwise is the front face).
#[derive(Clone, Debug)]
pub struct GraphicsDesc<'a> {
    /// Vertex shader.
    pub vertex: &'a Spirv,
    /// Fragment shader, if any (depth-only passes have none).
    pub fragment: Option<&'a Spirv>,
    /// Stride in bytes of each vertex buffer binding, by binding number; the pipeline declares
    /// the bindings its attributes use (none: no vertex buffer).
    pub vertex_strides: &'a [u32],
    /// The vertex attributes the vertex shader reads.
    pub vertex_attributes: &'a [VertexAttribute],
    /// Formats of the color attachments.
    pub color_formats: &'a [vk::Format],
    /// Depth attachment format (`UNDEFINED` for none).
    pub depth_format: vk::Format,
    /// Depth comparison (reversed-Z uses `GREATER_OR_EQUAL`).
    pub depth_compare: vk::CompareOp,
    /// Whether depth is written.
    pub depth_write: bool,
    /// Samples per pixel.
    pub samples: vk::SampleCountFlags,
    /// Stencil use (only with a depth format that has stencil).
    pub stencil: StencilRule,
    /// What the vertices make: triangles for geometry, lines for debug drawing.
    pub topology: vk::PrimitiveTopology,
    /// Whether every color attachment blends the fragment over what it holds (source alpha,
    /// one minus source alpha; the destination's alpha is kept).
    pub blend: bool,
}

/// What a pipeline does with the stencil aspect.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StencilRule {
    /// Stencil test off.
    #[default]
    Off,
    /// Each sample is written by the first fragment that reaches it: the test passes where the
    /// sample's stencil is 0 and sets it to 1. With depth EQUAL this keeps coplanar and
    /// duplicate triangles from writing a sample twice (the stencil must be cleared to 0).
    FirstFragmentWins,
}

/// Everything a pipeline is made from: equal keys make the same pipeline.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum PipelineKey {
    Compute { name: String, spirv: Spirv, constants: Vec<u32> },
    Graphics { name: String, shaders: Vec<Spirv>, state: Vec<i64> },
}

/// The pipelines alive on a device: making one whose key is here hands out the same objects.
/// A view's resize or a graph's reload builds its passes again, and their pipelines then cost
/// nothing to make, while the runtime being replaced still holds them. Entries whose pipeline
/// was dropped are swept as new ones arrive.
#[derive(Default)]
pub(crate) struct PipelineMemo {
    alive: Mutex<HashMap<PipelineKey, Weak<PipelineObjects>>>,
    /// Pipelines made on the device so far.
    made: std::sync::atomic::AtomicU64,
}

impl PipelineMemo {
    fn get(&self, key: &PipelineKey) -> Option<Pipeline> {
        let memo = self.alive.lock().unwrap_or_else(|p| p.into_inner());
        memo.get(key).and_then(Weak::upgrade).map(Pipeline)
    }

    fn insert(&self, key: PipelineKey, objects: PipelineObjects) -> Pipeline {
        let objects = Arc::new(objects);
        self.made.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut memo = self.alive.lock().unwrap_or_else(|p| p.into_inner());
        memo.retain(|_, weak| weak.strong_count() > 0);
        memo.insert(key, Arc::downgrade(&objects));
        Pipeline(objects)
    }

    /// Pipelines made on the device so far (each shared one counted once).
    pub fn made(&self) -> u64 {
        self.made.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// A pipeline with its reflected layout. Pipelines made from the same shaders and state share
/// their Vulkan objects: a device keeps a memo of the live ones ([`GpuContext::pipelines_made`]).
#[derive(Clone)]
pub struct Pipeline(Arc<PipelineObjects>);

/// A pipeline's Vulkan objects, destroyed with the last [`Pipeline`] that holds them.
pub(crate) struct PipelineObjects {
    shared: Arc<DeviceShared>,
    name: String,
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    bind_point: vk::PipelineBindPoint,
    stages: vk::ShaderStageFlags,
    interface: ShaderInterface,
}

impl Pipeline {
    /// A compute pipeline from one shader.
    pub fn compute(ctx: &GpuContext, name: &str, spirv: &Spirv) -> GpuResult<Self> {
        Self::compute_specialized(ctx, name, spirv, &[])
    }

    /// A compute pipeline from one shader whose specialization constants `0..constants.len()`
    /// (`layout(constant_id = i) const int ...` or `uint`: 32 bits each) take `constants[i]`;
    /// ids the shader does not declare are ignored. The driver compiles with the values known,
    /// so loops bounded by them can be unrolled.
    pub fn compute_specialized(ctx: &GpuContext, name: &str, spirv: &Spirv, constants: &[u32]) -> GpuResult<Self> {
        let key = PipelineKey::Compute { name: name.into(), spirv: spirv.clone(), constants: constants.to_vec() };
        if let Some(made) = ctx.shared.pipelines.get(&key) {
            return Ok(made);
        }
        let interface = reflect_or_err(name, &[spirv])?;
        let stages = vk::ShaderStageFlags::COMPUTE;
        let (set_layout, layout) = create_layout(ctx, &interface, stages)?;
        let mut p = Self::empty(ctx, name, set_layout, layout, vk::PipelineBindPoint::COMPUTE, stages, interface);
        let module = ShaderModule::new(ctx, spirv)?;
        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: i * 4, size: 4 })
            .collect();
        let data: &[u8] = bytemuck::cast_slice(constants);
        let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(data);
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.0)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&specialization);
        }
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
        // SAFETY: valid module and layout.
        let result = unsafe { ctx.device().create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
        module.destroy(ctx);
        p.pipeline = result.map_err(|(_, r)| r).vk("vkCreateComputePipelines")?[0];
        Ok(ctx.shared.pipelines.insert(key, p))
    }

    /// A graphics pipeline for dynamic rendering.
    pub fn graphics(ctx: &GpuContext, name: &str, desc: &GraphicsDesc<'_>) -> GpuResult<Self> {
        Self::graphics_with_views(ctx, name, desc, 0)
    }

    /// A graphics pipeline for dynamic rendering with multiview: it draws inside rendering
    /// whose `viewMask` is `view_mask` (each set bit a layer of the attachments, `gl_ViewIndex`
    /// in the shaders), and needs [`crate::gpu::DeviceCaps::multiview`] when `view_mask` is not 0.
    pub fn graphics_multiview(
        ctx: &GpuContext,
        name: &str,
        desc: &GraphicsDesc<'_>,
        view_mask: u32,
    ) -> GpuResult<Self> {
        if view_mask != 0 && !ctx.caps().multiview {
            return Err(GpuError::InvalidResource {
                name: name.into(),
                reason: format!("view mask {view_mask:#b} needs the multiview feature, which is not on"),
            });
        }
        Self::graphics_with_views(ctx, name, desc, view_mask)
    }

    fn graphics_with_views(ctx: &GpuContext, name: &str, desc: &GraphicsDesc<'_>, view_mask: u32) -> GpuResult<Self> {
        let mut key = graphics_key(name, desc);
        if let PipelineKey::Graphics { state, .. } = &mut key {
            state.push(view_mask as i64);
        }
        if let Some(made) = ctx.shared.pipelines.get(&key) {
            return Ok(made);
        }
        let mut sources = vec![desc.vertex];
        sources.extend(desc.fragment);
        let interface = reflect_or_err(name, &sources)?;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let (set_layout, layout) = create_layout(ctx, &interface, stages)?;
        let mut p = Self::empty(ctx, name, set_layout, layout, vk::PipelineBindPoint::GRAPHICS, stages, interface);

        let vs = ShaderModule::new(ctx, desc.vertex)?;
        let fs = match desc.fragment.map(|f| ShaderModule::new(ctx, f)).transpose() {
            Ok(fs) => fs,
            Err(e) => {
                vs.destroy(ctx);
                return Err(e);
            }
        };
        let mut stage_infos = vec![vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vs.0)
            .name(c"main")];
        if let Some(fs) = &fs {
            stage_infos.push(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::FRAGMENT)
                    .module(fs.0)
                    .name(c"main"),
            );
        }
        let mut used: Vec<u32> = desc.vertex_attributes.iter().map(|a| a.binding).collect();
        used.sort_unstable();
        used.dedup();
        let bindings: Vec<_> = used
            .iter()
            .map(|&binding| {
                vk::VertexInputBindingDescription::default()
                    .binding(binding)
                    .stride(desc.vertex_strides.get(binding as usize).copied().unwrap_or(0))
                    .input_rate(vk::VertexInputRate::VERTEX)
            })
            .collect();
        let attributes: Vec<_> = desc
            .vertex_attributes
            .iter()
            .map(|a| {
                vk::VertexInputAttributeDescription::default()
                    .location(a.location)
                    .binding(a.binding)
                    .format(a.format)
                    .offset(a.offset)
            })
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes);
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(desc.samples);
        let has_depth = desc.depth_format != vk::Format::UNDEFINED;
        // Passes while the sample's stencil is 0 and increments it, so only the first fragment
        // that reaches a sample passes (the reference stays 0).
        let first_wins = vk::StencilOpState::default()
            .fail_op(vk::StencilOp::KEEP)
            .pass_op(vk::StencilOp::INCREMENT_AND_CLAMP)
            .depth_fail_op(vk::StencilOp::KEEP)
            .compare_op(vk::CompareOp::EQUAL)
            .compare_mask(0xFF)
            .write_mask(0xFF)
            .reference(0);
        let stencil_on = desc.stencil == StencilRule::FirstFragmentWins;
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(has_depth)
            .depth_write_enable(has_depth && desc.depth_write)
            .depth_compare_op(desc.depth_compare)
            .stencil_test_enable(stencil_on)
            .front(first_wins)
            .back(first_wins);
        let blend_attachments: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| {
                let state =
                    vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA);
                if desc.blend {
                    state
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
                        .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ZERO)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                        .alpha_blend_op(vk::BlendOp::ADD)
                } else {
                    state
                }
            })
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        // The cull mode is per draw: each face-cull region of a command list sets its own.
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR, vk::DynamicState::CULL_MODE];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .view_mask(view_mask)
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format)
            .stencil_attachment_format(
                if crate::gpu::image::aspect_of(desc.depth_format).contains(vk::ImageAspectFlags::STENCIL) {
                    desc.depth_format
                } else {
                    vk::Format::UNDEFINED
                },
            );
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stage_infos)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering);
        // SAFETY: every pointer lives on this stack frame.
        let result = unsafe { ctx.device().create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
        vs.destroy(ctx);
        if let Some(fs) = fs {
            fs.destroy(ctx);
        }
        p.pipeline = result.map_err(|(_, r)| r).vk("vkCreateGraphicsPipelines")?[0];
        Ok(ctx.shared.pipelines.insert(key, p))
    }

    fn empty(
        ctx: &GpuContext,
        name: &str,
        set_layout: vk::DescriptorSetLayout,
        layout: vk::PipelineLayout,
        bind_point: vk::PipelineBindPoint,
        stages: vk::ShaderStageFlags,
        interface: ShaderInterface,
    ) -> PipelineObjects {
        PipelineObjects {
            shared: ctx.shared.clone(),
            name: name.into(),
            pipeline: vk::Pipeline::null(),
            layout,
            set_layout,
            bind_point,
            stages,
            interface,
        }
    }

    /// What the shaders declare (bindings, push constants, workgroup size).
    pub fn interface(&self) -> &ShaderInterface {
        &self.0.interface
    }

    /// Debug name.
    pub fn name(&self) -> &str {
        &self.0.name
    }

    /// Binds the pipeline.
    pub fn bind(&self, cmd: vk::CommandBuffer) {
        // SAFETY: cmd recording (caller contract).
        unsafe { self.0.shared.device.cmd_bind_pipeline(cmd, self.0.bind_point, self.0.pipeline) };
    }

    /// Pushes descriptors for set 0. Bindings the shader does not use (declared in a variant but
    /// optimized away, say) are skipped.
    pub fn push_bindings(&self, cmd: vk::CommandBuffer, binds: &[Bind]) {
        let binds: Vec<Bind> = binds
            .iter()
            .copied()
            .filter(|b| {
                let n = match *b {
                    Bind::Buffer(n, _)
                    | Bind::BufferRange(n, ..)
                    | Bind::StorageImage(n, _)
                    | Bind::Sampled(n, ..)
                    | Bind::SampledAt(n, ..) => n,
                };
                self.0.interface.bindings.contains_key(&n)
            })
            .collect();
        let binds = binds.as_slice();
        if binds.is_empty() {
            return;
        }
        // One write per binding, or per run of consecutive elements of an array binding (some
        // implementations, lavapipe among them, keep only one of several writes to a binding).
        struct Group {
            binding: u32,
            first: u32,
            buffers: Vec<vk::DescriptorBufferInfo>,
            images: Vec<vk::DescriptorImageInfo>,
            fallback: vk::DescriptorType,
        }
        let mut groups: Vec<Group> = Vec::with_capacity(binds.len());
        for b in binds {
            let (binding, element) = match *b {
                Bind::Buffer(n, _) | Bind::BufferRange(n, ..) | Bind::StorageImage(n, _) | Bind::Sampled(n, ..) => {
                    (n, 0)
                }
                Bind::SampledAt(n, element, ..) => (n, element),
            };
            let image = match *b {
                Bind::Buffer(..) | Bind::BufferRange(..) => None,
                Bind::StorageImage(_, view) => {
                    Some(vk::DescriptorImageInfo::default().image_view(view).image_layout(vk::ImageLayout::GENERAL))
                }
                Bind::Sampled(_, view, sampler, layout) | Bind::SampledAt(_, _, view, sampler, layout) => {
                    Some(vk::DescriptorImageInfo::default().image_view(view).sampler(sampler).image_layout(layout))
                }
            };
            if let (Bind::SampledAt(..), Some(info), Some(last)) = (b, image, groups.last_mut()) {
                if last.binding == binding
                    && !last.images.is_empty()
                    && last.first + last.images.len() as u32 == element
                {
                    last.images.push(info);
                    continue;
                }
            }
            let fallback = match b {
                Bind::Buffer(..) | Bind::BufferRange(..) => vk::DescriptorType::STORAGE_BUFFER,
                Bind::StorageImage(..) => vk::DescriptorType::STORAGE_IMAGE,
                Bind::Sampled(..) | Bind::SampledAt(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            };
            let buffers = match *b {
                Bind::Buffer(_, buffer) => {
                    vec![vk::DescriptorBufferInfo::default().buffer(buffer).range(vk::WHOLE_SIZE)]
                }
                Bind::BufferRange(_, buffer, offset, range) => {
                    vec![vk::DescriptorBufferInfo::default().buffer(buffer).offset(offset).range(range)]
                }
                _ => Vec::new(),
            };
            groups.push(Group { binding, first: element, buffers, images: image.into_iter().collect(), fallback });
        }
        let writes: Vec<vk::WriteDescriptorSet> = groups
            .iter()
            .map(|g| {
                let kind = self.0.interface.bindings.get(&g.binding).map_or(g.fallback, |i| i.kind);
                let w = vk::WriteDescriptorSet::default()
                    .dst_binding(g.binding)
                    .dst_array_element(g.first)
                    .descriptor_type(kind);
                if g.buffers.is_empty() {
                    w.image_info(&g.images)
                } else {
                    w.buffer_info(&g.buffers)
                }
            })
            .collect();
        // SAFETY: infos live until the call returns; cmd recording with this pipeline's layout.
        unsafe {
            self.0.shared.push_descriptor.cmd_push_descriptor_set(cmd, self.0.bind_point, self.0.layout, 0, &writes)
        };
    }

    /// Records a compute pass of one invocation per texel of `extent`: binds the pipeline, pushes
    /// `binds` and the push constants `push`, and dispatches enough workgroups of the shader's
    /// local size to cover `extent`.
    pub fn dispatch_over(&self, cmd: vk::CommandBuffer, binds: &[Bind], push: &[u8], extent: vk::Extent2D) {
        self.bind(cmd);
        self.push_bindings(cmd, binds);
        self.push_constant_bytes(cmd, push);
        let [x, y, _] = self.0.interface.local_size.unwrap_or([1, 1, 1]);
        let groups = (extent.width.div_ceil(x.max(1)).max(1), extent.height.div_ceil(y.max(1)).max(1));
        // SAFETY: cmd recording (caller contract), with this pipeline and its bindings just set.
        unsafe { self.0.shared.device.cmd_dispatch(cmd, groups.0, groups.1, 1) };
    }

    /// Sets push constants from a plain-old-data value.
    pub fn push_constants<T: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, value: &T) {
        self.push_constant_bytes(cmd, bytemuck::bytes_of(value));
    }

    /// Sets push constants from bytes (at most the shader's block size are used).
    pub fn push_constant_bytes(&self, cmd: vk::CommandBuffer, bytes: &[u8]) {
        let len = bytes.len().min(self.0.interface.push_constant_bytes as usize);
        if len == 0 {
            return;
        }
        // SAFETY: cmd recording; the range lies inside the layout's push-constant range.
        unsafe { self.0.shared.device.cmd_push_constants(cmd, self.0.layout, self.0.stages, 0, &bytes[..len]) };
    }
}

impl Drop for PipelineObjects {
    fn drop(&mut self) {
        // SAFETY: the caller guarantees no pending command buffer uses the pipeline.
        unsafe {
            let d = &self.shared.device;
            if self.pipeline != vk::Pipeline::null() {
                d.destroy_pipeline(self.pipeline, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// The key of a graphics pipeline: its shaders and every field of its state.
fn graphics_key(name: &str, desc: &GraphicsDesc<'_>) -> PipelineKey {
    let mut shaders = vec![desc.vertex.clone()];
    shaders.extend(desc.fragment.cloned());
    let mut state = vec![
        desc.vertex_strides.len() as i64,
        desc.depth_format.as_raw() as i64,
        desc.depth_compare.as_raw() as i64,
        desc.depth_write as i64,
        desc.samples.as_raw() as i64,
        desc.stencil as i64,
        desc.topology.as_raw() as i64,
        desc.blend as i64,
        desc.fragment.is_some() as i64,
        desc.color_formats.len() as i64,
    ];
    state.extend(desc.color_formats.iter().map(|f| f.as_raw() as i64));
    state.extend(desc.vertex_strides.iter().map(|&s| s as i64));
    for a in desc.vertex_attributes {
        state.extend([a.location as i64, a.binding as i64, a.format.as_raw() as i64, a.offset as i64]);
    }
    PipelineKey::Graphics { name: name.into(), shaders, state }
}

fn reflect_or_err(name: &str, sources: &[&Spirv]) -> GpuResult<ShaderInterface> {
    let invalid = |e: reflect::ReflectError| GpuError::InvalidResource { name: name.into(), reason: e.to_string() };
    let stages = sources.iter().map(|s| reflect::reflect(s)).collect::<Result<Vec<_>, _>>().map_err(invalid)?;
    reflect::merge(&stages).map_err(invalid)
}

fn create_layout(
    ctx: &GpuContext,
    interface: &ShaderInterface,
    stages: vk::ShaderStageFlags,
) -> GpuResult<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
    let bindings: Vec<_> = interface
        .bindings
        .iter()
        .map(|(&n, info)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(n)
                .descriptor_type(info.kind)
                .descriptor_count(info.count)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default()
        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
        .bindings(&bindings);
    let device = ctx.device();
    // SAFETY: valid device and create info.
    let set_layout = unsafe { device.create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")?;
    let ranges = [vk::PushConstantRange::default().stage_flags(stages).size(interface.push_constant_bytes)];
    let set_layouts = [set_layout];
    let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if interface.push_constant_bytes > 0 {
        layout_info = layout_info.push_constant_ranges(&ranges);
    }
    // SAFETY: valid device and create info.
    match unsafe { device.create_pipeline_layout(&layout_info, None) } {
        Ok(layout) => Ok((set_layout, layout)),
        Err(result) => {
            // SAFETY: unused layout.
            unsafe { device.destroy_descriptor_set_layout(set_layout, None) };
            Err(GpuError::Vk { call: "vkCreatePipelineLayout", result })
        }
    }
}

struct ShaderModule(vk::ShaderModule);

impl ShaderModule {
    fn new(ctx: &GpuContext, spirv: &Spirv) -> GpuResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(spirv);
        // SAFETY: SPIR-V produced by shaderc.
        unsafe { ctx.device().create_shader_module(&info, None) }.vk("vkCreateShaderModule").map(Self)
    }
    fn destroy(self, ctx: &GpuContext) {
        // SAFETY: modules may be destroyed once pipelines are created.
        unsafe { ctx.device().destroy_shader_module(self.0, None) };
    }
}
