//! The paper's fourth kernel (§3): `display` turns the accumulation buffer into
//! the image a window presents, every iteration, on the device that rendered it.
//!
//! Tone mapping is `cohort render`'s PNG (`cohort_render::output::write_png`): exposure
//! `2^stops`, clamp to [0, 1], the sRGB curve, rounding to 8 bits. A pixel the viewer
//! shows is therefore the pixel the PNG of the same paths holds (to one step of 8 bits,
//! where the device's `powf` and division round differently from the host's).

use cohort::prelude::*;

/// What `display` reads besides the buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct DisplayParams {
    /// Pixels: the ray slots of one copy (`Frame::copies`) of the accumulation buffer.
    pub slots: u32,
    /// Slots per pixel: copy `k` of slot `g` is slot `g + k * slots`.
    pub copies: u32,
    /// Image width in pixels.
    pub width: u32,
    /// Only pixels with `x_begin <= x < x_end` are written: two renderers share one
    /// image side by side, each writing its own columns.
    pub x_begin: u32,
    pub x_end: u32,
    /// Linear scale before the clamp: `2^exposure`.
    pub scale: f32,
}

/// sRGB encoding of a linear value in 8 bits, as the PNG writer encodes it (NaN and
/// negative values give 0, values above 1 give 255).
#[kernel_fn]
pub fn srgb8(linear: f32) -> u32 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u32
}

/// One invocation per pixel (per slot of the first copy): the mean of the completed paths
/// of the pixel's slots (`accum.w` of them, summed over its copies in copy order; black
/// before the first), tone-mapped and packed as `0x00RRGGBB` at the slot's
/// pixel of `out` (row-major, `width` wide): the layout X11 and most windowing systems
/// present directly.
#[kernel(workgroup = 256)]
pub fn display(
    #[builtin(global_index)] gi: u32,
    p: &DisplayParams,
    slot_pixel: &[u32],
    accum: &[Vec4],
    out: &mut [u32],
) {
    if gi >= p.slots {
        return;
    }
    let pixel = slot_pixel[gi as usize];
    let x = pixel % p.width;
    if x < p.x_begin || x >= p.x_end {
        return;
    }
    let mut a = Vec4::ZERO;
    let mut k = 0u32;
    while k < p.copies {
        a += accum[(gi + k * p.slots) as usize];
        k += 1;
    }
    let mut rgb = Vec3::ZERO;
    if a.w >= 1.0 {
        rgb = a.truncate() / a.w;
    }
    let r = srgb8(rgb.x * p.scale);
    let g = srgb8(rgb.y * p.scale);
    let b = srgb8(rgb.z * p.scale);
    out[pixel as usize] = (r << 16) | (g << 8) | b;
}
