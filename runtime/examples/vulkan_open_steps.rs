//! Milliseconds of each step of opening a Vulkan device, in this (fresh) process: loading
//! the loader, listing the instance layers and extensions (skipped with `--skip-enum`),
//! creating the instance, picking the first physical device, and creating the device with
//! every supported core feature enabled, as the Vulkan backend does (with none:
//! `--no-features`). It tells which part of `cohort render`'s "device" time is the
//! driver's own (BENCHMARKS.md, "startup: what the driver takes").
//!
//! `cargo run --release -p cohort-runtime --example vulkan_open_steps [-- --skip-enum]`

use ash::vk;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let skip_enum = args.iter().any(|a| a == "--skip-enum");
    let no_features = args.iter().any(|a| a == "--no-features");
    let start = Instant::now();
    let mut last = start;
    let mut line = String::new();
    let mut lap = |name: &str| {
        let now = Instant::now();
        line += &format!("{name} {:.1} ", (now - last).as_secs_f64() * 1e3);
        last = now;
    };
    let entry = unsafe { ash::Entry::load() }.expect("could not load libvulkan.so.1");
    lap("load");
    unsafe { entry.try_enumerate_instance_version() }.expect("vkEnumerateInstanceVersion");
    lap("version");
    if !skip_enum {
        unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
        lap("layers");
        unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
        lap("exts");
    }
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    let instance = unsafe { entry.create_instance(&info, None) }.expect("vkCreateInstance");
    lap("instance");
    let physical = unsafe { instance.enumerate_physical_devices() }.expect("no device");
    lap("physical");
    let pd = *physical.first().expect("no physical device");
    let props = unsafe { instance.get_physical_device_properties(pd) };
    unsafe { instance.enumerate_device_extension_properties(pd) }.expect("device extensions");
    let name = props.device_name_as_c_str().unwrap_or_default();
    lap("props");
    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let core = {
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut v11)
            .push_next(&mut v12)
            .push_next(&mut v13);
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        f2.features
    };
    // The query left its chain in the structs; the creation chain is built anew.
    v11.p_next = std::ptr::null_mut();
    v12.p_next = std::ptr::null_mut();
    v13.p_next = std::ptr::null_mut();
    lap("features");
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(0)
        .queue_priorities(&priorities)];
    let mut f2 = vk::PhysicalDeviceFeatures2::default()
        .features(core)
        .push_next(&mut v11)
        .push_next(&mut v12)
        .push_next(&mut v13);
    let mut create = vk::DeviceCreateInfo::default().queue_create_infos(&queues);
    if !no_features {
        create = create.push_next(&mut f2);
    }
    let device = unsafe { instance.create_device(pd, &create, None) }.expect("vkCreateDevice");
    lap("device");
    println!(
        "{line}total {:.1} ({})",
        start.elapsed().as_secs_f64() * 1e3,
        name.to_string_lossy()
    );
    unsafe {
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
}
