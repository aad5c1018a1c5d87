//! Writing images: linear EXR (exr crate) and tone-mapped sRGB PNG (png crate). Both
//! are written to a temporary file beside the target and renamed over it, so a failed
//! run never leaves a half-written file in place of a good one.

use crate::Image;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {message}")]
pub struct OutputError {
    pub path: PathBuf,
    pub message: String,
}

fn temp_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes `path` through a temporary file: `write` fills the temporary file, which is
/// renamed over `path` only if it succeeded.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), OutputError> {
    let err = |message: String| OutputError {
        path: path.to_path_buf(),
        message,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(err(format!("directory {} does not exist", dir.display())));
        }
    }
    let tmp = temp_beside(path);
    match write(&tmp) {
        Ok(()) => std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            err(e.to_string())
        }),
        Err(m) => {
            let _ = std::fs::remove_file(&tmp);
            Err(err(m))
        }
    }
}

/// Writes a linear EXR: channels R, G, B (each pixel's mean over its paths, in f32) and
/// `paths` (its path count, u32), which is what a merge weights by; `attributes` go into
/// the header as text (`crate::provenance` writes how the image was rendered there).
/// Text is stored as UTF-8 bytes, which OpenEXR's text attributes allow.
pub fn write_exr(
    path: &Path,
    img: &Image,
    attributes: &[(String, String)],
) -> Result<(), OutputError> {
    use exr::prelude::*;
    write_atomically(path, |tmp| {
        let channel = |name: &str, c: usize| {
            AnyChannel::new(
                name,
                FlatSamples::F32(img.pixels.iter().map(|p| p[c]).collect()),
            )
        };
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            channel("R", 0),
            channel("G", 1),
            channel("B", 2),
            AnyChannel::new("paths", FlatSamples::U32(img.paths.clone())),
        ]));
        let mut header = LayerAttributes::default();
        for (key, value) in attributes {
            header.other.insert(
                Text::from_slice_unchecked(key.as_bytes()),
                AttributeValue::Text(Text::from_slice_unchecked(value.as_bytes())),
            );
        }
        let layer = Layer::new(
            (img.width as usize, img.height as usize),
            header,
            Encoding::FAST_LOSSLESS,
            channels,
        );
        Image::from_layer(layer)
            .write()
            .to_file(tmp)
            .map_err(|e| e.to_string())
    })
}

/// The sRGB encoding of `display`, the viewer's kernel, run here as the Rust it is: the
/// PNG and the viewer round every pixel alike.
fn srgb(linear: f32) -> u8 {
    cohort_kernels::display::srgb8(linear) as u8
}

/// Tone-maps with exposure `2^stops` and clamping, then encodes sRGB.
pub fn write_png(path: &Path, img: &Image, stops: f32) -> Result<(), OutputError> {
    let scale = 2f32.powf(stops);
    write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), img.width, img.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        // fdeflate: several times faster than the default level, for a file a few percent
        // larger (6 % on the Cornell box; the EXR is the exact image, the PNG is for viewing).
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header().map_err(|e| e.to_string())?;
        let data: Vec<u8> = img
            .pixels
            .iter()
            .flat_map(|p| [srgb(p.x * scale), srgb(p.y * scale), srgb(p.z * scale)])
            .collect();
        writer.write_image_data(&data).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
}

/// Writes a text file (e.g. statistics JSON) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    write_atomically(path, |tmp| {
        let mut f = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        f.write_all(text.as_bytes()).map_err(|e| e.to_string())?;
        f.sync_all().map_err(|e| e.to_string())
    })
}
