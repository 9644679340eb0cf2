//! Whether the machine and the device hold what a built-in scene of `--instances N` needs,
//! checked before the scene is generated: a size beyond either is refused with an error that
//! names the flag and the memory needed, instead of an allocation aborting the process (or the
//! machine swapping) minutes into generating it.
//!
//! The figures per instance are upper bounds of what `cullgraph render` keeps at its peak
//! (generation, upload and the first frames), with a fifth for what varies with the graph; the
//! bench measures the same renderer. They need not be exact: they separate sizes that fit from
//! those that are out of reach by far, and the fallible allocations behind them
//! (`try_reserve` in the generators, the device allocator's errors) catch the rest.

use cullgraph::gpu::GpuContext;
use cullgraph::{Error, Result};

/// Host bytes per instance beyond the device's memory: the scene's instance, its draw list,
/// cull record and GPU record before upload, and the frame statistics.
const HOST_PER_INSTANCE: u64 = 224;
/// Device bytes per instance: its GPU record (64 bytes), cull record (32), draw-list and triangle
/// entries (12), and the graphs' per-instance lists (about 12 to 24).
const DEVICE_PER_INSTANCE: u64 = 144;
/// The same with `--animate`: a world keeps its instances, handles and change journal, and
/// reserves a quarter more slots on the device for instances to come.
const HOST_PER_MOVING_INSTANCE: u64 = 416;
const DEVICE_PER_MOVING_INSTANCE: u64 = 224;
/// Host bytes per instance of a scene that is generated but not rendered (`graph plan`).
const HOST_PER_GENERATED_INSTANCE: u64 = 112;
/// Bytes per mesh kind of `builtin:field` (a few hundred triangles each), on the host and on
/// the device.
const HOST_PER_KIND: u64 = 16 << 10;
const DEVICE_PER_KIND: u64 = 8 << 10;
/// Host bytes per point light, and device bytes.
const HOST_PER_LIGHT: u64 = 96;
const DEVICE_PER_LIGHT: u64 = 32;
/// Host bytes per output pixel: the read-back image, its staging copy and the PNG encoder's.
const HOST_PER_PIXEL: u64 = 12;
/// What the process takes whatever the scene: shader compiler, driver, pipelines.
const BASE: u64 = 256 << 20;

/// Memory a run needs, in bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Need {
    /// On the host, beyond the device's memory.
    pub host: u64,
    /// On the device.
    pub device: u64,
}

/// What a run does with its scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Use {
    /// Generated only, to size a graph (`graph check --size`, `plan`, `dot`).
    Generate,
    /// Rendered (`render`, `bench`).
    Render,
    /// Rendered as a changing world (`render --animate`, the bench's `dynamic` suite).
    Animate,
}

/// The sizes of a built-in scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneSize {
    /// Instances.
    pub instances: u64,
    /// Mesh kinds (`builtin:field`; 0 for the city, whose few dozen meshes are in [`BASE`]).
    pub kinds: u64,
    /// Point lights.
    pub lights: u64,
}

impl Need {
    /// What a scene of `size` needs when used as `usage`.
    pub fn of(size: SceneSize, usage: Use) -> Need {
        let (host, device) = match usage {
            Use::Generate => (HOST_PER_GENERATED_INSTANCE, 0),
            Use::Render => (HOST_PER_INSTANCE, DEVICE_PER_INSTANCE),
            Use::Animate => (HOST_PER_MOVING_INSTANCE, DEVICE_PER_MOVING_INSTANCE),
        };
        let rendered = u64::from(usage != Use::Generate);
        let sum =
            |terms: &[(u64, u64)]| terms.iter().fold(0u64, |acc, &(n, b)| acc.saturating_add(n.saturating_mul(b)));
        Need {
            host: sum(&[(size.instances, host), (size.kinds, HOST_PER_KIND), (size.lights, HOST_PER_LIGHT), (1, BASE)]),
            device: sum(&[
                (size.instances, device),
                (size.kinds * rendered, DEVICE_PER_KIND),
                (size.lights * rendered, DEVICE_PER_LIGHT),
            ]),
        }
    }

    /// What images of `pixels` pixels in all need on the host, read back and written.
    pub fn image(pixels: u64) -> Need {
        Need { host: pixels.saturating_mul(HOST_PER_PIXEL), device: 0 }
    }
}

impl std::ops::Add for Need {
    type Output = Need;

    fn add(self, other: Need) -> Need {
        Need { host: self.host.saturating_add(other.host), device: self.device.saturating_add(other.device) }
    }
}

/// Where the memory comes from.
#[derive(Clone, Debug, Default)]
pub struct Room {
    /// Host bytes this process may still take (None: unknown on this system).
    pub host: Option<u64>,
    /// The device's name and the size of its largest device-local heap.
    pub device: Option<(String, u64)>,
    /// The device's memory is the host's (a CPU or integrated device): device bytes are taken
    /// from the host's too.
    pub device_on_host: bool,
}

impl Room {
    /// The host's room alone (commands that do not render).
    pub fn host() -> Room {
        Room { host: host_available(), ..Default::default() }
    }

