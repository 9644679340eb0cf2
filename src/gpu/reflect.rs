//! SPIR-V reflection (through `spirq`): which descriptors, push constants, workgroup size and
//! workgroup memory a shader declares, so pipeline layouts are derived from the shader instead of
//! written twice and what a device bounds can be checked before a pipeline is created.

use ash::vk;
use spirq::prelude::*;
use spirq::ty::ImageFormat;
use std::collections::BTreeMap;

/// One descriptor binding of set 0.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BindingInfo {
    /// Variable name in the shader (block instance or sampler name), if any.
    pub name: Option<String>,
    /// Vulkan descriptor type.
    pub kind: vk::DescriptorType,
    /// Array size (1 for a single descriptor).
    pub count: u32,
    /// Whether the shader may write through it (storage buffers and images not declared readonly).
    pub writes: bool,
    /// For an image: what the shader declares of it.
    pub image: Option<ImageDecl>,
}

/// What a shader declares of an image it binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageDecl {
    /// The dimensionality (`sampler2D`: 2D, `sampler3D`: 3D, `samplerCube`: cube).
    pub dim: ImageDim,
    /// Arrayed (`sampler2DArray`, `image2DArray`): the view must have array layers.
    pub arrayed: bool,
    /// Multisampled (`sampler2DMS`, `image2DMS`).
    pub multisampled: bool,
    /// The scalar type a sampled image returns (`sampler2D`: float, `usampler2D`: uint,
    /// `isampler2D`: int); `None` for storage images, whose format qualifier decides.
    pub sampled: Option<SampledScalar>,
    /// A storage image's format qualifier (`rgba8`: `R8G8B8A8_UNORM`), which must be the format
    /// of the image view bound there; `None` for sampled images and for storage images declared
    /// without one.
    pub format: Option<vk::Format>,
}

impl ImageDecl {
    /// The GLSL type that declares it, e.g. `usampler2DMS`, `image2DArray`, `samplerCube`
    /// (storage: whether it is a storage image).
    pub fn glsl_type(&self, storage: bool) -> String {
        let prefix = match (self.sampled, self.format.and_then(format_qualifier)) {
            (Some(SampledScalar::Int), _) => "i",
            (Some(SampledScalar::Uint), _) => "u",
            (None, Some(q)) if q.ends_with("ui") => "u",
            (None, Some(q)) if q.ends_with('i') => "i",
            _ => "",
        };
        let dim = match self.dim {
            ImageDim::D1 => "1D",
            ImageDim::D2 => "2D",
            ImageDim::D3 => "3D",
            ImageDim::Cube => "Cube",
            ImageDim::Rect => "2DRect",
            ImageDim::Buffer => "Buffer",
            ImageDim::SubpassData => "SubpassData",
            ImageDim::Other => "",
        };
        let base = if storage { "image" } else { "sampler" };
        let ms = if self.multisampled { "MS" } else { "" };
        let array = if self.arrayed { "Array" } else { "" };
        format!("{prefix}{base}{dim}{ms}{array}")
    }
}

/// The dimensionality of an image a shader declares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageDim {
    /// `*1D`.
    D1,
    /// `*2D`.
    D2,
    /// `*3D`.
    D3,
    /// `*Cube`.
    Cube,
    /// `*2DRect`.
    Rect,
    /// `*Buffer` (texel buffers).
    Buffer,
    /// `subpassInput`.
    SubpassData,
    /// Anything newer SPIR-V adds.
    Other,
}

impl From<spirq::ty::Dim> for ImageDim {
    fn from(dim: spirq::ty::Dim) -> Self {
        use spirq::ty::Dim;
        match dim {
            Dim::Dim1D => Self::D1,
            Dim::Dim2D => Self::D2,
            Dim::Dim3D => Self::D3,
            Dim::DimCube => Self::Cube,
            Dim::DimRect => Self::Rect,
            Dim::DimBuffer => Self::Buffer,
            Dim::DimSubpassData => Self::SubpassData,
            _ => Self::Other,
        }
    }
}

