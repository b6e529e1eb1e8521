//! The device context: one [`Gpu`] per device, either created by the engine ([`Gpu::new`]) or
//! adopted from a host application ([`Gpu::from_raw`]).
//!
//! Like wgpu-hal's `DeviceShared`, everything resources need — the `ash::Device`, the queue,
//! the allocator, the capabilities, the retirement list — lives in one [`DeviceShared`] behind
//! an `Arc` that every resource holds. The device therefore outlives every buffer, image and
//! pipeline made on it, and teardown happens in one place, in a fixed order: finished work is
//! retired, the engine's command pool goes, the allocator is dropped (freeing its memory
//! blocks), then the device, the messenger and the instance — the last two only if the engine
//! created them.

use std::mem::ManuallyDrop;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::caps::Capabilities;
use super::debug::ValidationLog;
use super::error::{GpuError, GpuResult, VkContext};
use super::fault::FaultInjection;
use super::instance;
use super::retire::{Retirement, Tracker};

/// How to create a [`Gpu`]. `Default` is the same everywhere and reads nothing from the
/// environment (what an embedding host wants: its process's variables do not change the
/// engine's behaviour); [`GpuDesc::from_env`] adds what the command line reads:
/// `GALERKIN_VALIDATION=1` turns on the Khronos validation layer,
/// `GALERKIN_SYNC_VALIDATION=0` leaves out its synchronization checks,
/// `GALERKIN_DEVICE=<substring>` picks a device by name,
/// `GALERKIN_VULKAN_LIBRARY=<path>` loads a specific Vulkan loader,
/// `GALERKIN_SYNCHRONIZATION2=0` records Vulkan 1.0 barriers on a 1.3 device, and, in a build
/// with the `fault-injection` feature, the fault injection of the tests
/// (`GALERKIN_FAIL_ALLOCATION=N`, `GALERKIN_LOSE_DEVICE=N`).
#[derive(Clone, Debug)]
pub struct GpuDesc {
    /// Application name given to the driver.
    pub app_name: String,
    /// Enable `VK_LAYER_KHRONOS_validation` and record its errors in a [`ValidationLog`].
    pub validation: bool,
    /// With validation, also enable synchronization validation where the layer supports it.
    pub sync_validation: bool,
    /// Keep only devices whose name contains this (case-insensitive).
    pub device_name: Option<String>,
    /// Extra instance extensions (a window's surface extensions).
    pub instance_extensions: Vec<&'static std::ffi::CStr>,
    /// Require and enable `VK_KHR_swapchain` (the viewer).
    pub swapchain: bool,
    /// How long [`Gpu::run`] waits for a submission before reporting [`GpuError::Timeout`].
    pub fence_timeout: Duration,
    /// Bind storage buffers in chunks of at most this many bytes (clamped to the device's
    /// `maxStorageBufferRange`). Lets tests exercise chunking with small arrays.
    pub max_binding_bytes: Option<u64>,
    /// Load the Vulkan loader from this path instead of the system's `libvulkan.so.1`.
    pub loader_path: Option<PathBuf>,
    /// With validation: record its messages into this log (shared by every [`Gpu`] made from
    /// this description) instead of a new one per `Gpu`, so that a caller can check once,
    /// after all of them are dropped and their leak reports are in (the command line does).
    pub validation_log: Option<Arc<ValidationLog>>,
    /// Enable Vulkan 1.3's `synchronization2` where the device has it, and record barriers with
    /// `vkCmdPipelineBarrier2` (default); false keeps Vulkan 1.0's `vkCmdPipelineBarrier` (the
    /// path of older devices, kept tested).
    pub synchronization2: bool,
    /// Fault injection for tests (feature `fault-injection`): the device allocation with this number (1 = the first, counted
    /// per [`Gpu`]) fails as out of memory, and so does every one after it
    /// (`GALERKIN_FAIL_ALLOCATION=N`): every command must then fail with an error, leaving
    /// nothing behind and leaking no Vulkan object.
    #[cfg(feature = "fault-injection")]
    pub fail_allocation: Option<u64>,
    /// Fault injection for tests (feature `fault-injection`): the wait for the submission with this number (1 = the
    /// first, counted per [`Gpu`]) reports the device lost once the work has really finished,
    /// and every later submission fails as lost (`GALERKIN_LOSE_DEVICE=N`): every command must
    /// then fail with an error, leaving nothing behind and leaking no Vulkan object.
    #[cfg(feature = "fault-injection")]
    pub lose_device: Option<u64>,
}

