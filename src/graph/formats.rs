//! Image formats a graph file may name (`format: R16G16B16A16_SFLOAT`): the Vulkan name without
//! the `VK_FORMAT_` prefix, the `vk::Format`, bytes per texel (for memory estimates) and whether
//! it is a depth format.

use ash::vk;

/// One supported format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FormatInfo {
    /// Name in RON (Vulkan's, without `VK_FORMAT_`).
    pub name: &'static str,
    /// The Vulkan format.
    pub format: vk::Format,
    /// Bytes per texel (depth/stencil formats: a size drivers commonly use).
    pub bytes: u32,
    /// Whether it has a depth aspect.
    pub depth: bool,
}

const fn f(name: &'static str, format: vk::Format, bytes: u32, depth: bool) -> FormatInfo {
    FormatInfo { name, format, bytes, depth }
}

/// Every format a graph may use.
pub const FORMATS: &[FormatInfo] = &[
    f("R8_UNORM", vk::Format::R8_UNORM, 1, false),
    f("R8_UINT", vk::Format::R8_UINT, 1, false),
    f("R8G8_UNORM", vk::Format::R8G8_UNORM, 2, false),
    f("R8G8B8A8_UNORM", vk::Format::R8G8B8A8_UNORM, 4, false),
    f("R8G8B8A8_SRGB", vk::Format::R8G8B8A8_SRGB, 4, false),
    f("R8G8B8A8_SNORM", vk::Format::R8G8B8A8_SNORM, 4, false),
    f("R8G8B8A8_UINT", vk::Format::R8G8B8A8_UINT, 4, false),
    f("B8G8R8A8_UNORM", vk::Format::B8G8R8A8_UNORM, 4, false),
    f("B8G8R8A8_SRGB", vk::Format::B8G8R8A8_SRGB, 4, false),
    f("A2B10G10R10_UNORM_PACK32", vk::Format::A2B10G10R10_UNORM_PACK32, 4, false),
    f("B10G11R11_UFLOAT_PACK32", vk::Format::B10G11R11_UFLOAT_PACK32, 4, false),
    f("R16_UINT", vk::Format::R16_UINT, 2, false),
    f("R16_SFLOAT", vk::Format::R16_SFLOAT, 2, false),
    f("R16_UNORM", vk::Format::R16_UNORM, 2, false),
    f("R16G16_UNORM", vk::Format::R16G16_UNORM, 4, false),
    f("R16G16_SNORM", vk::Format::R16G16_SNORM, 4, false),
    f("R16G16_SFLOAT", vk::Format::R16G16_SFLOAT, 4, false),
    f("R16G16_UINT", vk::Format::R16G16_UINT, 4, false),
    f("R16G16B16A16_UNORM", vk::Format::R16G16B16A16_UNORM, 8, false),
    f("R16G16B16A16_SNORM", vk::Format::R16G16B16A16_SNORM, 8, false),
    f("R16G16B16A16_SFLOAT", vk::Format::R16G16B16A16_SFLOAT, 8, false),
    f("R16G16B16A16_UINT", vk::Format::R16G16B16A16_UINT, 8, false),
    f("R32_SFLOAT", vk::Format::R32_SFLOAT, 4, false),
    f("R32_UINT", vk::Format::R32_UINT, 4, false),
    f("R32_SINT", vk::Format::R32_SINT, 4, false),
    f("R32G32_SFLOAT", vk::Format::R32G32_SFLOAT, 8, false),
    f("R32G32_UINT", vk::Format::R32G32_UINT, 8, false),
    f("R32G32B32A32_SFLOAT", vk::Format::R32G32B32A32_SFLOAT, 16, false),
    f("R32G32B32A32_UINT", vk::Format::R32G32B32A32_UINT, 16, false),
    f("D16_UNORM", vk::Format::D16_UNORM, 2, true),
    f("D32_SFLOAT", vk::Format::D32_SFLOAT, 4, true),
    f("D24_UNORM_S8_UINT", vk::Format::D24_UNORM_S8_UINT, 4, true),
    f("D32_SFLOAT_S8_UINT", vk::Format::D32_SFLOAT_S8_UINT, 8, true),
];

/// Aliases accepted for convenience (the short name of the packed float format).
const ALIASES: &[(&str, vk::Format)] = &[("R11G11B10", vk::Format::B10G11R11_UFLOAT_PACK32)];

/// The format called `name` in RON.
pub fn by_name(name: &str) -> Option<&'static FormatInfo> {
    let format = ALIASES.iter().find(|(n, _)| *n == name).map(|(_, f)| *f);
    FORMATS.iter().find(|f| f.name == name || Some(f.format) == format)
}

/// The table entry of a Vulkan format.
pub fn info(format: vk::Format) -> Option<&'static FormatInfo> {
    FORMATS.iter().find(|f| f.format == format)
}

/// The RON name of a Vulkan format (its Debug name when not in the table).
pub fn name(format: vk::Format) -> String {
    info(format).map_or_else(|| format!("{format:?}"), |f| f.name.to_string())
}

/// Whether `format` has a depth aspect.
pub fn is_depth(format: vk::Format) -> bool {
    info(format).is_some_and(|f| f.depth)
}

/// Whether `format` is a depth format with a stencil aspect.
pub fn has_stencil(format: vk::Format) -> bool {
    matches!(format, vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D16_UNORM_S8_UINT)
}

/// Up to `max` supported names closest to `name` (for "unknown format" errors).
pub fn suggestions(name: &str, max: usize) -> Vec<&'static str> {
    let mut scored: Vec<(usize, &'static str)> = FORMATS
        .iter()
        .map(|f| (super::error::edit_distance(&name.to_ascii_uppercase(), f.name), f.name))
        .chain(ALIASES.iter().map(|(n, _)| (super::error::edit_distance(&name.to_ascii_uppercase(), n), *n)))
        .collect();
    scored.sort();
    scored.into_iter().take(max).map(|(_, n)| n).collect()
}

/// The scalar type sampling an image of `format` returns: integer formats give their integers,
/// every other format (normalized, float, sRGB, depth) floats.
pub fn sampled_scalar(format: vk::Format) -> crate::gpu::reflect::SampledScalar {
    use crate::gpu::reflect::SampledScalar;
    let name = name(format);
    if name.ends_with("_UINT") && !is_depth(format) {
        SampledScalar::Uint
    } else if name.ends_with("_SINT") {
        SampledScalar::Int
    } else {
        SampledScalar::Float
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_suggest() {
        for f in FORMATS {
            assert_eq!(by_name(f.name).map(|i| i.format), Some(f.format));
            assert_eq!(name(f.format), f.name);
        }
        assert_eq!(by_name("R11G11B10").map(|f| f.format), Some(vk::Format::B10G11R11_UFLOAT_PACK32));
        assert_eq!(suggestions("R8G8B8A8_UNROM", 3)[0], "R8G8B8A8_UNORM");
        assert!(is_depth(vk::Format::D24_UNORM_S8_UINT));
        assert!(!is_depth(vk::Format::R32_SFLOAT));
    }
}
