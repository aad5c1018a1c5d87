//! The `display` kernel on every backend against the PNG writer's tone mapping (the
//! host's run of `srgb8`, which the writer calls), over
//! edge values (NaN, infinities, -0, negatives, values past 1, unfinished pixels) and the
//! column window two side-by-side renderers use.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::display::{display, DisplayParams};
use glam::Vec4;

/// The sRGB encoding on the host (the PNG writer, `cohort_render::output`, calls it too).
fn srgb(linear: f32) -> u32 {
    cohort_kernels::display::srgb8(linear)
}

fn expected(a: Vec4, scale: f32) -> u32 {
    let rgb = if a.w >= 1.0 {
        a.truncate() / a.w
    } else {
        glam::Vec3::ZERO
    };
    (srgb(rgb.x * scale) << 16) | (srgb(rgb.y * scale) << 8) | srgb(rgb.z * scale)
}

fn check(kind: BackendKind) {
    let Some(d) = Device::for_tests(kind) else {
        return;
    };
    let values = [
        0.0,
        -0.0,
        1e-4,
        0.0031308,
        0.2,
        0.5,
        1.0,
        3.0,
        -2.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MIN_POSITIVE,
        f32::MAX,
    ];
    let (width, height) = (8u32, 7u32);
    let n = (width * height) as usize;
    let accum: Vec<Vec4> = (0..n)
        .map(|i| {
            let v = |k: usize| values[(i * 3 + k) % values.len()];
            // Path counts 0 (black), 1, 2, 4 and 16.
            let w = [0.0, 1.0, 2.0, 4.0, 16.0][i % 5];
            Vec4::new(v(0) * w, v(1) * w, v(2) * w, w)
        })
        .collect();
    // Slots in reverse pixel order, so a kernel that ignores `slot_pixel` is caught.
    let slot_pixel: Vec<u32> = (0..n as u32).rev().collect();
    for (scale, columns) in [(1.0f32, 0..width), (0.25, 0..3), (4.0, 3..width)] {
        let params = DisplayParams {
            slots: n as u32,
            copies: 1,
            width,
            x_begin: columns.start,
            x_end: columns.end,
            scale,
        };
        let out = d.upload(&vec![0xdead_beefu32; n]).unwrap();
        display::launch(
            &d,
            n as u32,
            &params,
            &d.upload(&slot_pixel).unwrap(),
            &d.upload(&accum).unwrap(),
            &out,
        )
        .unwrap();
        let got = d.read(&out).unwrap();
        for (slot, a) in accum.iter().enumerate() {
            let pixel = slot_pixel[slot] as usize;
            let x = pixel as u32 % width;
            let want = if columns.contains(&x) {
                expected(*a, scale)
            } else {
                0xdead_beef
            };
            let g = got[pixel];
            // One 8-bit step per channel where the device's powf or division rounds
            // differently from the host's; exact outside the window.
            let close = (0..3).all(|c| {
                let (gc, wc) = ((g >> (8 * c)) & 255, (want >> (8 * c)) & 255);
                gc.abs_diff(wc) <= 1
            }) && g >> 24 == want >> 24;
            assert!(
                close,
                "{}: slot {slot} (pixel {pixel}) accum {a} scale {scale}: got {g:08x}, want {want:08x}",
                d.info().adapter_name
            );
        }
    }
}

/// The encoding itself, at values whose 8-bit codes are known.
#[test]
fn srgb8_encodes_known_values() {
    assert_eq!(srgb(0.0), 0);
    assert_eq!(srgb(-1.0), 0);
    assert_eq!(srgb(f32::NAN), 0);
    assert_eq!(srgb(1.0), 255);
    assert_eq!(srgb(f32::INFINITY), 255);
    // Linear 0.5 is sRGB 0.7354: code 188; 0.0031308 is the knee, 12.92 x it = 0.04045.
    assert_eq!(srgb(0.5), 188);
    assert_eq!(srgb(0.0031308), 10);
    assert_eq!(srgb(0.216), 128);
}

#[test]
fn display_tone_maps_as_the_png_writer_on_the_cpu_backend() {
    check(BackendKind::Cpu);
}

#[test]
fn display_tone_maps_as_the_png_writer_on_vulkan() {
    check(BackendKind::Vulkan);
}

#[test]
fn display_tone_maps_as_the_png_writer_on_wgpu() {
    check(BackendKind::Wgpu);
}
