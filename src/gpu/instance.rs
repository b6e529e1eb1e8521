//! Creating what the engine owns when it is not embedded: the loader, the instance (with the
//! validation layer and synchronization validation when asked), the choice of physical device
//! and the logical device with one graphics+compute queue.

use std::ffi::{c_char, CStr, CString};
use std::sync::Arc;

use ash::vk;

use super::debug::{messenger_info, ValidationLog};
use super::error::{GpuError, GpuResult, VkContext};
use super::GpuDesc;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Opens the Vulkan loader: the system's `libvulkan.so.1`, or `desc.loader_path`.
pub(crate) fn load_entry(desc: &GpuDesc) -> GpuResult<ash::Entry> {
    let entry = match &desc.loader_path {
        // SAFETY: loading a Vulkan loader runs its initialisers; the user named this library
        // as one (GALERKIN_VULKAN_LIBRARY).
        Some(path) => unsafe { ash::Entry::load_from(path) },
        // SAFETY: as above, for the system's `libvulkan.so.1`.
        None => unsafe { ash::Entry::load() },
    };
    entry.map_err(|e| GpuError::NoLoader {
        detail: match &desc.loader_path {
            Some(p) => format!("{}: {e}", p.display()),
            None => e.to_string(),
        },
    })
}

/// The instance and, when validation is on, its messenger.
pub(crate) struct CreatedInstance {
    pub instance: ash::Instance,
    pub messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The API version the instance was created for.
    pub api: u32,
}

/// Creates the instance: Vulkan 1.3 where the loader has it (1.2 at least), the caller's
/// extra instance extensions (window surfaces), and with `desc.validation` the Khronos layer,
/// synchronization validation where the layer supports it, and the error canary.
pub(crate) fn create_instance(
    entry: &ash::Entry,
    desc: &GpuDesc,
    log: &Arc<ValidationLog>,
) -> GpuResult<CreatedInstance> {
    // SAFETY: plain loader query.
    let loader_version = unsafe { entry.try_enumerate_instance_version() }
        .vk("vkEnumerateInstanceVersion")?
        .unwrap_or(vk::API_VERSION_1_0);
    if loader_version < vk::API_VERSION_1_2 {
        return Err(GpuError::NoDevice {
            detail: format!(
                ": the Vulkan loader supports only {}.{}, galerkin needs 1.2",
                vk::api_version_major(loader_version),
                vk::api_version_minor(loader_version)
            ),
        });
    }
    let api = loader_version.min(vk::API_VERSION_1_3);
    let app_name = CString::new(desc.app_name.replace('\0', " ")).unwrap_or_default();
    let app = vk::ApplicationInfo::default()
        .application_name(&app_name)
        .engine_name(c"galerkin")
        .engine_version(vk::make_api_version(0, 0, 1, 0))
        .api_version(api);

    let mut layers: Vec<*const c_char> = Vec::new();
    let mut extensions: Vec<*const c_char> = desc.instance_extensions.iter().map(|e| e.as_ptr()).collect();
    let mut sync_validation = false;
    if desc.validation {
        // SAFETY: plain loader query.
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .vk("vkEnumerateInstanceLayerProperties")?;
        let found = available.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        if !found {
            return Err(GpuError::NoValidationLayer);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        // SAFETY: plain loader query for the layer's own extensions.
        let layer_exts = unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }
            .unwrap_or_default();
        if desc.sync_validation
            && layer_exts
                .iter()
                .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::validation_features::NAME))
        {
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
            sync_validation = true;
        }
    }

    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut chained_messenger = messenger_info(log);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if desc.validation {
        info = info.push_next(&mut chained_messenger);
        if sync_validation {
            info = info.push_next(&mut features);
        }
    }
    // SAFETY: every pointer in `info` refers to locals that outlive the call.
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(|result| match result {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
            GpuError::NoDevice { detail: ": vkCreateInstance found no compatible driver".into() }
        }
        vk::Result::ERROR_EXTENSION_NOT_PRESENT => {
            GpuError::Unsupported(format!("the instance extensions {:?}", desc.instance_extensions))
        }
        other => GpuError::Vk { call: "vkCreateInstance", result: other },
    })?;

    let messenger = if desc.validation {
        let loader = ash::ext::debug_utils::Instance::new(entry, &instance);
        // SAFETY: the instance was created with VK_EXT_debug_utils; `log` outlives the messenger
        // (the context holds the Arc until after it destroys the messenger).
        match unsafe { loader.create_debug_utils_messenger(&messenger_info(log), None) } {
            Ok(m) => Some((loader, m)),
            Err(e) => {
                // SAFETY: nothing else was created from this instance yet.
                unsafe { instance.destroy_instance(None) };
                return Err(GpuError::Vk { call: "vkCreateDebugUtilsMessengerEXT", result: e });
            }
        }
    } else {
        None
    };
    Ok(CreatedInstance { instance, messenger, api })
}

