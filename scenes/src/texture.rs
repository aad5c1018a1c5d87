//! Textures (Mitsuba `checkerboard` and `bitmap`) as the kernels read them.
//!
//! A texture maps surface coordinates (u, v) to a linear RGB colour. The kernels read every
//! texture of a scene from one array of `[f32; 4]`, [`gpu_textures`]: each texture starts
//! with a header of [`HEADER_LEN`] entries (kind, size, `to_uv`, colours), a bitmap's texels
//! follow it row by row from the top. `cohort_kernels::texture::texture_eval` reads it;
//! [`Texture::eval`] is the same lookup on the host.

use glam::{Vec2, Vec3};

/// Entries of a texture's header in [`gpu_textures`].
pub const HEADER_LEN: usize = 5;
/// Header kinds.
pub const CHECKERBOARD: u32 = 0;
pub const BITMAP: u32 = 1;
/// Mitsuba `mesh_attribute`: header entry 0 holds (kind, start of the attribute's values at
/// the triangle corners in the array, 0, 0) and entry 3 (scale, 0, 0, 0).
pub const MESH_ATTRIBUTE: u32 = 2;
/// Header flags: the bitmap's filter and wrap mode.
pub const FILTER_NEAREST: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;
pub const WRAP_CLAMP: u32 = 4;

/// Mitsuba's `to_uv`: `uv' = x * u + y * v + offset`, the 2D affine part of its 4x4 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub x: Vec2,
    pub y: Vec2,
    pub offset: Vec2,
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform {
        x: Vec2::X,
        y: Vec2::Y,
        offset: Vec2::ZERO,
    };

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.x * uv.x + self.y * uv.y + self.offset
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    /// Mitsuba's default.
    Bilinear,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Mitsuba's default.
    Repeat,
    Mirror,
    Clamp,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// Mitsuba `checkerboard`: `color0` where the fractional parts of u and v are on the same
    /// side of 1/2, else `color1`.
    Checkerboard {
        color0: Vec3,
        color1: Vec3,
        to_uv: UvTransform,
    },
    /// Mitsuba `bitmap`: linear RGB texels, row 0 at v = 0.
    Bitmap {
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        filter: Filter,
        wrap: Wrap,
        to_uv: UvTransform,
    },
    /// Mitsuba `mesh_attribute`: the hit triangle's values of the mesh attribute `name`
    /// ([`crate::Triangles::attributes`]: `vertex_*` interpolated at the hit, `face_*`
    /// constant), times `scale`. It varies with the surface point, not with (u, v):
    /// [`Texture::eval`] and [`Texture::mean`] give grey 0.5 x `scale` for it.
    MeshAttribute { name: String, scale: f32 },
}

impl Texture {
    /// The colour at surface coordinates `uv`, as the kernels compute it.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::MeshAttribute { scale, .. } => Vec3::splat(0.5 * scale),
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.apply(uv);
                let fu = p.x - p.x.floor() > 0.5;
                let fv = p.y - p.y.floor() > 0.5;
                if fu == fv {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::Bitmap {
                width,
                height,
                texels,
                filter,
                wrap,
                to_uv,
            } => {
                let p = to_uv.apply(uv);
                let (w, h) = (*width as i64, *height as i64);
                let texel = |x: i64, y: i64| {
                    texels[(wrap_index(y, h, *wrap) * w + wrap_index(x, w, *wrap)) as usize]
                };
                match filter {
                    Filter::Nearest => texel(
                        (p.x * w as f32).floor() as i64,
                        (p.y * h as f32).floor() as i64,
                    ),
                    Filter::Bilinear => {
                        let x = p.x * w as f32 - 0.5;
                        let y = p.y * h as f32 - 0.5;
                        let (x0, y0) = (x.floor(), y.floor());
                        let (fx, fy) = (x - x0, y - y0);
                        let (x0, y0) = (x0 as i64, y0 as i64);
                        (texel(x0, y0) * (1.0 - fx) + texel(x0 + 1, y0) * fx) * (1.0 - fy)
                            + (texel(x0, y0 + 1) * (1.0 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy
                    }
                }
            }
        }
    }

    /// The mean colour (what a renderer without texture coordinates would use).
    pub fn mean(&self) -> Vec3 {
        match self {
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (*color0 + *color1),
            Texture::Bitmap { texels, .. } => {
                texels.iter().copied().sum::<Vec3>() / texels.len().max(1) as f32
            }
            Texture::MeshAttribute { scale, .. } => Vec3::splat(0.5 * scale),
        }
    }

    fn to_uv(&self) -> UvTransform {
        match self {
            Texture::Checkerboard { to_uv, .. } | Texture::Bitmap { to_uv, .. } => *to_uv,
            Texture::MeshAttribute { .. } => UvTransform::IDENTITY,
        }
    }
}

/// Texel index `i` of a row or column of `n` texels under `wrap`.
fn wrap_index(i: i64, n: i64, wrap: Wrap) -> i64 {
    match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let p = i.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    }
}