impl Default for GpuDesc {
    /// No validation (synchronization validation on when validation is), the first suitable
    /// device, the system's loader, a 600 s fence timeout, no fault injection.
    fn default() -> Self {
        Self {
            app_name: "galerkin".into(),
            validation: false,
            sync_validation: true,
            device_name: None,
            instance_extensions: Vec::new(),
            swapchain: false,
            fence_timeout: Duration::from_secs(600),
            max_binding_bytes: None,
            loader_path: None,
            validation_log: None,
            synchronization2: true,
            #[cfg(feature = "fault-injection")]
            fail_allocation: None,
            #[cfg(feature = "fault-injection")]
            lose_device: None,
        }
    }
}

impl GpuDesc {
    /// [`GpuDesc::default`] with the `GALERKIN_*` environment variables applied (the command
    /// line's description; see [`GpuDesc`]). A variable that is unset, empty or unparsable
    /// leaves the default.
    pub fn from_env() -> Self {
        let var = |k: &str| std::env::var(k).ok().filter(|v| !v.trim().is_empty());
        let d = Self::default();
        Self {
            validation: var("GALERKIN_VALIDATION").is_some_and(|v| v != "0"),
            sync_validation: var("GALERKIN_SYNC_VALIDATION").map_or(d.sync_validation, |v| v != "0"),
            device_name: var("GALERKIN_DEVICE"),
            loader_path: std::env::var_os("GALERKIN_VULKAN_LIBRARY")
                .filter(|p| !p.is_empty())
                .map(PathBuf::from),
            synchronization2: var("GALERKIN_SYNCHRONIZATION2").map_or(d.synchronization2, |v| v != "0"),
            #[cfg(feature = "fault-injection")]
            fail_allocation: var("GALERKIN_FAIL_ALLOCATION").and_then(|v| v.trim().parse().ok()),
            #[cfg(feature = "fault-injection")]
            lose_device: var("GALERKIN_LOSE_DEVICE").and_then(|v| v.trim().parse().ok()),
            ..d
        }
    }
}

/// The Vulkan objects a host application hands to [`Gpu::from_raw`]. The engine uses them and
/// destroys none of them.
pub struct RawDevice {
    /// The host's loader entry.
    pub entry: ash::Entry,
    /// The host's instance.
    pub instance: ash::Instance,
    /// The physical device `device` was created from.
    pub physical_device: vk::PhysicalDevice,
    /// The host's logical device.
    pub device: ash::Device,
    /// Family index of `queue`.
    pub queue_family: u32,
    /// A queue of that family supporting graphics and compute. The engine submits to it only
    /// from [`Gpu::run`] / [`Gpu::submit`]; the host must not use it concurrently with those.
    pub queue: vk::Queue,
    /// The core features the host enabled on `device` (the engine only uses what is enabled).
    pub enabled_features: vk::PhysicalDeviceFeatures,
    /// True if the host enabled dynamic rendering (Vulkan 1.3's `dynamicRendering` or
    /// `VK_KHR_dynamic_rendering`): galerkin's draws can then be recorded inside the host's
    /// `vkCmdBeginRendering` ([`super::RenderPass::dynamic`]).
    pub dynamic_rendering: bool,
    /// True if the host enabled Vulkan 1.3's `synchronization2` (then the engine records its
    /// barriers with `vkCmdPipelineBarrier2`; `VK_KHR_synchronization2` on a 1.2 device is not
    /// used: say false, and the Vulkan 1.0 barrier is recorded).
    pub synchronization2: bool,
}

