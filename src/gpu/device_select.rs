//! Choosing a physical device: prefer a discrete GPU, fall back to whatever exists (lavapipe on CI).

use super::error::{GpuError, GpuResult, VkResultExt};
use ash::vk;
use std::fmt;
use std::str::FromStr;

/// Environment variable that overrides automatic device choice, by name substring or index.
pub const DEVICE_ENV: &str = "CULLGRAPH_DEVICE";

/// Which physical device to use.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DeviceSelector {
    /// Discrete GPU first, then integrated, virtual, CPU (lavapipe).
    #[default]
    Auto,
    /// The first device whose name contains this text (case-insensitive), e.g. `llvmpipe` or `H100`.
    Name(String),
    /// The device at this index in `vkEnumeratePhysicalDevices` order (`cullgraph devices` lists them).
    Index(usize),
}

impl DeviceSelector {
    /// `explicit` if given, otherwise the [`DEVICE_ENV`] variable, otherwise [`DeviceSelector::Auto`].
    pub fn or_from_env(explicit: Option<DeviceSelector>) -> DeviceSelector {
        explicit.or_else(|| std::env::var(DEVICE_ENV).ok().and_then(|v| v.parse().ok())).unwrap_or_default()
    }
}

impl FromStr for DeviceSelector {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        Ok(if s.is_empty() || s.eq_ignore_ascii_case("auto") {
            DeviceSelector::Auto
        } else if let Ok(i) = s.parse::<usize>() {
            DeviceSelector::Index(i)
        } else {
            DeviceSelector::Name(s.to_string())
        })
    }
}

impl fmt::Display for DeviceSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DeviceSelector::Auto => write!(f, "auto"),
            DeviceSelector::Name(n) => write!(f, "name containing '{n}'"),
            DeviceSelector::Index(i) => write!(f, "index {i}"),
        }
    }
}

/// One physical device as the user sees it in listings and errors.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// Position in enumeration order.
    pub index: usize,
    /// `deviceName`.
    pub name: String,
    /// Discrete, integrated, CPU...
    pub kind: vk::PhysicalDeviceType,
    /// Supported API version.
    pub api_version: u32,
    /// Whether the device has `VK_EXT_post_depth_coverage`, which the compressed G-buffer needs.
    pub post_depth_coverage: bool,
    /// Whether it has `VK_EXT_fragment_shader_interlock` with `fragmentShaderSampleInterlock`,
    /// with which the sample-claim G-buffer claims in draw order.
    pub sample_interlock: bool,
    /// The handle.
    pub handle: vk::PhysicalDevice,
}

impl fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} ({:?}, Vulkan {}.{}.{})",
            self.index,
            self.name,
            self.kind,
            vk::api_version_major(self.api_version),
            vk::api_version_minor(self.api_version),
            vk::api_version_patch(self.api_version),
        )
    }
}

impl DeviceInfo {
    /// What the optional graphs need, as `cullgraph devices` lists it: whether the compressed
    /// G-buffer can run (it needs Vulkan 1.3 too, as everything does) and whether sample claims
    /// can go in draw order.
    pub fn capabilities(&self) -> String {
        let yes_no = |b: bool| if b { "yes" } else { "no" };
        format!(
            "compressed G-buffer: {}, draw-order sample claims: {}",
            yes_no(self.post_depth_coverage),
            yes_no(self.sample_interlock)
        )
    }
}

/// Lists the physical devices of `instance`.
pub fn enumerate(instance: &ash::Instance) -> GpuResult<Vec<DeviceInfo>> {
    // SAFETY: valid instance.
    let handles = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    Ok(handles
        .into_iter()
        .enumerate()
        .map(|(index, handle)| {
            // SAFETY: handle comes from this instance.
            let props = unsafe { instance.get_physical_device_properties(handle) };
            // SAFETY: handle comes from this instance.
            let exts = unsafe { instance.enumerate_device_extension_properties(handle) }.unwrap_or_default();
            let has = |name: &std::ffi::CStr| super::features::lists_extension(&exts, name);
            DeviceInfo {
                index,
                name: props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
                kind: props.device_type,
                api_version: props.api_version,
                post_depth_coverage: has(ash::ext::post_depth_coverage::NAME),
                sample_interlock: has(ash::ext::fragment_shader_interlock::NAME)
                    && super::context::sample_interlock_supported(instance, handle),
                handle,
            }
        })
        .collect())
}

/// Picks the device `selector` asks for among those that run Vulkan 1.3.
pub fn select(devices: &[DeviceInfo], selector: &DeviceSelector) -> GpuResult<DeviceInfo> {
    let listing = || devices.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("; ");
    let chosen = match selector {
        DeviceSelector::Index(i) => devices.get(*i),
        DeviceSelector::Name(n) => {
            let n = n.to_lowercase();
            devices.iter().find(|d| d.name.to_lowercase().contains(&n))
        }
        DeviceSelector::Auto => {
            devices.iter().filter(|d| d.api_version >= vk::API_VERSION_1_3).min_by_key(|d| preference(d.kind))
        }
    };
    let chosen =
        chosen.ok_or_else(|| GpuError::NoDevice(format!("no device matches {selector}; devices: [{}]", listing())))?;
    if chosen.api_version < vk::API_VERSION_1_3 {
        return Err(GpuError::NoDevice(format!("{chosen} does not support Vulkan 1.3")));
    }
    Ok(chosen.clone())
}

/// Lower is better.
fn preference(kind: vk::PhysicalDeviceType) -> u8 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(index: usize, name: &str, kind: vk::PhysicalDeviceType) -> DeviceInfo {
        DeviceInfo {
            index,
            name: name.into(),
            kind,
            api_version: vk::API_VERSION_1_3,
            post_depth_coverage: true,
            sample_interlock: false,
            handle: vk::PhysicalDevice::null(),
        }
    }

    #[test]
    fn auto_prefers_discrete_and_name_and_index_override() {
        let devices = [
            dev(0, "llvmpipe (LLVM 15.0.6, 256 bits)", vk::PhysicalDeviceType::CPU),
            dev(1, "NVIDIA H100 80GB HBM3", vk::PhysicalDeviceType::DISCRETE_GPU),
        ];
        assert_eq!(select(&devices, &DeviceSelector::Auto).unwrap().index, 1);
        assert_eq!(select(&devices, &"LLVMPIPE".parse().unwrap()).unwrap().index, 0);
        assert_eq!(select(&devices, &"0".parse().unwrap()).unwrap().index, 0);
        let err = select(&devices, &"radeon".parse().unwrap()).unwrap_err().to_string();
        assert!(err.contains("radeon") && err.contains("H100"), "{err}");
        assert!(select(&devices, &DeviceSelector::Index(7)).is_err());
    }
}
