//! The Vulkan context: instance, device, queue and allocator, either owned or borrowed from a host engine.

use super::device_select::{self, DeviceInfo, DeviceSelector};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::features::{lists_extension, RequiredFeatures, REQUIRED_DEVICE_EXTENSIONS};
use super::validation::{self, ValidationLog};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_char, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Environment variable that turns the validation layer on for any context (`1`/`0`).
pub const VALIDATION_ENV: &str = "CULLGRAPH_VALIDATION";

/// How to create an owned context.
#[derive(Clone, Debug)]
pub struct ContextOptions {
    /// Which physical device to use.
    pub device: DeviceSelector,
    /// Enable the Khronos validation layer with synchronization validation and count its messages.
    pub validation: bool,
    /// Application name reported to the driver.
    pub app_name: String,
    /// Instance extensions to enable besides cullgraph's own: those a window's surface needs
    /// (`ash_window::enumerate_required_extensions`). A loader without one is refused, naming it.
    pub instance_extensions: Vec<CString>,
    /// Device extensions to enable besides cullgraph's own (`VK_KHR_swapchain` to present to a
    /// window). A device without one is refused, naming it.
    pub device_extensions: Vec<CString>,
}

impl Default for ContextOptions {
    fn default() -> Self {
        Self {
            device: DeviceSelector::or_from_env(None),
            validation: std::env::var(VALIDATION_ENV).is_ok_and(|v| v == "1"),
            app_name: "cullgraph".into(),
            instance_extensions: Vec::new(),
            device_extensions: Vec::new(),
        }
    }
}

/// Handles a host engine passes to [`GpuContext::from_host`]; cullgraph creates no device of its own.
///
/// The host must have created the device with [`REQUIRED_DEVICE_EXTENSIONS`] and
/// [`RequiredFeatures::new`] enabled, and API version 1.3. cullgraph never waits on the host's
/// device: the host drops a renderer (and the context) only once the frames it recorded have
/// executed, as it would free any resource of its own.
pub struct HostHandles {
    /// The loader entry the host used.
    pub entry: ash::Entry,
    /// The host's instance.
    pub instance: ash::Instance,
    /// The physical device behind `device`.
    pub physical_device: vk::PhysicalDevice,
    /// The host's logical device.
    pub device: ash::Device,
    /// A queue family with graphics and compute.
    pub queue_family_index: u32,
    /// A queue of that family; cullgraph only submits to it when asked to (headless helpers).
    pub queue: vk::Queue,
    /// The host's allocator, if it has one; otherwise cullgraph creates its own on the host device.
    pub allocator: Option<Arc<Mutex<Allocator>>>,
    /// Whether the host enabled `VK_EXT_debug_utils` on the instance (for pass labels).
    pub debug_utils: bool,
    /// The device extensions the host enabled: every one of [`REQUIRED_DEVICE_EXTENSIONS`], and
    /// those of [`OPTIONAL_DEVICE_EXTENSIONS`] it chose to. Vulkan cannot be asked which
    /// extensions a device was created with, and cullgraph uses an optional one only when it is
    /// listed here (a pass that needs a missing one refuses to be built, naming it).
    ///
    /// `VK_EXT_fragment_shader_interlock` is not among the optional ones because it needs a
    /// feature too: list it only if the device was created with it and with
    /// `fragmentShaderSampleInterlock` on; the sample-claim G-buffer then claims in draw order.
    ///
    /// List [`MULTIVIEW_EXTENSION`] (`VK_KHR_multiview`) only if the device was created with the
    /// Vulkan 1.1 `multiview` feature on ([`DeviceCaps::multiview`]).
    ///
    /// [`MULTIVIEW_EXTENSION`]: super::features::MULTIVIEW_EXTENSION
    /// [`OPTIONAL_DEVICE_EXTENSIONS`]: super::features::OPTIONAL_DEVICE_EXTENSIONS
    pub enabled_device_extensions: Vec<CString>,
}