/// State shared by the context and every resource made on it.
pub(crate) struct DeviceShared {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub raw: ash::Device,
    pub queue: Mutex<vk::Queue>,
    pub queue_family: u32,
    pub caps: Capabilities,
    pub max_binding_bytes: u64,
    pub fence_timeout: Duration,
    /// The faults the description asks for (feature `fault-injection`), with their counts.
    pub(crate) fault: FaultInjection,
    pub(crate) allocator: Mutex<ManuallyDrop<Allocator>>,
    pub(crate) tracker: Mutex<Tracker>,
    /// Destructors of objects whose last reference went while this device was being torn
    /// down (they can no longer reach it); its teardown runs them. Every [`super::lifetime::Lifetime`]
    /// made on this device holds it.
    pub(crate) graveyard: Arc<Mutex<Vec<Retirement>>>,
    debug_names: Option<ash::ext::debug_utils::Device>,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    log: Option<Arc<ValidationLog>>,
    owns_instance: bool,
    owns_device: bool,
}

impl DeviceShared {
    /// Locks the allocator; a poisoned lock (a panic while allocating) is still usable.
    pub(crate) fn allocator(&self) -> MutexGuard<'_, ManuallyDrop<Allocator>> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Gives a Vulkan object a debug name (shown in validation messages), when debug utils is on.
    pub(crate) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(d) = &self.debug_names {
            let Ok(name) = std::ffi::CString::new(name.replace('\0', " ")) else {
                return;
            };
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // SAFETY: `handle` is a live object of this device; naming is informational.
            let _ = unsafe { d.set_debug_utils_object_name(&info) };
        }
    }
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        // Every Submission holds an Arc to this, so none is in flight except timed-out ones
        // (waited for here). Release their objects and those of orphaned host recordings.
        let (abandoned_slots, uses) = self.drain_abandoned();
        drop(uses);
        drop(self.tracker.get_mut().map(|t| std::mem::take(&mut t.orphans)));
        // Destructors may release further objects (a set the resources it bound), whose
        // destructors, unable to reach this device any more, queue for it: run until none is
        // left (bounded: every object is destroyed once).
        loop {
            let leftovers: Vec<Retirement> =
                self.graveyard.lock().unwrap_or_else(|p| p.into_inner()).drain(..).collect();
            if leftovers.is_empty() {
                break;
            }
            for f in leftovers {
                f(self);
            }
        }
        for slot in abandoned_slots {
            slot.destroy(self);
        }
        // SAFETY: teardown in dependency order; no work is in flight (see above), every resource
        // made on this device has been dropped (they hold this Arc), and the engine destroys only
        // the objects it created.
        unsafe {
            let slots = self.tracker.get_mut().map(|t| std::mem::take(&mut t.free)).unwrap_or_default();
            for slot in slots {
                slot.destroy(self);
            }
            if let Ok(a) = self.allocator.get_mut() {
                ManuallyDrop::drop(a);
            }
            if self.owns_device {
                self.raw.destroy_device(None);
            }
            if let Some((loader, m)) = self.messenger.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            if self.owns_instance {
                self.instance.destroy_instance(None);
            }
        }
        // `log` (if any) drops after the instance, so the leak reports of destroy_* land in it.
        let _ = self.log.take();
    }
}

/// The engine's handle on a Vulkan device: create one with [`Gpu::new`] or adopt a host's with
/// [`Gpu::from_raw`]. Cheap to clone (an `Arc`); the device goes when the last clone and the
/// last resource made on it are dropped.
#[derive(Clone)]
pub struct Gpu {
    pub(crate) shared: Arc<DeviceShared>,
    pub(crate) staging: Arc<super::staging::StagingPool>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("device", &self.shared.caps.device_name)
            .field("driver", &self.shared.caps.driver)
            .field("adopted", &!self.shared.owns_device)
            .finish()
    }
}

