//! SPIR-V reflection (through `spirq`): which descriptors, push constants and workgroup size a
//! shader declares, so pipeline layouts are derived from the shader instead of written twice.

use ash::vk;
use spirq::prelude::*;
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
    /// Multisampled (`sampler2DMS`, `image2DMS`).
    pub multisampled: bool,
    /// The scalar type a sampled image returns (`sampler2D`: float, `usampler2D`: uint,
    /// `isampler2D`: int); `None` for storage images, whose format qualifier decides.
    pub sampled: Option<SampledScalar>,
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
        ImageDecl { multisampled: t.is_multisampled, sampled: Some(scalar) }
    };
    match ty {
        Type::CombinedImageSampler(t) => Some(sampled(&t.sampled_image_ty)),
        Type::SampledImage(t) => Some(sampled(t)),
        Type::StorageImage(t) => Some(ImageDecl { multisampled: t.is_multisampled, sampled: None }),
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
    let mut out = ShaderInterface::default();
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