/// What the rest of the library needs to know about the device.
#[derive(Clone, Debug)]
pub struct DeviceCaps {
    /// Device name, e.g. `NVIDIA H100 80GB HBM3` or `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Discrete, integrated, CPU...
    pub kind: vk::PhysicalDeviceType,
    /// Device limits.
    pub limits: vk::PhysicalDeviceLimits,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f64,
    /// Valid bits of timestamps on our queue family (0: no timestamps).
    pub timestamp_valid_bits: u32,
    /// Subgroup size reported by the device (8 on lavapipe, 32 on NVIDIA).
    pub subgroup_size: u32,
    /// Subgroup operations the device supports in compute shaders (empty if none there).
    pub subgroup_compute_ops: vk::SubgroupFeatureFlags,
    /// `VK_EXT_post_depth_coverage` is enabled: supported, on a device cullgraph creates; supported
    /// and listed in [`HostHandles::enabled_device_extensions`], on a host's device.
    pub post_depth_coverage: bool,
    /// `VK_EXT_fragment_shader_interlock` with `fragmentShaderSampleInterlock` is enabled: both
    /// supported, on a device cullgraph creates; supported and the extension listed in
    /// [`HostHandles::enabled_device_extensions`] (which then promises the feature too), on a
    /// host's device. The sample-claim G-buffer can then claim in draw order (`claim_order`).
    pub sample_interlock: bool,
    /// Storage buffers have device addresses (`Buffer::device_address`): the device has
    /// `bufferDeviceAddress` on (a required feature) and cullgraph allocates with it, which it
    /// knows only of its own allocator (not of a host's, [`HostHandles::allocator`]). Without it
    /// the instance-cull pass culls each view in a dispatch of its own.
    pub buffer_addresses: bool,
    /// The Vulkan 1.1 `multiview` feature is on (render passes with a view mask, `gl_ViewIndex`):
    /// supported, on a device cullgraph creates; supported and
    /// [`MULTIVIEW_EXTENSION`](super::features::MULTIVIEW_EXTENSION) listed in
    /// [`HostHandles::enabled_device_extensions`], on a host's device. Only the multiview
    /// measurement of the views bench needs it (`crate::bench::multiview`).
    pub multiview: bool,
}

/// State shared by the context and every resource created from it; dropped last.
pub(crate) struct DeviceShared {
    /// Keeps libvulkan loaded for as long as any handle exists.
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue_family: u32,
    queue: Mutex<vk::Queue>,
    allocator: ManuallyDrop<Arc<Mutex<Allocator>>>,
    pub push_descriptor: ash::khr::push_descriptor::Device,
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    pub caps: DeviceCaps,
    validation: ValidationLog,
    owned: Option<OwnedParts>,
    /// The pipelines alive on this device, by everything they were made from.
    pub pipelines: super::pipeline::PipelineMemo,
}

/// What an owned context created and must destroy.
struct OwnedParts {
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The callback's user data; boxed so its address stays fixed.
    _log_anchor: Box<ValidationLog>,
}

impl DeviceShared {
    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        // SAFETY: every resource holds an Arc to this struct, so nothing created from the device is
        // left. A host's device is not waited on: vkDeviceWaitIdle needs every queue of the device
        // externally synchronized, and the host's other threads may be submitting; the host
        // knows, by its own fences, when cullgraph's frames have executed (see `HostHandles`).
        unsafe {
            if self.owned.is_some() {
                let _ = self.device.device_wait_idle();
            }
            ManuallyDrop::drop(&mut self.allocator);
            if let Some(owned) = self.owned.take() {
                self.device.destroy_device(None);
                if let Some((loader, messenger)) = owned.messenger {
                    loader.destroy_debug_utils_messenger(messenger, None);
                }
                self.instance.destroy_instance(None);
            }
        }
    }
}

/// A Vulkan device ready for cullgraph: cheap to clone, shared by every resource made from it.
///
/// Create it with [`GpuContext::new`] (cullgraph owns the instance and device) or
/// [`GpuContext::from_host`] (an engine hands over its own). Nothing is global: several contexts
/// can live in one process.
#[derive(Clone)]
pub struct GpuContext {
    pub(crate) shared: Arc<DeviceShared>,
}

impl GpuContext {
    /// Pipelines made on this device so far. Passes that ask for a pipeline that is alive
    /// (the same shaders and state) share it, so rebuilding a graph for a new size makes none.
    pub fn pipelines_made(&self) -> u64 {
        self.shared.pipelines.made()
    }