/// The chosen device and the family of its one queue.
pub(crate) struct Choice {
    pub physical: vk::PhysicalDevice,
    pub queue_family: u32,
}

fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Picks a device: Vulkan 1.2 or newer with a graphics+compute queue (and the swapchain
/// extension when asked), preferring discrete > integrated > virtual > CPU; `desc.device_name`
/// (from `GALERKIN_DEVICE`) keeps only devices whose name contains it, case-insensitively.
pub(crate) fn choose_device(instance: &ash::Instance, desc: &GpuDesc) -> GpuResult<Choice> {
    // SAFETY: plain instance query.
    let devices = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    let mut seen = Vec::new();
    let mut best: Option<(u32, Choice)> = None;
    for physical in devices {
        // SAFETY: `physical` comes from this instance.
        let props = unsafe { instance.get_physical_device_properties(physical) };
        let name = props.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        seen.push(name.clone());
        if let Some(want) = &desc.device_name {
            if !name.to_lowercase().contains(&want.to_lowercase()) {
                continue;
            }
        }
        if props.api_version < vk::API_VERSION_1_2 {
            continue;
        }
        if desc.swapchain && !has_device_extension(instance, physical, ash::khr::swapchain::NAME) {
            continue;
        }
        // SAFETY: as above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let Some(family) = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        else {
            continue;
        };
        let rank = type_rank(props.device_type);
        if best.as_ref().is_none_or(|(r, _)| rank < *r) {
            best = Some((rank, Choice { physical, queue_family: family as u32 }));
        }
    }
    best.map(|(_, c)| c).ok_or_else(|| GpuError::NoDevice {
        detail: match (&desc.device_name, seen.is_empty()) {
            (_, true) => " (the loader found no devices)".to_string(),
            (Some(want), false) => format!(
                " matching GALERKIN_DEVICE={want:?} with Vulkan 1.2 and a graphics+compute queue \
                 (devices seen: {})",
                seen.join(", ")
            ),
            (None, false) => {
                format!(" with Vulkan 1.2 and a graphics+compute queue (devices seen: {})", seen.join(", "))
            }
        },
    })
}

pub(crate) fn has_device_extension(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    name: &CStr,
) -> bool {
    // SAFETY: plain instance query on a device of this instance.
    unsafe { instance.enumerate_device_extension_properties(physical) }
        .unwrap_or_default()
        .iter()
        .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
}

/// Creates the logical device with one queue of `choice.queue_family`, enabling the optional
/// core features galerkin uses when the device has them (f64 in shaders, geometry and
/// tessellation shaders, wireframe fill, and on Vulkan 1.3 dynamic rendering). Returns the
/// device, the core features actually enabled and whether dynamic rendering and
/// synchronization2 were.
pub(crate) fn create_device(
    instance: &ash::Instance,
    instance_api: u32,
    choice: &Choice,
    desc: &GpuDesc,
) -> GpuResult<(ash::Device, vk::PhysicalDeviceFeatures, bool, bool)> {
    // SAFETY: plain instance query.
    let supported = unsafe { instance.get_physical_device_features(choice.physical) };
    // Vulkan 1.3's features, on a 1.3 device under a 1.3 instance (create_instance asks for 1.3
    // whenever the loader has it).
    // SAFETY: plain instance query.
    let api = unsafe { instance.get_physical_device_properties(choice.physical) }.api_version;
    let has_13 = api >= vk::API_VERSION_1_3 && instance_api >= vk::API_VERSION_1_3;
    let mut supported13 = vk::PhysicalDeviceVulkan13Features::default();
    if has_13 {
        let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut supported13);
        // SAFETY: Vulkan 1.1 core query on a device of this instance; the chain outlives it.
        unsafe { instance.get_physical_device_features2(choice.physical, &mut features2) };
    }
    let dynamic_rendering = has_13 && supported13.dynamic_rendering == vk::TRUE;
    let synchronization2 = desc.synchronization2 && has_13 && supported13.synchronization2 == vk::TRUE;
    let mut enabled13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(dynamic_rendering)
        .synchronization2(synchronization2);
    let enabled = vk::PhysicalDeviceFeatures {
        shader_float64: supported.shader_float64,
        geometry_shader: supported.geometry_shader,
        tessellation_shader: supported.tessellation_shader,
        fill_mode_non_solid: supported.fill_mode_non_solid,
        wide_lines: supported.wide_lines,
        ..Default::default()
    };
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(choice.queue_family)
        .queue_priorities(&priorities)];
    let mut extensions: Vec<*const c_char> = Vec::new();
    if desc.swapchain {
        extensions.push(ash::khr::swapchain::NAME.as_ptr());
    }
    let mut info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .enabled_features(&enabled);
    if has_13 {
        info = info.push_next(&mut enabled13);
    }
    // SAFETY: `info` points at locals that outlive the call; `choice.physical` is of `instance`.
    let device = unsafe { instance.create_device(choice.physical, &info, None) }.vk("vkCreateDevice")?;
    Ok((device, enabled, dynamic_rendering, synchronization2))
}
