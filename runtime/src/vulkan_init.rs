//! Opening a raw Vulkan device: load libvulkan, create the instance (with the validation
//! layer and a messenger that collects its messages where wanted), pick a physical device,
//! enable its features, create the logical device and the memory allocator, and describe
//! the result as `DeviceInfo` + `Limits`. `vulkan_backend` builds everything else on top.

use std::ffi::{c_void, CStr};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::{AllocationSizes, AllocatorDebugSettings};

use crate::device::Limits;
use crate::error::VkContext;
use crate::{BackendKind, DeviceInfo, Result, RuntimeError};

const BACKEND: BackendKind = BackendKind::Vulkan;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Owns the instance, the logical device and the allocator; destroyed last (every buffer
/// holds it through an `Arc`).
pub(crate) struct Shared {
    /// Keeps libvulkan loaded for as long as any handle exists.
    _entry: ash::Entry,
    instance: ash::Instance,
    pub(crate) debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The debug messenger's user data points at this mutex; dropped after the instance.
    pub(crate) messages: Arc<Mutex<Vec<String>>>,
    pub(crate) device: ash::Device,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
}

impl Drop for Shared {
    fn drop(&mut self) {
        let _lifecycle = lifecycle();
        unsafe {
            let _ = self.device.device_wait_idle();
            // The allocator frees its memory blocks through the device, so it goes first.
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct SubgroupControl {
    /// subgroupSizeControl was enabled on the device and covers compute shaders.
    pub(crate) enabled: bool,
    pub(crate) full_subgroups: bool,
    pub(crate) min: u32,
    pub(crate) max: u32,
    pub(crate) max_workgroup_subgroups: u32,
}

pub(crate) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Held while this process creates or destroys a Vulkan instance or device, through either
/// backend. NVIDIA's driver (580) deadlocked when devices came and went on several threads
/// at once: `vkDestroyDevice` joined a driver thread whose exit never finished, and threads
/// that had used the driver waited on its lock as they exited. The runtime's dispatch tests
/// with parallel test threads hung in 11 of 17 runs on an H200, and in none of 17 with
/// this lock (BENCHMARKS.md, 2026-11-30).
pub(crate) fn lifecycle() -> std::sync::MutexGuard<'static, ()> {
    static LIFECYCLE: Mutex<()> = Mutex::new(());
    lock(&LIFECYCLE)
}

fn no_adapter(detail: impl Into<String>) -> RuntimeError {
    RuntimeError::NoAdapter {
        backend: BACKEND,
        detail: detail.into(),
    }
}

fn creation(detail: impl Into<String>) -> RuntimeError {
    RuntimeError::DeviceCreation {
        backend: BACKEND,
        detail: detail.into(),
    }
}

fn version_string(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

/// Validation is on in debug builds when the layer is installed. `COHORT_VK_VALIDATION=0`
/// turns it off (it slows software drivers down), `=1` turns it on in release builds.
fn want_validation() -> bool {
    match std::env::var("COHORT_VK_VALIDATION").as_deref() {
        Ok("0") => false,
        Ok("1") => true,
        _ => cfg!(debug_assertions),
    }
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    let text = unsafe { (*data).message_as_c_str() }
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        "error"
    } else {
        "warning"
    };
    let msg = format!("vulkan validation {level}: {text}");
    eprintln!("{msg}");
    let sink = unsafe { &*(user as *const Mutex<Vec<String>>) };
    lock(sink).push(msg);
    vk::FALSE
}

/// What `pick_physical_device` found out about the chosen device.
struct Candidate {
    physical: vk::PhysicalDevice,
    props: vk::PhysicalDeviceProperties,
    api: u32,
    queue_family: u32,
    timestamp_valid_bits: u32,
}

fn device_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Prefers a discrete GPU, or takes the usable device number `which` in the loader's
/// order; needs Vulkan 1.1 (subgroup operations) and a compute queue, preferring a
/// compute family that supports timestamps.
fn pick_physical_device(
    instance: &ash::Instance,
    instance_api: u32,
    which: Option<usize>,
) -> Result<Candidate> {
    let physicals =
        unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    if physicals.is_empty() {
        return Err(no_adapter(
            "the Vulkan loader found no physical device (no driver ICD installed?)",
        ));
    }
    let mut rejected = Vec::new();
    let mut candidates = Vec::new();
    for physical in physicals {
        let props = unsafe { instance.get_physical_device_properties(physical) };
        let name = props
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy())
            .unwrap_or_default();
        let api = props.api_version.min(instance_api);
        if api < vk::API_VERSION_1_1 {
            rejected.push(format!(
                "{name} supports only Vulkan {}",
                version_string(api)
            ));
            continue;
        }
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let compute: Vec<(u32, &vk::QueueFamilyProperties)> = families
            .iter()
            .enumerate()
            .filter(|(_, f)| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .map(|(i, f)| (i as u32, f))
            .collect();
        let Some((queue_family, family)) = compute
            .iter()
            .find(|(_, f)| f.timestamp_valid_bits > 0)
            .or(compute.first())
            .copied()
        else {
            rejected.push(format!("{name} has no compute queue"));
            continue;
        };
        candidates.push(Candidate {
            physical,
            props,
            api,
            queue_family,
            timestamp_valid_bits: family.timestamp_valid_bits,
        });
    }
    if let Some(index) = which {
        if index >= candidates.len() {
            let available = candidates
                .iter()
                .map(|c| {
                    c.props
                        .device_name_as_c_str()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default()
                })
                .collect();
            return Err(RuntimeError::NoSuchDevice {
                backend: BackendKind::Vulkan,
                index,
                available,
            });
        }
        return Ok(candidates.swap_remove(index));
    }
    candidates
        .into_iter()
        .min_by_key(|c| device_rank(c.props.device_type))
        .ok_or_else(|| no_adapter(format!("no usable device: {}", rejected.join("; "))))
}

/// A freshly opened device: the owned handles plus what was found out about them.
pub(crate) struct Opened {
    pub(crate) shared: Shared,
    pub(crate) desc: Description,
}

pub(crate) struct Description {
    pub(crate) queue_family: u32,
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    pub(crate) subgroup_control: SubgroupControl,
    pub(crate) timestamp_valid_bits: u32,
    pub(crate) timestamp_period_ns: f64,
}

/// The Vulkan loader, and the instance version to ask for (1.1 at least: subgroup
/// operations).
fn load() -> Result<(ash::Entry, u32)> {
    let entry = unsafe { ash::Entry::load() }
        .map_err(|e| no_adapter(format!("could not load libvulkan.so.1 ({e})")))?;
    let loader_api = unsafe { entry.try_enumerate_instance_version() }
        .vk("vkEnumerateInstanceVersion")?
        .unwrap_or(vk::API_VERSION_1_0);
    if loader_api < vk::API_VERSION_1_1 {
        return Err(no_adapter(format!(
            "the Vulkan loader supports only Vulkan {} (1.1 is needed for subgroup operations)",
            version_string(loader_api)
        )));
    }
    Ok((entry, loader_api.min(vk::API_VERSION_1_3)))
}

/// Loads Vulkan, creates the instance (with validation where wanted), picks a physical
/// device (the best, or the usable one numbered `which`) and creates the logical device
/// with its allocator.
pub(crate) fn open(which: Option<usize>) -> Result<Opened> {
    match open_with(which, false)? {
        Found::Opened(opened) => Ok(*opened),
        Found::Software(name) => unreachable!("{name}: no device is skipped here"),
    }
}

/// What [`open_unless_software`] found.
pub(crate) enum Found {
    Opened(Box<Opened>),
    /// The best device is Mesa's software driver (named): no device was created.
    Software(String),
}

/// [`open`]`(None)`, except that when the best device is Mesa's software driver, the
/// instance alone tells so and no device is created (`Device::best` then takes the CPU
/// backend, which is faster on the same cores).
pub(crate) fn open_unless_software() -> Result<Found> {
    open_with(None, true)
}

/// Whether candidate `c` is Mesa's software driver: by the driver's id, which Vulkan 1.2
/// reports (the rule `DeviceInfo::software_driver` follows).
fn is_software(instance: &ash::Instance, c: &Candidate) -> bool {
    c.api >= vk::API_VERSION_1_2 && {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        unsafe { instance.get_physical_device_properties2(c.physical, &mut props2) };
        driver.driver_id == vk::DriverId::MESA_LLVMPIPE
    }
}

fn open_with(which: Option<usize>, skip_software: bool) -> Result<Found> {
    let _lifecycle = lifecycle();
    let (entry, instance_api) = load()?;

    let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
    let has_layer = layers
        .iter()
        .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
    let extensions =
        unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
    let has_debug_utils = extensions
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
    let validation = want_validation() && has_layer;
    let debug_utils = validation && has_debug_utils;

    let messages: Arc<Mutex<Vec<String>>> = Arc::new(Mutex::new(Vec::new()));
    let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(&messages) as *mut c_void);

    let app = vk::ApplicationInfo::default()
        .application_name(c"cohort")
        .engine_name(c"cohort-runtime")
        .api_version(instance_api);
    let layer_names = if validation {
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        vec![]
    };
    let ext_names = if debug_utils {
        vec![ash::ext::debug_utils::NAME.as_ptr()]
    } else {
        vec![]
    };
    let mut instance_info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names);
    if debug_utils {
        // Chained so that messages from instance creation itself are caught too.
        instance_info = instance_info.push_next(&mut messenger_info);
    }
    let instance = unsafe { entry.create_instance(&instance_info, None) }.map_err(|e| match e {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => {
            no_adapter("vkCreateInstance found no compatible driver (ERROR_INCOMPATIBLE_DRIVER)")
        }
        e => creation(format!("vkCreateInstance failed: {e}")),
    })?;
    let debug = debug_utils.then(|| {
        let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let info = messenger_info;
        unsafe { loader.create_debug_utils_messenger(&info, None) }
            .ok()
            .map(|m| (loader, m))
    });
    let debug = debug.flatten();

    let destroy = |debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| unsafe {
        if let Some((loader, m)) = debug {
            loader.destroy_debug_utils_messenger(m, None);
        }
        instance.destroy_instance(None);
    };
    // From here on, failures must destroy the instance; `open_device` does the rest.
    let c = match pick_physical_device(&instance, instance_api, which) {
        Ok(c) => c,
        Err(e) => {
            destroy(debug);
            return Err(e);
        }
    };
    let software = is_software(&instance, &c);
    if skip_software && software {
        destroy(debug);
        return Ok(Found::Software(device_name(&c.props)));
    }
    match open_device(&instance, c, software) {
        Ok((device, allocator, desc)) => Ok(Found::Opened(Box::new(Opened {
            shared: Shared {
                _entry: entry,
                instance,
                debug,
                messages,
                device,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
            },
            desc,
        }))),
        Err(e) => {
            destroy(debug);
            Err(e)
        }
    }
}

fn device_name(props: &vk::PhysicalDeviceProperties) -> String {
    props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Creates the logical device of candidate `c` (the software driver where `software`) and
/// queries everything `DeviceInfo` reports.
fn open_device(
    instance: &ash::Instance,
    c: Candidate,
    software: bool,
) -> Result<(ash::Device, Allocator, Description)> {
    let api = c.api;
    let pd = c.physical;

    let dev_exts = unsafe { instance.enumerate_device_extension_properties(pd) }
        .vk("vkEnumerateDeviceExtensionProperties")?;
    let has_ext = |name: &CStr| {
        dev_exts
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(name))
    };
    let is_13 = api >= vk::API_VERSION_1_3;
    let is_12 = api >= vk::API_VERSION_1_2;
    let sgc_ext = !is_13 && has_ext(ash::ext::subgroup_size_control::NAME);
    let atomic_float_ext = has_ext(ash::ext::shader_atomic_float::NAME);

    // Properties.
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut sgc_props = vk::PhysicalDeviceSubgroupSizeControlProperties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut float_controls = vk::PhysicalDeviceFloatControlsProperties::default();
    {
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
        if is_13 || sgc_ext {
            props2 = props2.push_next(&mut sgc_props);
        }
        if is_12 {
            props2 = props2.push_next(&mut driver);
            props2 = props2.push_next(&mut float_controls);
        }
        unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    }

    // Features: enable everything the device supports. Kernels are arbitrary SPIR-V
    // (int64, float16, atomics, ...) and an unused enabled feature costs nothing here.
    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut sgc = vk::PhysicalDeviceSubgroupSizeControlFeatures::default();
    let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let core = {
        let mut f2 = vk::PhysicalDeviceFeatures2::default();
        if is_12 {
            f2 = f2.push_next(&mut v11).push_next(&mut v12);
        }
        if is_13 {
            f2 = f2.push_next(&mut v13);
        } else if sgc_ext {
            f2 = f2.push_next(&mut sgc);
        }
        if atomic_float_ext {
            f2 = f2.push_next(&mut atomic_float);
        }
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        f2.features
    };
    let (size_control, full_subgroups) = if is_13 {
        (v13.subgroup_size_control, v13.compute_full_subgroups)
    } else {
        (sgc.subgroup_size_control, sgc.compute_full_subgroups)
    };

    let mut ext_names: Vec<*const std::ffi::c_char> = Vec::new();
    if sgc_ext {
        ext_names.push(ash::ext::subgroup_size_control::NAME.as_ptr());
    }
    if atomic_float_ext {
        ext_names.push(ash::ext::shader_atomic_float::NAME.as_ptr());
    }
    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(c.queue_family)
        .queue_priorities(&priorities)];
    // The queried structs still carry the query's p_next pointers; clear them before
    // building the creation chain.
    v11.p_next = std::ptr::null_mut();
    v12.p_next = std::ptr::null_mut();
    v13.p_next = std::ptr::null_mut();
    sgc.p_next = std::ptr::null_mut();
    atomic_float.p_next = std::ptr::null_mut();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().features(core);
    if is_12 {
        f2 = f2.push_next(&mut v11).push_next(&mut v12);
    }
    if is_13 {
        f2 = f2.push_next(&mut v13);
    } else if sgc_ext {
        f2 = f2.push_next(&mut sgc);
    }
    if atomic_float_ext {
        f2 = f2.push_next(&mut atomic_float);
    }
    let device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&ext_names)
        .push_next(&mut f2);
    let device = unsafe { instance.create_device(pd, &device_info, None) }
        .map_err(|e| creation(format!("vkCreateDevice failed: {e}")))?;

    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: pd,
        debug_settings: AllocatorDebugSettings::default(),
        buffer_device_address: false,
        // Smaller blocks than the 256 MiB default: tests open many devices at once.
        allocation_sizes: AllocationSizes::new(64 << 20, 16 << 20),
    })
    .map_err(|e| {
        unsafe { device.destroy_device(None) };
        creation(format!("gpu-allocator: {e}"))
    })?;

    let p = &c.props;
    let l = &p.limits;
    let name = device_name(p);
    let driver_text = if is_12 {
        let dn = driver
            .driver_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned());
        let di = driver
            .driver_info_as_c_str()
            .map(|s| s.to_string_lossy().into_owned());
        format!("{} {}", dn.unwrap_or_default(), di.unwrap_or_default())
            .trim()
            .to_string()
    } else {
        format!("driver version {:#x}", p.driver_version)
    };
    let sgc_stages_ok = sgc_props
        .required_subgroup_size_stages
        .contains(vk::ShaderStageFlags::COMPUTE);
    let has_sgc_props = is_13 || sgc_ext;
    let (sg_min, sg_max) = if has_sgc_props && sgc_props.min_subgroup_size > 0 {
        (sgc_props.min_subgroup_size, sgc_props.max_subgroup_size)
    } else {
        (subgroup.subgroup_size, subgroup.subgroup_size)
    };
    let subgroup_control = SubgroupControl {
        enabled: size_control == vk::TRUE && sgc_stages_ok,
        full_subgroups: full_subgroups == vk::TRUE,
        min: sg_min,
        max: sg_max,
        max_workgroup_subgroups: sgc_props.max_compute_workgroup_subgroups,
    };
    let subgroup_ops_ok = subgroup
        .supported_stages
        .contains(vk::ShaderStageFlags::COMPUTE);
    let timestamps = c.timestamp_valid_bits > 0 && l.timestamp_period > 0.0;
    let info = DeviceInfo {
        backend: BACKEND,
        adapter_name: name,
        driver: driver_text,
        software_driver: software,
        subgroup_size_min: sg_min,
        subgroup_size_max: sg_max,
        subgroup_size: subgroup.subgroup_size,
        supports_required_subgroup_size: subgroup_control.enabled,
        timestamps,
        max_workgroups_per_dim: l
            .max_compute_work_group_count
            .iter()
            .copied()
            .min()
            .unwrap_or(0),
        max_storage_buffer_binding_size: l.max_storage_buffer_range as u64,
        // Float controls are core in Vulkan 1.2 (SPIR-V 1.3 modules name the extension).
        // The software driver keeps IEEE behaviour unasked (the conformance suite is exact
        // there); asking would only change its optimisations and make its Vulkan images
        // differ from its wgpu ones in the last bits.
        f32_subnormals: is_12
            && !software
            && float_controls.shader_denorm_preserve_float32 == vk::TRUE,
        f32_nan_inf: is_12
            && !software
            && float_controls.shader_signed_zero_inf_nan_preserve_float32 == vk::TRUE,
        uniforms_as_storage: crate::device::uniforms_as_storage(software),
    };
    let limits = Limits {
        max_workgroups: l.max_compute_work_group_count,
        max_workgroup_size: l.max_compute_work_group_size,
        max_invocations: l.max_compute_work_group_invocations,
        max_storage_binding: l.max_storage_buffer_range as u64,
        max_workgroup_memory: l.max_compute_shared_memory_size as u64,
        max_uniform_binding: l.max_uniform_buffer_range as u64,
        subgroups: subgroup_ops_ok,
    };

    let desc = Description {
        queue_family: c.queue_family,
        info,
        limits,
        subgroup_control,
        timestamp_valid_bits: c.timestamp_valid_bits,
        timestamp_period_ns: l.timestamp_period as f64,
    };
    Ok((device, allocator, desc))
}