    /// Loads Vulkan, picks a device and creates everything cullgraph needs.
    pub fn new(options: &ContextOptions) -> GpuResult<Self> {
        // SAFETY: loading the system Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::Loader(e.to_string()))?;
        let log = Box::new(ValidationLog::default());
        let (instance, messenger) = create_instance(&entry, options, &log)?;
        // From here on, destroy the instance if anything fails.
        let guard = InstanceGuard { instance: &instance, messenger: messenger.as_ref() };
        let devices = device_select::enumerate(&instance)?;
        let chosen = device_select::select(&devices, &options.device)?;
        let queue_family = find_queue_family(&instance, chosen.handle).ok_or_else(|| {
            GpuError::NoDevice(format!("{} has no queue family with graphics and compute", chosen.name))
        })?;
        let device = create_device(&instance, &chosen, queue_family, &options.device_extensions)?;
        std::mem::forget(guard);
        // SAFETY: family index validated above; one queue was requested.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let owned = OwnedParts { messenger, _log_anchor: log };
        let validation = (*owned._log_anchor).clone();
        Self::assemble(
            entry,
            instance,
            chosen.handle,
            device,
            queue_family,
            queue,
            None,
            options.validation,
            validation,
            Some(owned),
            // `create_device` enabled every optional extension the device supports.
            &|_| true,
        )
    }

    /// Wraps a host engine's instance and device; creates no instance or device and never destroys them.
    ///
    /// Fails if the physical device lacks a feature cullgraph needs, or the host did not list a
    /// required extension as enabled (the host must also have *enabled* the features).
    pub fn from_host(host: HostHandles) -> GpuResult<Self> {
        let name = device_name(&host.instance, host.physical_device);
        let supported = RequiredFeatures::supported_by(&host.instance, host.physical_device);
        let mut missing: Vec<String> =
            RequiredFeatures::new().missing_from(&supported).into_iter().map(String::from).collect();
        let enabled = |want: &CStr| host.enabled_device_extensions.iter().any(|e| e.as_c_str() == want);
        missing.extend(
            REQUIRED_DEVICE_EXTENSIONS
                .iter()
                .filter(|want| !enabled(want))
                .map(|want| format!("{} (not among the host's enabled extensions)", want.to_string_lossy())),
        );
        if !missing.is_empty() {
            return Err(GpuError::MissingFeatures { device: name, missing: missing.join(", ") });
        }
        Self::assemble(
            host.entry,
            host.instance,
            host.physical_device,
            host.device,
            host.queue_family_index,
            host.queue,
            host.allocator,
            host.debug_utils,
            ValidationLog::default(),
            None,
            // Supported is not enabled: only the host knows what it created the device with.
            &enabled,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        entry: ash::Entry,
        instance: ash::Instance,
        physical_device: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
        allocator: Option<Arc<Mutex<Allocator>>>,
        debug_utils: bool,
        validation: ValidationLog,
        owned: Option<OwnedParts>,
        enabled_extension: &dyn Fn(&CStr) -> bool,
    ) -> GpuResult<Self> {
        let mut caps = query_caps(&instance, physical_device, queue_family, enabled_extension);
        caps.buffer_addresses = allocator.is_none();
        let allocator = match allocator {
            Some(a) => a,
            None => {
                let desc = AllocatorCreateDesc {
                    instance: instance.clone(),
                    device: device.clone(),
                    physical_device,
                    debug_settings: Default::default(),
                    buffer_device_address: true,
                    allocation_sizes: Default::default(),
                };
                let a = Allocator::new(&desc)
                    .map_err(|source| GpuError::Allocation { name: "allocator".into(), source })?;
                Arc::new(Mutex::new(a))
            }
        };
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        let debug_utils = debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        Ok(Self {
            shared: Arc::new(DeviceShared {
                entry,
                instance,
                physical_device,
                device,
                queue_family,
                queue: Mutex::new(queue),
                allocator: ManuallyDrop::new(allocator),
                push_descriptor,
                debug_utils,
                caps,
                validation,
                owned,
                pipelines: Default::default(),
            }),
        })
    }

    /// The logical device.
    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// The loader entry (for a host's instance-level extensions, such as a window's surface).
    pub fn entry(&self) -> &ash::Entry {
        &self.shared.entry
    }

    /// The instance.
    pub fn instance(&self) -> &ash::Instance {
        &self.shared.instance
    }

    /// The physical device.
    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.shared.physical_device
    }

    /// The queue family every pass runs on.
    pub fn queue_family(&self) -> u32 {
        self.shared.queue_family
    }