/// The GLSL format qualifiers of storage images with the Vulkan format each one means (the
/// Vulkan specification's "SPIR-V Image Format" compatibility table): a storage image view must
/// have exactly the format its declaration names.
const STORAGE_FORMATS: &[(ImageFormat, &str, vk::Format)] = &[
    (ImageFormat::Rgba32f, "rgba32f", vk::Format::R32G32B32A32_SFLOAT),
    (ImageFormat::Rgba16f, "rgba16f", vk::Format::R16G16B16A16_SFLOAT),
    (ImageFormat::R32f, "r32f", vk::Format::R32_SFLOAT),
    (ImageFormat::Rgba8, "rgba8", vk::Format::R8G8B8A8_UNORM),
    (ImageFormat::Rgba8Snorm, "rgba8_snorm", vk::Format::R8G8B8A8_SNORM),
    (ImageFormat::Rg32f, "rg32f", vk::Format::R32G32_SFLOAT),
    (ImageFormat::Rg16f, "rg16f", vk::Format::R16G16_SFLOAT),
    (ImageFormat::R11fG11fB10f, "r11f_g11f_b10f", vk::Format::B10G11R11_UFLOAT_PACK32),
    (ImageFormat::R16f, "r16f", vk::Format::R16_SFLOAT),
    (ImageFormat::Rgba16, "rgba16", vk::Format::R16G16B16A16_UNORM),
    (ImageFormat::Rgb10A2, "rgb10_a2", vk::Format::A2B10G10R10_UNORM_PACK32),
    (ImageFormat::Rg16, "rg16", vk::Format::R16G16_UNORM),
    (ImageFormat::Rg8, "rg8", vk::Format::R8G8_UNORM),
    (ImageFormat::R16, "r16", vk::Format::R16_UNORM),
    (ImageFormat::R8, "r8", vk::Format::R8_UNORM),
    (ImageFormat::Rgba16Snorm, "rgba16_snorm", vk::Format::R16G16B16A16_SNORM),
    (ImageFormat::Rg16Snorm, "rg16_snorm", vk::Format::R16G16_SNORM),
    (ImageFormat::Rg8Snorm, "rg8_snorm", vk::Format::R8G8_SNORM),
    (ImageFormat::R16Snorm, "r16_snorm", vk::Format::R16_SNORM),
    (ImageFormat::R8Snorm, "r8_snorm", vk::Format::R8_SNORM),
    (ImageFormat::Rgba32i, "rgba32i", vk::Format::R32G32B32A32_SINT),
    (ImageFormat::Rgba16i, "rgba16i", vk::Format::R16G16B16A16_SINT),
    (ImageFormat::Rgba8i, "rgba8i", vk::Format::R8G8B8A8_SINT),
    (ImageFormat::R32i, "r32i", vk::Format::R32_SINT),
    (ImageFormat::Rg32i, "rg32i", vk::Format::R32G32_SINT),
    (ImageFormat::Rg16i, "rg16i", vk::Format::R16G16_SINT),
    (ImageFormat::Rg8i, "rg8i", vk::Format::R8G8_SINT),
    (ImageFormat::R16i, "r16i", vk::Format::R16_SINT),
    (ImageFormat::R8i, "r8i", vk::Format::R8_SINT),
    (ImageFormat::Rgba32ui, "rgba32ui", vk::Format::R32G32B32A32_UINT),
    (ImageFormat::Rgba16ui, "rgba16ui", vk::Format::R16G16B16A16_UINT),
    (ImageFormat::Rgba8ui, "rgba8ui", vk::Format::R8G8B8A8_UINT),
    (ImageFormat::R32ui, "r32ui", vk::Format::R32_UINT),
    (ImageFormat::Rgb10a2ui, "rgb10_a2ui", vk::Format::A2B10G10R10_UINT_PACK32),
    (ImageFormat::Rg32ui, "rg32ui", vk::Format::R32G32_UINT),
    (ImageFormat::Rg16ui, "rg16ui", vk::Format::R16G16_UINT),
    (ImageFormat::Rg8ui, "rg8ui", vk::Format::R8G8_UINT),
    (ImageFormat::R16ui, "r16ui", vk::Format::R16_UINT),
    (ImageFormat::R8ui, "r8ui", vk::Format::R8_UINT),
    (ImageFormat::R64ui, "r64ui", vk::Format::R64_UINT),
    (ImageFormat::R64i, "r64i", vk::Format::R64_SINT),
];

