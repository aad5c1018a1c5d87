//! Texture lookup: Mitsuba's `checkerboard` and `bitmap` at a surface point's texture
//! coordinates, from the array `cohort_scenes::texture::gpu_textures` lays out (a header of
//! five entries, then a bitmap's texels row by row from the top).

use cohort::prelude::*;

/// Header flags (`cohort_scenes::texture`).
pub const TEXTURE_BITMAP: u32 = 1;
/// Mitsuba `mesh_attribute` (`texture_at_hit`).
pub const TEXTURE_MESH_ATTRIBUTE: u32 = 2;
pub const FILTER_NEAREST: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;
pub const WRAP_CLAMP: u32 = 4;
/// Entries of a texture's header.
pub const TEXTURE_HEADER: u32 = 5;

/// The texture coordinates of hit `h` (barycentric weights of v1 and v2 in `h.y`, `h.z`) on
/// triangle `original`, whose three corners' coordinates are in `tex_coords[2 original]` (u0,
/// v0, u1, v1) and `tex_coords[2 original + 1]` (u2, v2).
#[kernel_fn]
pub fn hit_uv(tex_coords: &[Vec4], original: u32, h: Vec4) -> Vec2 {
    let k = original as usize * 2;
    let a = tex_coords[k];
    let b = tex_coords[k + 1];
    let w0 = 1.0 - h.y - h.z;
    Vec2::new(
        a.x * w0 + a.z * h.y + b.x * h.z,
        a.y * w0 + a.w * h.y + b.y * h.z,
    )
}

/// Texel index `i` of a row or column of `n` texels under the wrap mode in `flags`.
#[kernel_fn]
pub fn wrap_texel(i: i32, n: i32, flags: u32) -> i32 {
    let mut r = ((i % n) + n) % n;
    if flags & WRAP_CLAMP != 0 {
        r = i.max(0).min(n - 1);
    } else if flags & WRAP_MIRROR != 0 {
        let m = 2 * n;
        let p = ((i % m) + m) % m;
        r = p;
        if p >= n {
            r = m - 1 - p;
        }
    }
    r
}

/// Texel (x, y) of the bitmap of `w` x `h` texels starting at `base`, wrapped by `flags`.
#[kernel_fn]
pub fn texel(textures: &[Vec4], base: u32, w: i32, h: i32, x: i32, y: i32, flags: u32) -> Vec3 {
    let i = wrap_texel(y, h, flags) * w + wrap_texel(x, w, flags);
    textures[(base + i as u32) as usize].truncate()
}

/// The point of the texture's own domain (in [0, 1)^2 per repetition) for texture
/// coordinates `uv`: its `to_uv` applied.
#[kernel_fn]
pub fn texture_point(textures: &[Vec4], header: u32, uv: Vec2) -> Vec2 {
    let m = textures[(header + 1) as usize];
    let o = textures[(header + 2) as usize];
    Vec2::new(m.x * uv.x + m.z * uv.y + o.x, m.y * uv.x + m.w * uv.y + o.y)
}

/// The bilinear lookup's cell at point `p` of a `w` x `h` bitmap: the texel (x, y) whose
/// centre is at or before `p` in each axis (as f32) and the fractions towards the next
/// (z, w).
#[kernel_fn]
pub fn bilinear_cell(p: Vec2, w: i32, h: i32) -> Vec4 {
    let x = p.x * w as f32 - 0.5;
    let y = p.y * h as f32 - 0.5;
    let x0 = x.floor();
    let y0 = y.floor();
    Vec4::new(x0, y0, x - x0, y - y0)
}