    /// Runs `use_queue` with the queue every pass runs on ([`GpuContext::queue_family`]), held
    /// for the call: Vulkan requires a queue's submissions and presents to be externally
    /// synchronised, and cullgraph's own submissions take the same lock. An engine that let
    /// cullgraph create the device submits and presents its own work this way.
    pub fn with_queue<R>(&self, use_queue: impl FnOnce(vk::Queue) -> R) -> R {
        let queue = self.shared.queue.lock().unwrap_or_else(|p| p.into_inner());
        use_queue(*queue)
    }

    /// Device name, limits and timing facts.
    pub fn caps(&self) -> &DeviceCaps {
        &self.shared.caps
    }

    /// Validation messages counted so far (always empty when validation is off or the host owns the messenger).
    pub fn validation_log(&self) -> &ValidationLog {
        &self.shared.validation
    }

    /// Whether pass debug labels can be emitted.
    pub fn has_debug_labels(&self) -> bool {
        self.shared.debug_utils.is_some()
    }

    /// Submits `cmd` to the context's queue, signalling `fence`, with optional extra semaphores.
    ///
    /// Only the headless helpers call this; an embedded renderer records into the host's
    /// command buffers and the host submits.
    pub fn submit(&self, submit: &vk::SubmitInfo2<'_>, fence: vk::Fence) -> GpuResult<()> {
        let queue = self.shared.queue.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: the queue is externally synchronised by the mutex; the caller keeps the
        // command buffers and semaphores alive until the fence signals.
        unsafe { self.shared.device.queue_submit2(*queue, std::slice::from_ref(submit), fence) }.vk("vkQueueSubmit2")
    }

    /// Records commands with `record`, submits them and waits until the GPU has finished.
    pub fn submit_and_wait<R, E: From<GpuError>>(
        &self,
        record: impl FnOnce(vk::CommandBuffer) -> Result<R, E>,
    ) -> Result<R, E> {
        let device = &self.shared.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.shared.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: plain object creation on a valid device; everything is destroyed below.
        unsafe {
            let pool = device.create_command_pool(&pool_info, None).vk("vkCreateCommandPool")?;
            let result = (|| -> Result<R, E> {
                let alloc = vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1);
                let cmd = device.allocate_command_buffers(&alloc).vk("vkAllocateCommandBuffers")?[0];
                let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
                device.begin_command_buffer(cmd, &begin).vk("vkBeginCommandBuffer")?;
                let value = record(cmd)?;
                device.end_command_buffer(cmd).vk("vkEndCommandBuffer")?;
                let fence = device.create_fence(&vk::FenceCreateInfo::default(), None).vk("vkCreateFence")?;
                let cmd_info = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                let submitted = self.submit(&vk::SubmitInfo2::default().command_buffer_infos(&cmd_info), fence);
                profiling::scope!("cullgraph::wait_gpu");
                let waited =
                    submitted.and_then(|_| device.wait_for_fences(&[fence], true, u64::MAX).vk("vkWaitForFences"));
                device.destroy_fence(fence, None);
                waited?;
                Ok(value)
            })();
            device.destroy_command_pool(pool, None);
            result
        }
    }

    /// Opens a debug-label region (no-op without `VK_EXT_debug_utils`).
    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str) {
        if let Some(du) = &self.shared.debug_utils {
            let name = CString::new(name.replace('\0', " ")).unwrap_or_default();
            let label = vk::DebugUtilsLabelEXT::default().label_name(&name);
            // SAFETY: cmd is in the recording state (caller contract).
            unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
        }
    }

    /// Closes the innermost debug-label region.
    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(du) = &self.shared.debug_utils {
            // SAFETY: pairs with begin_label.
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> GpuResult<()> {
        // SAFETY: valid device.
        unsafe { self.shared.device.device_wait_idle() }.vk("vkDeviceWaitIdle")
    }
}

/// Lists the devices the loader sees, for `cullgraph devices` and error messages.
pub fn list_devices() -> GpuResult<Vec<DeviceInfo>> {
    // SAFETY: loading the system Vulkan loader.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::Loader(e.to_string()))?;
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    // SAFETY: minimal instance, destroyed below.
    unsafe {
        let instance = entry.create_instance(&info, None).vk("vkCreateInstance")?;
        let devices = device_select::enumerate(&instance);
        instance.destroy_instance(None);
        devices
    }
}