/// Luminance of a linear sRGB colour, Mitsuba's coefficients (a texture read as a number,
/// `eval_1`; `cohort_kernels::texture::luminance` on the device).
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.212_671, 0.715_160, 0.072_169))
}

/// Where each texture's header starts in [`gpu_textures`].
pub fn gpu_texture_starts(textures: &[Texture]) -> Vec<u32> {
    let mut at = 0u32;
    textures
        .iter()
        .map(|t| {
            let start = at;
            at += gpu_len(t);
            start
        })
        .collect()
}

/// Entries of [`gpu_textures`]' array.
pub fn gpu_textures_len(textures: &[Texture]) -> u32 {
    textures.iter().map(gpu_len).sum()
}

/// Entries texture `t` takes in [`gpu_textures`]' array.
fn gpu_len(t: &Texture) -> u32 {
    HEADER_LEN as u32
        + match t {
            Texture::Bitmap { texels, .. } => texels.len() as u32,
            Texture::Checkerboard { .. } | Texture::MeshAttribute { .. } => 0,
        }
}

/// Every texture of a scene in the kernels' layout, and where each one's header starts. The
/// mesh attributes that textures read ([`attributes_read`]) follow, in that order, each
/// with a value per triangle corner (`3 * triangles` entries): their headers point there.
pub fn gpu_textures(textures: &[Texture], triangles: usize) -> (Vec<[f32; 4]>, Vec<u32>) {
    let mut data = Vec::new();
    let mut starts = Vec::new();
    for t in textures {
        starts.push(data.len() as u32);
        let uv = t.to_uv();
        let (kind, w, h, flags, c0, c1) = match t {
            Texture::Checkerboard { color0, color1, .. } => {
                (CHECKERBOARD, 0, 0, 0, *color0, *color1)
            }
            Texture::Bitmap {
                width,
                height,
                filter,
                wrap,
                ..
            } => {
                let mut flags = 0;
                if *filter == Filter::Nearest {
                    flags |= FILTER_NEAREST;
                }
                flags |= match wrap {
                    Wrap::Repeat => 0,
                    Wrap::Mirror => WRAP_MIRROR,
                    Wrap::Clamp => WRAP_CLAMP,
                };
                (BITMAP, *width, *height, flags, Vec3::ZERO, Vec3::ZERO)
            }
            // The values follow every texture: their start is filled in below.
            Texture::MeshAttribute { scale, .. } => (
                MESH_ATTRIBUTE,
                0,
                0,
                0,
                Vec3::new(*scale, 0.0, 0.0),
                Vec3::ZERO,
            ),
        };
        let bits = |v: u32| f32::from_bits(v);
        data.push([bits(kind), bits(w), bits(h), bits(flags)]);
        data.push([uv.x.x, uv.x.y, uv.y.x, uv.y.y]);
        data.push([uv.offset.x, uv.offset.y, 0.0, 0.0]);
        data.push(c0.extend(0.0).to_array());
        data.push(c1.extend(0.0).to_array());
        if let Texture::Bitmap { texels, .. } = t {
            data.extend(texels.iter().map(|c| c.extend(0.0).to_array()));
        }
    }
    let total = data.len() as u32;
    let read = attributes_read(textures);
    for (t, &start) in textures.iter().zip(&starts) {
        if let Texture::MeshAttribute { name, .. } = t {
            let block = read.iter().position(|n| n == name).unwrap() as u32;
            data[start as usize][1] = f32::from_bits(total + block * 3 * triangles as u32);
        }
    }
    (data, starts)
}

/// The names of the mesh attributes that `textures` read, each once, in first-use order
/// (their values follow the textures in the kernels' array: `Scene::gpu_textures`).
pub fn attributes_read(textures: &[Texture]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for t in textures {
        if let Texture::MeshAttribute { name, .. } = t {
            if !names.contains(name) {
                names.push(name.clone());
            }
        }
    }
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_is_mitsubas() {
        let t = Texture::Checkerboard {
            color0: Vec3::ONE,
            color1: Vec3::ZERO,
            to_uv: UvTransform::IDENTITY,
        };
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(-0.25, 0.25)), Vec3::ZERO);
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres_and_wraps() {
        let texels = vec![Vec3::ZERO, Vec3::ONE];
        let t = |wrap| Texture::Bitmap {
            width: 2,
            height: 1,
            texels: texels.clone(),
            filter: Filter::Bilinear,
            wrap,
            to_uv: UvTransform::IDENTITY,
        };
        // Texel centres at u = 0.25 and 0.75; between them, halfway.
        assert_eq!(t(Wrap::Repeat).eval(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t(Wrap::Repeat).eval(Vec2::new(0.5, 0.5)), Vec3::splat(0.5));
        // At u = 0 repeat blends the last and first texels, clamp holds the first.
        assert_eq!(t(Wrap::Repeat).eval(Vec2::new(0.0, 0.5)), Vec3::splat(0.5));
        assert_eq!(t(Wrap::Clamp).eval(Vec2::new(0.0, 0.5)), Vec3::ZERO);
        assert_eq!(t(Wrap::Mirror).eval(Vec2::new(0.0, 0.5)), Vec3::ZERO);
    }
}
