//! Radiance HDR (RGBE) images for bitmap textures: flat or run-length encoded scanlines (both
//! the new per-channel and the old repeat-pixel encoding), rows from the top (`-Y H +X W`).
//! Values are linear, converted as Mitsuba's RGBE reader does (`mantissa * 2^(e - 136)`).

use crate::image_file::Image;
use glam::Vec3;

fn bad(what: &str) -> String {
    format!("cannot read it as Radiance HDR: {what}")
}

pub fn read_hdr(b: &[u8]) -> Result<Image, String> {
    // Header: text lines up to an empty one, then the resolution line.
    let mut at = 0;
    let mut line = || -> Result<&str, String> {
        let end = b[at..]
            .iter()
            .position(|&c| c == b'\n')
            .ok_or_else(|| bad("the header does not end"))?;
        let l = std::str::from_utf8(&b[at..at + end]).map_err(|_| bad("header is not text"))?;
        at += end + 1;
        Ok(l.trim_end_matches('\r'))
    };
    let magic = line()?;
    if !magic.starts_with("#?") {
        return Err(bad("no '#?RADIANCE' signature"));
    }
    loop {
        let l = line()?;
        if l.is_empty() {
            break;
        }
        if let Some(f) = l.strip_prefix("FORMAT=") {
            if f != "32-bit_rle_rgbe" {
                return Err(bad(&format!(
                    "format {f} (only 32-bit_rle_rgbe is supported)"
                )));
            }
        }
    }
    let res = line()?.to_string();
    let parts: Vec<&str> = res.split_whitespace().collect();
    let (h, w) = match parts.as_slice() {
        ["-Y", h, "+X", w] => (h.parse::<usize>(), w.parse::<usize>()),
        _ => {
            return Err(bad(&format!(
                "orientation '{res}' (only the standard '-Y H +X W' is supported)"
            )))
        }
    };
    let (h, w) = match (h, w) {
        (Ok(h), Ok(w)) if h > 0 && w > 0 && h <= 1 << 16 && w <= 1 << 16 => (h, w),
        _ => return Err(bad(&format!("bad resolution line '{res}'"))),
    };
    let data = &b[at..];
    let mut pos = 0;
    let mut byte = || -> Result<u8, String> {
        let v = *data
            .get(pos)
            .ok_or_else(|| bad("the pixel data are truncated"))?;
        pos += 1;
        Ok(v)
    };
    let mut rgbe = vec![[0u8; 4]; w * h];
    for y in 0..h {
        let row = &mut rgbe[y * w..(y + 1) * w];
        let first = [byte()?, byte()?, byte()?, byte()?];
        let new_rle =
            (8..0x8000).contains(&w) && first[0] == 2 && first[1] == 2 && first[2] & 0x80 == 0;
        if new_rle {
            if ((first[2] as usize) << 8 | first[3] as usize) != w {
                return Err(bad("a scanline's length differs from the width"));
            }
            for c in 0..4 {
                let mut x = 0;
                while x < w {
                    let count = byte()? as usize;
                    if count > 128 {
                        let n = count - 128;
                        let v = byte()?;
                        if x + n > w {
                            return Err(bad("a run overflows its scanline"));
                        }
                        row[x..x + n].iter_mut().for_each(|p| p[c] = v);
                        x += n;
                    } else {
                        if count == 0 || x + count > w {
                            return Err(bad("a literal run overflows its scanline"));
                        }
                        for p in &mut row[x..x + count] {
                            p[c] = byte()?;
                        }
                        x += count;
                    }
                }
            }
        } else {
            // Flat pixels; (1, 1, 1, n) repeats the previous pixel n << shift times.
            let mut x = 0;
            let mut shift = 0;
            let mut p = first;
            loop {
                if p[0] == 1 && p[1] == 1 && p[2] == 1 {
                    if x == 0 {
                        return Err(bad("a repeat run starts a scanline"));
                    }
                    let n = (p[3] as usize) << shift;
                    if x + n > w {
                        return Err(bad("a repeat run overflows its scanline"));
                    }
                    let prev = row[x - 1];
                    row[x..x + n].iter_mut().for_each(|q| *q = prev);
                    x += n;
                    shift += 8;
                } else {
                    row[x] = p;
                    x += 1;
                    shift = 0;
                }
                if x == w {
                    break;
                }
                p = [byte()?, byte()?, byte()?, byte()?];
            }
        }
    }
    let texels = rgbe
        .iter()
        .map(|&[r, g, b, e]| {
            if e == 0 {
                Vec3::ZERO
            } else {
                let f = 2f32.powi(e as i32 - 136);
                Vec3::new(r as f32 * f, g as f32 * f, b as f32 * f)
            }
        })
        .collect();
    Ok(Image {
        width: w as u32,
        height: h as u32,
        texels,
    })
}