/// The GLSL format qualifier that declares a storage image of `format` (`R8G8B8A8_UNORM`:
/// `rgba8`); `None` if no qualifier names it (sRGB, BGRA, depth and packed formats other than
/// `r11f_g11f_b10f` and `rgb10_a2`), so it cannot be a storage image of a graph pass.
pub fn format_qualifier(format: vk::Format) -> Option<&'static str> {
    STORAGE_FORMATS.iter().find(|(_, _, f)| *f == format).map(|(_, q, _)| *q)
}

fn storage_format(format: ImageFormat) -> Option<vk::Format> {
    STORAGE_FORMATS.iter().find(|(f, _, _)| *f == format).map(|(_, _, v)| *v)
}

/// The scalar type a sampled image returns; the bound image's format must give the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampledScalar {
    /// `sampler*`: float (UNORM, SNORM, SFLOAT, SRGB and depth formats).
    Float,
    /// `isampler*`: signed integer (SINT formats).
    Int,
    /// `usampler*`: unsigned integer (UINT formats).
    Uint,
}

/// What `ty`, a descriptor's type, declares of an image.
fn image_decl(ty: &Type) -> Option<ImageDecl> {
    let sampled = |t: &spirq::ty::SampledImageType| {
        let scalar = match t.scalar_ty {
            spirq::ty::ScalarType::Integer { is_signed: true, .. } => SampledScalar::Int,
            spirq::ty::ScalarType::Integer { is_signed: false, .. } => SampledScalar::Uint,
            _ => SampledScalar::Float,
        };
        ImageDecl {
            dim: t.dim.into(),
            arrayed: t.is_array,
            multisampled: t.is_multisampled,
            sampled: Some(scalar),
            format: None,
        }
    };
    match ty {
        Type::CombinedImageSampler(t) => Some(sampled(&t.sampled_image_ty)),
        Type::SampledImage(t) => Some(sampled(t)),
        Type::StorageImage(t) => Some(ImageDecl {
            dim: t.dim.into(),
            arrayed: t.is_array,
            multisampled: t.is_multisampled,
            sampled: None,
            format: storage_format(t.fmt),
        }),
        _ => None,
    }
}

/// What one shader module declares.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShaderInterface {
    /// Bindings of descriptor set 0, by binding number.
    pub bindings: BTreeMap<u32, BindingInfo>,
    /// Bytes of the push-constant block (0 if none).
    pub push_constant_bytes: u32,
    /// `local_size_x/y/z` of a compute shader.
    pub local_size: Option<[u32; 3]>,
    /// Bytes of workgroup (`shared`) memory, counted conservatively
    /// ([`workgroup_memory_bytes`](super::workgroup_memory::workgroup_memory_bytes)).
    pub workgroup_memory_bytes: u64,
}

/// Why reflection refused a shader.
#[derive(Debug, thiserror::Error)]
pub enum ReflectError {
    /// spirq could not parse the module.
    #[error("SPIR-V reflection failed: {0}")]
    Parse(String),
    /// Only descriptor set 0 exists (push descriptors).
    #[error("binding '{name}' uses descriptor set {set}; cullgraph shaders use set 0 only")]
    WrongSet {
        /// Variable name.
        name: String,
        /// The set it asked for.
        set: u32,
    },
    /// The shared variables could not be sized.
    #[error("cannot count the shader's shared memory: {0}")]
    WorkgroupMemory(String),
    /// Two stages declare the same binding differently.
    #[error("binding {binding} is declared as {a:?} in one stage and {b:?} in another")]
    Conflict {
        /// Binding number.
        binding: u32,
        /// One declaration.
        a: vk::DescriptorType,
        /// The other.
        b: vk::DescriptorType,
    },
}