    /// The host's room and that of `ctx`'s device.
    pub fn with_device(ctx: &GpuContext) -> Room {
        // SAFETY: the instance and physical device are valid while `ctx` lives.
        let props = unsafe { ctx.instance().get_physical_device_memory_properties(ctx.physical_device()) };
        let heaps = &props.memory_heaps[..props.memory_heap_count as usize];
        let device_local =
            heaps.iter().filter(|h| h.flags.contains(ash::vk::MemoryHeapFlags::DEVICE_LOCAL)).map(|h| h.size).max();
        let caps = ctx.caps();
        let on_host =
            matches!(caps.kind, ash::vk::PhysicalDeviceType::CPU | ash::vk::PhysicalDeviceType::INTEGRATED_GPU);
        Room { host: host_available(), device: device_local.map(|b| (caps.name.clone(), b)), device_on_host: on_host }
    }

    /// An error naming `flag` (given as `value`) when `need` does not fit.
    pub fn check(&self, flag: &str, value: &str, need: Need) -> Result<()> {
        let host_need = if self.device_on_host { need.host.saturating_add(need.device) } else { need.host };
        let what = if self.device_on_host && need.device > 0 {
            format!(
                "about {} of memory ({} for the host and {} for the device, which shares it)",
                gb(host_need),
                gb(need.host),
                gb(need.device)
            )
        } else {
            format!("about {} of host memory", gb(need.host))
        };
        if let Some(host) = self.host.filter(|&h| host_need > h) {
            return Err(Error::Invalid(format!(
                "{flag} {value} needs {what}, and this process can take {} more; ask for less",
                gb(host)
            )));
        }
        if let Some((name, heap)) = self.device.as_ref().filter(|(_, heap)| need.device > *heap) {
            return Err(Error::Invalid(format!(
                "{flag} {value} needs about {} of device memory, and {name} has {}; ask for less",
                gb(need.device),
                gb(*heap)
            )));
        }
        Ok(())
    }
}

/// `bytes` in gigabytes (or megabytes below one), for messages.
fn gb(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        format!("{:.0} MiB", bytes as f64 / (1u64 << 20) as f64)
    }
}

/// Host bytes this process may still take: the least of the memory the system has available,
/// what its control group still allows, and what its address-space limit (`ulimit -v`) leaves.
/// None where the system says nothing (not Linux).
pub fn host_available() -> Option<u64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let field = |text: &str, name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
        Some(kb * 1024)
    };
    let mut room: Vec<u64> = Vec::new();
    room.extend(read("/proc/meminfo").and_then(|t| field(&t, "MemAvailable:")));
    // cgroup v2, then v1 (whose "no limit" is a huge number, harmless in a minimum).
    let cgroup = |limit: &str, usage: &str| -> Option<u64> {
        let limit: u64 = read(limit)?.trim().parse().ok()?;
        let usage: u64 = read(usage)?.trim().parse().ok()?;
        Some(limit.saturating_sub(usage))
    };
    room.extend(cgroup("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"));
    room.extend(cgroup("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"));
    let address_limit = read("/proc/self/limits").and_then(|t| {
        let line = t.lines().find(|l| l.starts_with("Max address space"))?;
        line["Max address space".len()..].split_whitespace().next()?.parse::<u64>().ok()
    });
    if let (Some(limit), Some(size)) = (address_limit, read("/proc/self/status").and_then(|t| field(&t, "VmSize:"))) {
        room.push(limit.saturating_sub(size));
    }
    room.into_iter().min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_beyond_the_room_is_refused_naming_the_flag_and_the_memory() {
        let size = SceneSize { instances: 50_000_000, kinds: 0, lights: 32 };
        let need = Need::of(size, Use::Render) + Need::image(1280 * 720);
        assert_eq!(need.device, 50_000_000 * DEVICE_PER_INSTANCE + 32 * DEVICE_PER_LIGHT);
        let small = Room { host: Some(8 << 30), device: Some(("gpu".into(), 80 << 30)), device_on_host: false };
        let e = small.check("--instances", "50000000", need).unwrap_err().to_string();
        assert!(e.starts_with("--instances 50000000 needs about 10.7 GiB of host memory"), "{e}");
        assert!(e.contains("can take 8.0 GiB more"), "{e}");
        let small_device = Room { host: Some(64 << 30), device: Some(("gpu".into(), 4 << 30)), device_on_host: false };
        let e = small_device.check("--instances", "50000000", need).unwrap_err().to_string();
        assert!(e.contains("about 6.7 GiB of device memory, and gpu has 4.0 GiB"), "{e}");
        // A CPU device's memory is the host's: both come out of it.
        let shared = Room { host: Some(16 << 30), device: Some(("cpu".into(), 64 << 30)), device_on_host: true };
        let e = shared.check("--instances", "50000000", need).unwrap_err().to_string();
        assert!(e.contains("about 17.4 GiB of memory (10.7 GiB for the host and 6.7 GiB for the device"), "{e}");
        let big = Room { host: Some(64 << 30), device: Some(("gpu".into(), 80 << 30)), device_on_host: true };
        assert!(big.check("--instances", "50000000", need).is_ok());
        assert!(Room::default().check("--instances", "50000000", need).is_ok(), "nothing known, nothing refused");
    }

    #[test]
    fn this_machine_says_how_much_it_has() {
        if cfg!(target_os = "linux") {
            assert!(host_available().is_some_and(|b| b > 0));
        }
    }
}
