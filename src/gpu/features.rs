//! The Vulkan extensions and features cullgraph needs, in one place.
//!
//! A host engine that creates the device itself chains [`RequiredFeatures`] into its
//! `VkDeviceCreateInfo` (see `examples/embed.rs`), so the library and the engine agree on what is on.

use ash::vk;
use std::ffi::CStr;

/// Device extensions cullgraph uses. All are present on NVIDIA drivers and on lavapipe (Mesa 22.3).
pub const REQUIRED_DEVICE_EXTENSIONS: &[&CStr] = &[ash::khr::push_descriptor::NAME];

/// Device extensions enabled when present; passes that need one refuse to run without it
/// (`VK_EXT_post_depth_coverage`: the compressed G-buffer's per-sample coverage after the depth
/// and stencil tests). A host engine that creates the device enables those it wants too, and
/// lists them in `HostHandles::enabled_device_extensions`.
pub const OPTIONAL_DEVICE_EXTENSIONS: &[&CStr] = &[ash::ext::post_depth_coverage::NAME];

/// The name a host lists in `HostHandles::enabled_device_extensions` to say that it created the
/// device with the Vulkan 1.1 `multiview` feature on (`VkPhysicalDeviceVulkan11Features`).
/// Multiview is core since 1.1, so it needs no extension on a 1.3 device, but Vulkan cannot be
/// asked which features a device was created with: the name is the host's word that it was
/// (as `VK_EXT_fragment_shader_interlock` is for its feature). cullgraph turns the feature on
/// where the device supports it on a device it creates itself. Only the multiview measurement
/// of `cullgraph bench --suites views` (`crate::bench::multiview`) draws with it, and is skipped
/// without it.
pub const MULTIVIEW_EXTENSION: &CStr = ash::khr::multiview::NAME;

/// Whether `extensions` (as Vulkan lists them) has the one called `name`.
pub(crate) fn lists_extension(extensions: &[vk::ExtensionProperties], name: &CStr) -> bool {
    extensions.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
}

/// The feature structs cullgraph enables, ready to chain into `VkDeviceCreateInfo`.
///
/// Everything here is core Vulkan 1.3 or earlier; the struct only exists so that the same list
/// serves the owned device, the embedding check and the error message naming what is missing.
#[derive(Default)]
pub struct RequiredFeatures {
    /// Core 1.0 features.
    pub core: vk::PhysicalDeviceFeatures,
    /// Core 1.1 features.
    pub v11: vk::PhysicalDeviceVulkan11Features<'static>,
    /// Core 1.2 features.
    pub v12: vk::PhysicalDeviceVulkan12Features<'static>,
    /// Core 1.3 features.
    pub v13: vk::PhysicalDeviceVulkan13Features<'static>,
}

impl RequiredFeatures {
    /// The features cullgraph turns on.
    pub fn new() -> Self {
        let mut f = Self::default();
        f.core.multi_draw_indirect = vk::TRUE;
        f.core.draw_indirect_first_instance = vk::TRUE;
        f.core.fragment_stores_and_atomics = vk::TRUE;
        f.core.shader_int64 = vk::TRUE;
        f.core.sample_rate_shading = vk::TRUE;
        // Fragment shaders read gl_PrimitiveID (the visibility buffer), which needs it.
        f.core.geometry_shader = vk::TRUE;
        f.core.shader_storage_image_write_without_format = vk::TRUE;
        // Textures seen at grazing angles (floors, terrain) stay sharp.
        f.core.sampler_anisotropy = vk::TRUE;
        f.v11.shader_draw_parameters = vk::TRUE;
        f.v12.draw_indirect_count = vk::TRUE;
        f.v12.scalar_block_layout = vk::TRUE;
        f.v12.host_query_reset = vk::TRUE;
        f.v12.sampler_filter_minmax = vk::TRUE;
        f.v12.shader_int8 = vk::TRUE;
        f.v12.storage_buffer8_bit_access = vk::TRUE;
        // One instance-cull dispatch reaches every view's buffers through their addresses.
        f.v12.buffer_device_address = vk::TRUE;
        f.v13.synchronization2 = vk::TRUE;
        f.v13.dynamic_rendering = vk::TRUE;
        f.v13.maintenance4 = vk::TRUE;
        f
    }

