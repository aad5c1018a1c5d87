//! Image files that bitmap textures read: PNG (8 or 16 bits, grey or colour, with or without
//! alpha), JPEG, BMP, OpenEXR and Radiance HDR, as linear RGB rows from the top, the way
//! Mitsuba's `Bitmap` loads them (integer formats are sRGB-encoded unless the texture is
//! `raw`; EXR and HDR values are linear). BMP and HDR have their own files (`image_bmp`,
//! `image_hdr`).

use std::path::Path;

use glam::Vec3;

/// A decoded image: `width * height` linear RGB texels, row 0 at the top.
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

/// Reads `path` by its extension; `raw`: keep PNG values as stored (no sRGB decoding).
pub fn read_image(path: &Path, raw: bool) -> Result<Image, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let image = match ext.as_str() {
        "png" => read_png(path, raw),
        "jpg" | "jpeg" => read_jpeg(path, raw),
        "bmp" => crate::image_bmp::read_bmp(&read_bytes(path)?, raw),
        "hdr" | "rgbe" | "pic" => crate::image_hdr::read_hdr(&read_bytes(path)?),
        "exr" => read_exr(path),
        other => Err(format!(
            "image format '{other}' is not supported for textures (PNG, JPEG, BMP, OpenEXR and \
             Radiance HDR are; convert it)"
        )),
    }?;
    if image.width == 0 || image.height == 0 {
        return Err("the image is empty".into());
    }
    Ok(image)
}

/// sRGB transfer function to linear, as Mitsuba's `srgb_to_linear`.
fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot open it: {e}"))
}

/// Texels from `channels` samples per pixel (1 or 2: grey with optional alpha, which
/// Mitsuba reads as one channel; 3 or 4: RGB with optional alpha), given as values in
/// [0, 1] in row order from the top; sRGB-decoded unless `raw`.
pub(crate) fn texels_from_samples(
    width: u32,
    height: u32,
    channels: usize,
    sample: impl Fn(usize) -> f32,
    raw: bool,
) -> Image {
    let decode = |v: f32| if raw { v } else { srgb_to_linear(v) };
    let texels = (0..width as usize * height as usize)
        .map(|p| {
            let base = p * channels;
            match channels {
                1 | 2 => Vec3::splat(decode(sample(base))),
                _ => Vec3::new(
                    decode(sample(base)),
                    decode(sample(base + 1)),
                    decode(sample(base + 2)),
                ),
            }
        })
        .collect();
    Image {
        width,
        height,
        texels,
    }
}

fn read_jpeg(path: &Path, raw: bool) -> Result<Image, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open it: {e}"))?;
    let mut decoder = jpeg_decoder::Decoder::new(std::io::BufReader::new(file));
    let pixels = decoder
        .decode()
        .map_err(|e| format!("cannot read it as JPEG: {e}"))?;
    let info = decoder.info().ok_or("cannot read it as JPEG: no image")?;
    let channels = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        other => {
            return Err(format!(
                "JPEG pixel format {other:?} is not supported (8-bit grey and RGB are)"
            ))
        }
    };
    Ok(texels_from_samples(
        info.width as u32,
        info.height as u32,
        channels,
        |i| pixels[i] as f32 / 255.0,
        raw,
    ))
}

fn read_png(path: &Path, raw: bool) -> Result<Image, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open it: {e}"))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    // Palettes and low bit depths become 8-bit grey or RGB(A); 16 bits stay 16 bits.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("cannot read it as PNG: {e}"))?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or("the PNG is too large")?];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("cannot read it as PNG: {e}"))?;
    let channels = info.color_type.samples();
    let wide = info.bit_depth == png::BitDepth::Sixteen;
    let sample = |i: usize| -> f32 {
        if wide {
            u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]]) as f32 / 65535.0
        } else {
            buf[i] as f32 / 255.0
        }
    };
    Ok(texels_from_samples(
        info.width,
        info.height,
        channels,
        sample,
        raw,
    ))
}

fn read_exr(path: &Path) -> Result<Image, String> {
    use exr::prelude::{read, ReadChannels, ReadLayers};
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("cannot read it as OpenEXR: {e}"))?;
    let layer = img.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
    };
    let texels = match (channel("R"), channel("G"), channel("B"), channel("Y")) {
        (Some(r), Some(g), Some(b), _) => (0..w * h).map(|i| Vec3::new(r[i], g[i], b[i])).collect(),
        (_, _, _, Some(y)) => y.into_iter().map(Vec3::splat).collect(),
        _ => return Err("the OpenEXR file has neither R, G, B nor Y channels".into()),
    };
    Ok(Image {
        width: w as u32,
        height: h as u32,
        texels,
    })
}
