//! Windows BMP images for bitmap textures: uncompressed 1-, 4-, 8-bit (palette), 16-, 24- and
//! 32-bit pixels (with or without bit-field masks), bottom-up or top-down rows. Run-length
//! compressed files are refused with a message. Values are 8-bit, sRGB-encoded unless the
//! texture is `raw`, as Mitsuba reads them.

use crate::image_file::{texels_from_samples, Image};

fn u16_at(b: &[u8], at: usize) -> Result<u16, String> {
    b.get(at..at + 2)
        .map(|s| u16::from_le_bytes([s[0], s[1]]))
        .ok_or_else(truncated)
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(truncated)
}

fn truncated() -> String {
    "cannot read it as BMP: the file is truncated".into()
}

/// One colour channel described by a bit mask: its value scaled to [0, 1].
fn masked(pixel: u32, mask: u32) -> f32 {
    if mask == 0 {
        return 0.0;
    }
    let max = mask >> mask.trailing_zeros();
    ((pixel & mask) >> mask.trailing_zeros()) as f32 / max as f32
}

pub fn read_bmp(b: &[u8], raw: bool) -> Result<Image, String> {
    if b.get(0..2) != Some(b"BM") {
        return Err("cannot read it as BMP: no 'BM' signature".into());
    }
    let data_at = u32_at(b, 10)? as usize;
    let header = u32_at(b, 14)? as usize;
    let (width, height, bpp, compression, palette_len) = if header == 12 {
        // OS/2 core header: 16-bit sizes, 3-byte palette entries.
        let w = u16_at(b, 18)? as i64;
        let h = u16_at(b, 20)? as i16 as i64;
        (w, h, u16_at(b, 24)?, 0, 0)
    } else if header >= 40 {
        let w = u32_at(b, 18)? as i32 as i64;
        let h = u32_at(b, 22)? as i32 as i64;
        (w, h, u16_at(b, 28)?, u32_at(b, 30)?, u32_at(b, 46)?)
    } else {
        return Err(format!(
            "cannot read it as BMP: unknown header size {header}"
        ));
    };
    if width <= 0 || height == 0 || width > 1 << 16 || height.abs() > 1 << 16 {
        return Err(format!(
            "cannot read it as BMP: bad size {width} x {height}"
        ));
    }
    let (w, h) = (width as usize, height.unsigned_abs() as usize);
    let top_down = height < 0;
    // Channel masks: given (BI_BITFIELDS, 3; or in a V4/V5 header), else the defaults.
    let (rm, gm, bm) = match (compression, bpp) {
        (3 | 6, _) => (u32_at(b, 54)?, u32_at(b, 58)?, u32_at(b, 62)?),
        (0, 16) => (0x7c00, 0x03e0, 0x001f),
        (0, _) => (0x00ff_0000, 0x0000_ff00, 0x0000_00ff),
        (c, _) => {
            return Err(format!(
                "BMP compression {c} (run-length or embedded JPEG/PNG) is not supported; \
                 save the image uncompressed"
            ))
        }
    };
    let palette: Vec<[u8; 3]> = if bpp <= 8 {
        let entry = if header == 12 { 3 } else { 4 };
        let count = if palette_len == 0 {
            1usize << bpp
        } else {
            palette_len as usize
        };
        (0..count)
            .map(|i| {
                let at = 14 + header + i * entry;
                b.get(at..at + 3)
                    .map(|s| [s[2], s[1], s[0]])
                    .ok_or_else(truncated)
            })
            .collect::<Result<_, _>>()?
    } else {
        Vec::new()
    };
    if !matches!(bpp, 1 | 4 | 8 | 16 | 24 | 32) {
        return Err(format!("BMP with {bpp} bits per pixel is not supported"));
    }
    let row_bytes = (w * bpp as usize).div_ceil(32) * 4;
    let mut rgb = vec![0f32; w * h * 3];
    for y in 0..h {
        let src_row = if top_down { y } else { h - 1 - y };
        let row_at = data_at + src_row * row_bytes;
        let row = b.get(row_at..row_at + row_bytes).ok_or_else(truncated)?;
        for x in 0..w {
            let c = match bpp {
                1 | 4 | 8 => {
                    let bit = x * bpp as usize;
                    let byte = row[bit / 8];
                    let index = (byte >> (8 - bpp as usize - bit % 8)) & ((1u16 << bpp) - 1) as u8;
                    let p = palette.get(index as usize).ok_or_else(|| {
                        format!("cannot read it as BMP: palette index {index} out of range")
                    })?;
                    p.map(|v| v as f32 / 255.0)
                }
                16 => {
                    let px = u16::from_le_bytes([row[2 * x], row[2 * x + 1]]) as u32;
                    [masked(px, rm), masked(px, gm), masked(px, bm)]
                }
                24 => [row[3 * x + 2], row[3 * x + 1], row[3 * x]].map(|v| v as f32 / 255.0),
                _ => {
                    let s = &row[4 * x..4 * x + 4];
                    let px = u32::from_le_bytes([s[0], s[1], s[2], s[3]]);
                    [masked(px, rm), masked(px, gm), masked(px, bm)]
                }
            };
            rgb[(y * w + x) * 3..][..3].copy_from_slice(&c);
        }
    }
    Ok(texels_from_samples(w as u32, h as u32, 3, |i| rgb[i], raw))
}