    /// Names of the features in `self` that `available` lacks; empty when all are there.
    pub fn missing_from(&self, available: &RequiredFeatures) -> Vec<&'static str> {
        let mut missing = Vec::new();
        let mut check = |want: vk::Bool32, have: vk::Bool32, name: &'static str| {
            if want == vk::TRUE && have != vk::TRUE {
                missing.push(name);
            }
        };
        let (w, h) = (&self.core, &available.core);
        check(w.multi_draw_indirect, h.multi_draw_indirect, "multiDrawIndirect");
        check(w.draw_indirect_first_instance, h.draw_indirect_first_instance, "drawIndirectFirstInstance");
        check(w.fragment_stores_and_atomics, h.fragment_stores_and_atomics, "fragmentStoresAndAtomics");
        check(w.shader_int64, h.shader_int64, "shaderInt64");
        check(w.sample_rate_shading, h.sample_rate_shading, "sampleRateShading");
        check(w.geometry_shader, h.geometry_shader, "geometryShader");
        check(
            w.shader_storage_image_write_without_format,
            h.shader_storage_image_write_without_format,
            "shaderStorageImageWriteWithoutFormat",
        );
        check(w.sampler_anisotropy, h.sampler_anisotropy, "samplerAnisotropy");
        check(self.v11.shader_draw_parameters, available.v11.shader_draw_parameters, "shaderDrawParameters");
        let (w, h) = (&self.v12, &available.v12);
        check(w.draw_indirect_count, h.draw_indirect_count, "drawIndirectCount");
        check(w.scalar_block_layout, h.scalar_block_layout, "scalarBlockLayout");
        check(w.host_query_reset, h.host_query_reset, "hostQueryReset");
        check(w.sampler_filter_minmax, h.sampler_filter_minmax, "samplerFilterMinmax");
        check(w.buffer_device_address, h.buffer_device_address, "bufferDeviceAddress");
        check(w.shader_int8, h.shader_int8, "shaderInt8");
        check(w.storage_buffer8_bit_access, h.storage_buffer8_bit_access, "storageBuffer8BitAccess");
        let (w, h) = (&self.v13, &available.v13);
        check(w.synchronization2, h.synchronization2, "synchronization2");
        check(w.dynamic_rendering, h.dynamic_rendering, "dynamicRendering");
        check(w.maintenance4, h.maintenance4, "maintenance4");
        missing
    }

    /// Queries what `physical_device` supports, in the same shape.
    pub fn supported_by(instance: &ash::Instance, physical_device: vk::PhysicalDevice) -> Self {
        let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut features2 =
            vk::PhysicalDeviceFeatures2::default().push_next(&mut v11).push_next(&mut v12).push_next(&mut v13);
        // SAFETY: valid instance and physical device; the chain lives on this stack frame.
        unsafe { instance.get_physical_device_features2(physical_device, &mut features2) };
        let core = features2.features;
        Self { core, v11: strip(v11), v12: strip(v12), v13: strip(v13) }
    }

    /// Chains the 1.1/1.2/1.3 structs into `info`; the core struct goes into `features2`.
    ///
    /// Returns the `PhysicalDeviceFeatures2` to push into `VkDeviceCreateInfo`.
    pub fn chain(&mut self) -> vk::PhysicalDeviceFeatures2<'_> {
        vk::PhysicalDeviceFeatures2::default()
            .features(self.core)
            .push_next(&mut self.v11)
            .push_next(&mut self.v12)
            .push_next(&mut self.v13)
    }
}

/// Clears the `p_next` pointer of a queried feature struct so it can be stored on its own.
trait StripNext {
    fn clear_next(&mut self);
}
macro_rules! impl_strip {
    ($($t:ty),*) => {$(impl StripNext for $t { fn clear_next(&mut self) { self.p_next = std::ptr::null_mut(); } })*};
}
impl_strip!(
    vk::PhysicalDeviceVulkan11Features<'_>,
    vk::PhysicalDeviceVulkan12Features<'_>,
    vk::PhysicalDeviceVulkan13Features<'_>
);

fn strip<T: StripNext>(mut s: T) -> T {
    s.clear_next();
    s
}