/// The colour of the texture whose header starts at `header` at texture coordinates `uv`,
/// as `cohort_scenes::Texture::eval` (and Mitsuba) compute it.
#[kernel_fn]
pub fn texture_eval(textures: &[Vec4], header: u32, uv: Vec2) -> Vec3 {
    let h0 = textures[header as usize];
    let p = texture_point(textures, header, uv);
    let flags = h0.w.to_bits();
    let mut c = textures[(header + 4) as usize].truncate();
    if h0.x.to_bits() == TEXTURE_BITMAP {
        let w = h0.y.to_bits() as i32;
        let h = h0.z.to_bits() as i32;
        let base = header + TEXTURE_HEADER;
        if flags & FILTER_NEAREST != 0 {
            let x = (p.x * w as f32).floor() as i32;
            let y = (p.y * h as f32).floor() as i32;
            c = texel(textures, base, w, h, x, y, flags);
        } else {
            let cell = bilinear_cell(p, w, h);
            let xi = cell.x as i32;
            let yi = cell.y as i32;
            let fx = cell.z;
            let fy = cell.w;
            let top = texel(textures, base, w, h, xi, yi, flags) * (1.0 - fx)
                + texel(textures, base, w, h, xi + 1, yi, flags) * fx;
            let bottom = texel(textures, base, w, h, xi, yi + 1, flags) * (1.0 - fx)
                + texel(textures, base, w, h, xi + 1, yi + 1, flags) * fx;
            c = top * (1.0 - fy) + bottom * fy;
        }
    } else {
        // Checkerboard: colour0 where the fractional parts of u and v lie on the same side of
        // one half, else colour1 (already in `c`).
        let fu = p.x - p.x.floor() > 0.5;
        let fv = p.y - p.y.floor() > 0.5;
        if fu == fv {
            c = textures[(header + 3) as usize].truncate();
        }
    }
    c
}

/// Luminance of a linear sRGB colour (Mitsuba's `luminance`: a texture's `eval_1`).
#[kernel_fn]
pub fn luminance(c: Vec3) -> f32 {
    c.x * 0.212_671 + c.y * 0.715_160 + c.z * 0.072_169
}

/// Gradient in (u, v) of the luminance of the texture whose header starts at `header`, at
/// texture coordinates `uv`: Mitsuba's `eval_1_grad` of a bilinear `bitmap` (the partials of
/// the bilinear interpolation across the texel cell, through `to_uv` and times the
/// resolution exactly as Mitsuba multiplies them); zero for a nearest-filtered bitmap and
/// for a checkerboard.
#[kernel_fn]
pub fn texture_gradient(textures: &[Vec4], header: u32, uv: Vec2) -> Vec2 {
    let h0 = textures[header as usize];
    let m = textures[(header + 1) as usize];
    let p = texture_point(textures, header, uv);
    let flags = h0.w.to_bits();
    let mut g = Vec2::ZERO;
    if h0.x.to_bits() == TEXTURE_BITMAP && flags & FILTER_NEAREST == 0 {
        let w = h0.y.to_bits() as i32;
        let h = h0.z.to_bits() as i32;
        let base = header + TEXTURE_HEADER;
        let cell = bilinear_cell(p, w, h);
        let xi = cell.x as i32;
        let yi = cell.y as i32;
        let fx = cell.z;
        let fy = cell.w;
        let f00 = luminance(texel(textures, base, w, h, xi, yi, flags));
        let f10 = luminance(texel(textures, base, w, h, xi + 1, yi, flags));
        let f01 = luminance(texel(textures, base, w, h, xi, yi + 1, flags));
        let f11 = luminance(texel(textures, base, w, h, xi + 1, yi + 1, flags));
        let dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        g = Vec2::new(
            w as f32 * (m.x * dx + m.y * dy),
            h as f32 * (m.z * dx + m.w * dy),
        );
    }
    g
}

/// A texture read at a surface point: hit `h` (barycentric weights of v1 and v2 in `h.y`,
/// `h.z`) of triangle `original`, whose texture coordinates are `uv`. For Mitsuba's
/// `mesh_attribute`, the attribute's values at the triangle's corners interpolated, times
/// the texture's scale (the values, 3 per triangle, start where header entry 0's y says; a
/// per-face attribute has one value three times); else `texture_eval`.
#[kernel_fn]
pub fn texture_at_hit(textures: &[Vec4], header: u32, uv: Vec2, original: u32, h: Vec4) -> Vec3 {
    let h0 = textures[header as usize];
    if h0.x.to_bits() == TEXTURE_MESH_ATTRIBUTE {
        let k = h0.y.to_bits() + 3 * original;
        let scale = textures[(header + 3) as usize].x;
        (textures[k as usize].truncate() * (1.0 - h.y - h.z)
            + textures[(k + 1) as usize].truncate() * h.y
            + textures[(k + 2) as usize].truncate() * h.z)
            * scale
    } else {
        texture_eval(textures, header, uv)
    }
}