impl Gpu {
    /// Creates an instance and a headless device (no window needed): see [`GpuDesc`] for the
    /// choices and the environment variables that set them.
    pub fn new(desc: &GpuDesc) -> GpuResult<Self> {
        let entry = instance::load_entry(desc)?;
        let log = desc.validation.then(|| desc.validation_log.clone().unwrap_or_default());
        let created = instance::create_instance(&entry, desc, log.as_ref().unwrap_or(&Arc::default()))?;
        // From here on a failure must destroy what was created: wrap in a guard.
        struct InstanceGuard(Option<instance::CreatedInstance>);
        impl Drop for InstanceGuard {
            fn drop(&mut self) {
                if let Some(c) = self.0.take() {
                    // SAFETY: nothing made from this instance survives a failed `Gpu::new`.
                    unsafe {
                        if let Some((l, m)) = c.messenger {
                            l.destroy_debug_utils_messenger(m, None);
                        }
                        c.instance.destroy_instance(None);
                    }
                }
            }
        }
        let mut guard = InstanceGuard(Some(created));
        let inst = &guard.0.as_ref().expect("guard holds the instance").instance;
        let choice = instance::choose_device(inst, desc)?;
        let api = guard.0.as_ref().expect("guard holds the instance").api;
        let (device, enabled, dynamic_rendering, synchronization2) =
            instance::create_device(inst, api, &choice, desc)?;
        // SAFETY: queue 0 of the family was requested in `create_device`.
        let queue = unsafe { device.get_device_queue(choice.queue_family, 0) };
        let created = guard.0.take().expect("guard holds the instance");
        let debug_names =
            desc.validation.then(|| ash::ext::debug_utils::Device::new(&created.instance, &device));
        Self::assemble(Parts {
            entry,
            instance: created.instance,
            physical: choice.physical,
            device,
            queue_family: choice.queue_family,
            queue,
            enabled,
            dynamic_rendering,
            synchronization2,
            messenger: created.messenger,
            debug_names,
            log,
            owns: true,
            desc,
        })
    }

    /// Adopts a host application's Vulkan objects. The engine creates its own command pools,
    /// fences, allocator and resources on the host's device, submits only from
    /// [`Gpu::run`]/[`Gpu::submit`], and on drop destroys only those. Of `desc`, only
    /// `fence_timeout` and `max_binding_bytes` apply: validation, extensions and device choice
    /// are the host's (validation messages go to the host's own messenger).
    ///
    /// # Safety
    /// - `raw.instance`, `raw.physical_device` and `raw.device` are valid, belong together, and
    ///   were loaded from `raw.entry`; the device was created with API version 1.2 or newer.
    /// - `raw.queue` is a queue of family `raw.queue_family` of `raw.device`, that family
    ///   supports graphics and compute, and the host does not access the queue concurrently
    ///   with [`Gpu::run`]/[`Gpu::submit`] (Vulkan requires external synchronisation).
    /// - `raw.enabled_features` is a subset of what the device was created with, and
    ///   `raw.dynamic_rendering` is true only if dynamic rendering was enabled.
    /// - The host keeps the instance and device alive until this `Gpu`, its clones and every
    ///   resource made from it have been dropped.
    /// - Work the host submits that uses engine resources has completed before those resources
    ///   are dropped (the engine tracks only its own submissions).
    pub unsafe fn from_raw(raw: RawDevice, desc: &GpuDesc) -> GpuResult<Self> {
        Self::assemble(Parts {
            entry: raw.entry,
            instance: raw.instance,
            physical: raw.physical_device,
            device: raw.device,
            queue_family: raw.queue_family,
            queue: raw.queue,
            enabled: raw.enabled_features,
            dynamic_rendering: raw.dynamic_rendering,
            synchronization2: raw.synchronization2,
            messenger: None,
            debug_names: None,
            log: None,
            owns: false,
            desc,
        })
    }