/// Reflects the `main` entry point of a SPIR-V module.
pub fn reflect(spirv: &[u32]) -> Result<ShaderInterface, ReflectError> {
    let entries = ReflectConfig::new()
        .spv(spirv)
        .ref_all_rscs(false)
        .combine_img_samplers(true)
        .reflect()
        .map_err(|e| ReflectError::Parse(e.to_string()))?;
    let entry = entries
        .into_iter()
        .find(|e| e.name == "main")
        .ok_or_else(|| ReflectError::Parse("no entry point 'main'".into()))?;
    let mut out = ShaderInterface {
        workgroup_memory_bytes: super::workgroup_memory::workgroup_memory_bytes(spirv)
            .map_err(ReflectError::WorkgroupMemory)?,
        ..ShaderInterface::default()
    };
    for var in &entry.vars {
        match var {
            Variable::Descriptor { name, desc_bind, desc_ty, nbind, ty, .. } => {
                if desc_bind.set() != 0 {
                    return Err(ReflectError::WrongSet {
                        name: name.clone().unwrap_or_default(),
                        set: desc_bind.set(),
                    });
                }
                let (kind, writes) = descriptor_kind(desc_ty);
                out.bindings.insert(
                    desc_bind.bind(),
                    BindingInfo { name: name.clone(), kind, count: (*nbind).max(1), writes, image: image_decl(ty) },
                );
            }
            Variable::PushConstant { ty, .. } => {
                out.push_constant_bytes = ty.nbyte().unwrap_or(0) as u32;
            }
            _ => {}
        }
    }
    for mode in &entry.exec_modes {
        // SPIR-V 1.6 output uses LocalSizeId (constant ids); older output LocalSize (literals).
        let is_local_size =
            matches!(mode.exec_mode, spirq::spirv::ExecutionMode::LocalSize | spirq::spirv::ExecutionMode::LocalSizeId);
        if is_local_size && mode.operands.len() == 3 {
            let v: Vec<u32> = mode
                .operands
                .iter()
                .map(|c| match &c.value {
                    ConstantValue::U32(x) => *x,
                    ConstantValue::S32(x) => *x as u32,
                    _ => 1,
                })
                .collect();
            out.local_size = Some([v[0], v[1], v[2]]);
        }
    }
    Ok(out)
}

/// Merges the interfaces of the stages of one pipeline.
pub fn merge(stages: &[ShaderInterface]) -> Result<ShaderInterface, ReflectError> {
    let mut out = ShaderInterface::default();
    for s in stages {
        for (binding, info) in &s.bindings {
            match out.bindings.get_mut(binding) {
                Some(existing) if existing.kind != info.kind => {
                    return Err(ReflectError::Conflict { binding: *binding, a: existing.kind, b: info.kind })
                }
                Some(existing) => existing.writes |= info.writes,
                None => {
                    out.bindings.insert(*binding, info.clone());
                }
            }
        }
        out.push_constant_bytes = out.push_constant_bytes.max(s.push_constant_bytes);
        out.local_size = out.local_size.or(s.local_size);
        out.workgroup_memory_bytes = out.workgroup_memory_bytes.max(s.workgroup_memory_bytes);
    }
    Ok(out)
}

fn descriptor_kind(ty: &DescriptorType) -> (vk::DescriptorType, bool) {
    let writes = |a: &AccessType| !matches!(a, AccessType::ReadOnly);
    match ty {
        DescriptorType::Sampler() => (vk::DescriptorType::SAMPLER, false),
        DescriptorType::CombinedImageSampler() => (vk::DescriptorType::COMBINED_IMAGE_SAMPLER, false),
        DescriptorType::SampledImage() => (vk::DescriptorType::SAMPLED_IMAGE, false),
        DescriptorType::StorageImage(a) => (vk::DescriptorType::STORAGE_IMAGE, writes(a)),
        DescriptorType::UniformTexelBuffer() => (vk::DescriptorType::UNIFORM_TEXEL_BUFFER, false),
        DescriptorType::StorageTexelBuffer(a) => (vk::DescriptorType::STORAGE_TEXEL_BUFFER, writes(a)),
        DescriptorType::UniformBuffer() => (vk::DescriptorType::UNIFORM_BUFFER, false),
        DescriptorType::StorageBuffer(a) => (vk::DescriptorType::STORAGE_BUFFER, writes(a)),
        DescriptorType::InputAttachment(_) => (vk::DescriptorType::INPUT_ATTACHMENT, false),
        DescriptorType::AccelStruct() => (vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, false),
    }
}