/// Destroys a half-built instance when device creation fails.
struct InstanceGuard<'a> {
    instance: &'a ash::Instance,
    messenger: Option<&'a (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl Drop for InstanceGuard<'_> {
    fn drop(&mut self) {
        // SAFETY: nothing else was created from the instance yet.
        unsafe {
            if let Some((loader, m)) = self.messenger {
                loader.destroy_debug_utils_messenger(*m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

type Messenger = (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT);

fn create_instance(
    entry: &ash::Entry,
    options: &ContextOptions,
    log: &ValidationLog,
) -> GpuResult<(ash::Instance, Option<Messenger>)> {
    // SAFETY: querying the loader.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
    let has_layer = layers.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
    if options.validation && !has_layer {
        return Err(GpuError::ValidationLayerMissing);
    }
    // SAFETY: querying the loader.
    let exts =
        unsafe { entry.enumerate_instance_extension_properties(None) }.vk("vkEnumerateInstanceExtensionProperties")?;
    let has_ext = |name: &CStr| lists_extension(&exts, name);
    let debug_utils = has_ext(ash::ext::debug_utils::NAME) || options.validation;

    let app_name = CString::new(options.app_name.replace('\0', " ")).unwrap_or_default();
    let app = vk::ApplicationInfo::default()
        .application_name(&app_name)
        .engine_name(c"cullgraph")
        .api_version(vk::API_VERSION_1_3);
    let mut layer_names: Vec<*const c_char> = Vec::new();
    let mut ext_names: Vec<*const c_char> = Vec::new();
    if debug_utils {
        ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    if options.validation {
        layer_names.push(VALIDATION_LAYER.as_ptr());
        ext_names.push(ash::ext::validation_features::NAME.as_ptr());
    }
    let missing: Vec<String> = options
        .instance_extensions
        .iter()
        .filter(|want| !has_ext(want))
        .map(|want| want.to_string_lossy().into_owned())
        .collect();
    if !missing.is_empty() {
        return Err(GpuError::Loader(format!("the Vulkan loader lacks instance extension(s) {}", missing.join(", "))));
    }
    ext_names.extend(options.instance_extensions.iter().map(|e| e.as_ptr()));
    let ext_names = without_repeats(ext_names);
    // Synchronization validation is off by default in the layer; the Debian layer (1.3.239) only
    // understands VkValidationFeaturesEXT, not VK_EXT_layer_settings.
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut messenger_info = validation::messenger_info(log);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names);
    if options.validation {
        // Chaining the messenger catches messages raised during vkCreateInstance/vkDestroyInstance.
        info = info.push_next(&mut features).push_next(&mut messenger_info);
    }
    // SAFETY: every pointer in `info` lives on this stack frame.
    let instance = unsafe { entry.create_instance(&info, None) }.vk("vkCreateInstance")?;
    let messenger = if options.validation {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        let info = validation::messenger_info(log);
        // SAFETY: `log` is boxed by the caller and outlives the messenger.
        match unsafe { loader.create_debug_utils_messenger(&info, None) } {
            Ok(m) => Some((loader, m)),
            Err(result) => {
                // SAFETY: nothing else was created from the instance.
                unsafe { instance.destroy_instance(None) };
                return Err(GpuError::Vk { call: "vkCreateDebugUtilsMessengerEXT", result });
            }
        }
    } else {
        None
    };
    Ok((instance, messenger))
}

fn find_queue_family(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Option<u32> {
    // SAFETY: valid handles.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    families.iter().position(|f| f.queue_flags.contains(wanted)).map(|i| i as u32)
}

fn create_device(
    instance: &ash::Instance,
    chosen: &DeviceInfo,
    queue_family: u32,
    extra_extensions: &[CString],
) -> GpuResult<ash::Device> {
    let supported = RequiredFeatures::supported_by(instance, chosen.handle);
    let mut required = RequiredFeatures::new();
    // Not needed by cullgraph itself, but a caller of `FramePipeline::submit_with` can only make
    // timeline semaphores on a device that enabled them (every Vulkan 1.2 device supports them).
    required.v12.timeline_semaphore = supported.v12.timeline_semaphore;
    // Optional: only the views bench's multiview measurement draws with it (`DeviceCaps::multiview`).
    required.v11.multiview = supported.v11.multiview;
    let mut missing: Vec<String> = required.missing_from(&supported).into_iter().map(String::from).collect();
    // SAFETY: valid handles.
    let exts = unsafe { instance.enumerate_device_extension_properties(chosen.handle) }
        .vk("vkEnumerateDeviceExtensionProperties")?;
    for want in REQUIRED_DEVICE_EXTENSIONS.iter().copied().chain(extra_extensions.iter().map(CString::as_c_str)) {
        if !lists_extension(&exts, want) {
            missing.push(want.to_string_lossy().into_owned());
        }
    }
    if !missing.is_empty() {
        return Err(GpuError::MissingFeatures { device: chosen.name.clone(), missing: missing.join(", ") });
    }
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
    let mut ext_names: Vec<*const c_char> = REQUIRED_DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
    ext_names.extend(extra_extensions.iter().map(|e| e.as_ptr()));
    for want in super::features::OPTIONAL_DEVICE_EXTENSIONS {
        if lists_extension(&exts, want) {
            ext_names.push(want.as_ptr());
        }
    }
    // An ordered sample interlock lets the claim graph settle coplanar ties in draw order
    // (`gbuffer_compressed`'s `claim_order`); enabled with its extension when the device has both.
    let interlock_ext = ash::ext::fragment_shader_interlock::NAME;
    let has_interlock = lists_extension(&exts, interlock_ext) && sample_interlock_supported(instance, chosen.handle);
    if has_interlock {
        ext_names.push(interlock_ext.as_ptr());
    }
    let ext_names = without_repeats(ext_names);
    let mut interlock =
        vk::PhysicalDeviceFragmentShaderInterlockFeaturesEXT::default().fragment_shader_sample_interlock(true);
    let mut features2 = required.chain();
    let mut info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&ext_names)
        .push_next(&mut features2);
    if has_interlock {
        info = info.push_next(&mut interlock);
    }
    // SAFETY: every pointer in `info` lives on this stack frame.
    unsafe { instance.create_device(chosen.handle, &info, None) }.vk("vkCreateDevice")
}

/// The extension names with repeats dropped: a host may ask for one that cullgraph enables too,
/// and Vulkan takes each name once.
fn without_repeats(names: Vec<*const c_char>) -> Vec<*const c_char> {
    let mut out: Vec<*const c_char> = Vec::with_capacity(names.len());
    for name in names {
        // SAFETY: every pointer is a NUL-terminated name (static, or the caller's options) that
        // outlives the create call it is gathered for.
        if !out.iter().any(|&seen| unsafe { CStr::from_ptr(seen) == CStr::from_ptr(name) }) {
            out.push(name);
        }
    }
    out
}

/// Whether the device supports `fragmentShaderSampleInterlock`.
pub(crate) fn sample_interlock_supported(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let mut interlock = vk::PhysicalDeviceFragmentShaderInterlockFeaturesEXT::default();
    let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut interlock);
    // SAFETY: valid handles; the chain lives on this stack frame.
    unsafe { instance.get_physical_device_features2(pd, &mut features2) };
    interlock.fragment_shader_sample_interlock == vk::TRUE
}

fn device_name(instance: &ash::Instance, pd: vk::PhysicalDevice) -> String {
    // SAFETY: valid handles.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The device's properties; `enabled_extension` says whether a supported device extension was
/// enabled when the device was created.
fn query_caps(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    queue_family: u32,
    enabled_extension: &dyn Fn(&CStr) -> bool,
) -> DeviceCaps {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    // SAFETY: valid handles; the chain lives on this frame.
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;
    // SAFETY: valid handles.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    // SAFETY: valid handles.
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |name: &CStr| lists_extension(&exts, name) && enabled_extension(name);
    DeviceCaps {
        name: props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        kind: props.device_type,
        limits: props.limits,
        timestamp_period_ns: props.limits.timestamp_period as f64,
        timestamp_valid_bits: families.get(queue_family as usize).map_or(0, |f| f.timestamp_valid_bits),
        subgroup_size: subgroup.subgroup_size,
        subgroup_compute_ops: if subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE) {
            subgroup.supported_operations
        } else {
            vk::SubgroupFeatureFlags::empty()
        },
        post_depth_coverage: has(ash::ext::post_depth_coverage::NAME),
        sample_interlock: has(ash::ext::fragment_shader_interlock::NAME) && sample_interlock_supported(instance, pd),
        buffer_addresses: false,
        // Core since 1.1: the extension's name is only a host's word that the feature is on
        // (an owned device says yes to every name, having enabled what is supported).
        multiview: enabled_extension(super::features::MULTIVIEW_EXTENSION)
            && RequiredFeatures::supported_by(instance, pd).v11.multiview == vk::TRUE,
    }
}