    fn assemble(p: Parts<'_>) -> GpuResult<Self> {
        let caps = Capabilities::read(
            &p.instance,
            p.physical,
            p.queue_family,
            &p.enabled,
            p.dynamic_rendering,
            p.synchronization2,
        );
        let mut debug = gpu_allocator::AllocatorDebugSettings::default();
        debug.log_leaks_on_shutdown = true;
        let allocator = match Allocator::new(&AllocatorCreateDesc {
            instance: p.instance.clone(),
            device: p.device.clone(),
            physical_device: p.physical,
            debug_settings: debug,
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        }) {
            Ok(a) => a,
            Err(e) => {
                if p.owns {
                    // SAFETY: nothing was created on this device yet; the engine owns both.
                    unsafe {
                        p.device.destroy_device(None);
                        if let Some((l, m)) = p.messenger {
                            l.destroy_debug_utils_messenger(m, None);
                        }
                        p.instance.destroy_instance(None);
                    }
                }
                return Err(GpuError::OutOfMemory {
                    name: "gpu-allocator".into(),
                    bytes: 0,
                    detail: e.to_string(),
                });
            }
        };
        let range = caps.max_storage_buffer_range;
        let max_binding_bytes = p.desc.max_binding_bytes.map_or(range, |m| m.clamp(256, range));
        tracing::info!(device = %caps.device_name, driver = %caps.driver, adopted = !p.owns, "galerkin Gpu ready");
        Ok(Self {
            staging: Arc::default(),
            shared: Arc::new(DeviceShared {
                entry: p.entry,
                instance: p.instance,
                physical: p.physical,
                raw: p.device,
                queue: Mutex::new(p.queue),
                queue_family: p.queue_family,
                caps,
                max_binding_bytes,
                fence_timeout: p.desc.fence_timeout,
                fault: FaultInjection::from_desc(p.desc),
                allocator: Mutex::new(ManuallyDrop::new(allocator)),
                tracker: Mutex::new(Tracker::default()),
                graveyard: Arc::default(),
                debug_names: p.debug_names,
                messenger: p.messenger,
                log: p.log,
                owns_instance: p.owns,
                owns_device: p.owns,
            }),
        })
    }

    /// Waits until the queue has finished everything submitted to it, presentation included:
    /// before destroying objects (a swapchain's semaphores) that a present may still be
    /// waiting on, which no fence covers.
    pub fn wait_queue_idle(&self) -> GpuResult<()> {
        let queue = self.shared.queue.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: the queue is externally synchronised by its mutex.
        unsafe { self.shared.raw.queue_wait_idle(*queue) }.vk("vkQueueWaitIdle")
    }

    /// What the device can do.
    pub fn caps(&self) -> &Capabilities {
        &self.shared.caps
    }

    /// The logical device, for recording commands.
    pub fn device(&self) -> &ash::Device {
        &self.shared.raw
    }

    /// The instance.
    pub fn instance(&self) -> &ash::Instance {
        &self.shared.instance
    }

    /// The loader entry.
    pub fn entry(&self) -> &ash::Entry {
        &self.shared.entry
    }

    /// The physical device.
    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.shared.physical
    }

    /// Family index of the queue the engine submits to.
    pub fn queue_family(&self) -> u32 {
        self.shared.queue_family
    }

    /// Largest byte range the engine binds as one storage-buffer descriptor: the device's
    /// `maxStorageBufferRange`, or less if [`GpuDesc::max_binding_bytes`] asked.
    pub fn max_binding_bytes(&self) -> u64 {
        self.shared.max_binding_bytes
    }

    /// The validation errors recorded on this context (`None` without validation).
    /// Keep the `Arc` past dropping the `Gpu` to see leak reports.
    pub fn validation_log(&self) -> Option<Arc<ValidationLog>> {
        self.shared.log.clone()
    }

    /// True if the engine adopted a host's device ([`Gpu::from_raw`]).
    pub fn is_adopted(&self) -> bool {
        !self.shared.owns_device
    }
}

struct Parts<'a> {
    entry: ash::Entry,
    instance: ash::Instance,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue_family: u32,
    queue: vk::Queue,
    enabled: vk::PhysicalDeviceFeatures,
    dynamic_rendering: bool,
    synchronization2: bool,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    debug_names: Option<ash::ext::debug_utils::Device>,
    log: Option<Arc<ValidationLog>>,
    owns: bool,
    desc: &'a GpuDesc,
}
