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

/// A file written to a temporary path beside its destination, not yet in place:
/// [`commit`](Staged::commit) renames it over the destination; dropped uncommitted, it is
/// removed. A run that writes several files stages them all first and commits them only
/// when every one was written, so that a failure leaves every existing file as it was.
#[must_use = "a staged file is removed unless committed"]
pub struct Staged {
    tmp: PathBuf,
    path: PathBuf,
    committed: bool,
}

impl Staged {
    /// Puts the file in place.
    pub fn commit(mut self) -> Result<(), OutputError> {
        self.committed = true;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| {
            let _ = std::fs::remove_file(&self.tmp);
            OutputError {
                path: self.path.clone(),
                message: e.to_string(),
            }
        })
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Fails unless `path` could be written: its directory exists. Checked before a render
/// starts, so that a mistyped output path is reported in a second, not after the render.
pub fn check_destination(path: &Path) -> Result<(), OutputError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(OutputError {
                path: path.to_path_buf(),
                message: format!("directory {} does not exist", dir.display()),
            });
        }
    }
    if path.is_dir() {
        return Err(OutputError {
            path: path.to_path_buf(),
            message: "it is a directory".into(),
        });
    }
    Ok(())
}

/// Writes `path`'s content to a temporary file beside it with `write`: the [`Staged`] file
/// to commit, or the error (and no file).
pub fn stage(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<Staged, OutputError> {
    check_destination(path)?;
    let staged = Staged {
        tmp: temp_beside(path),
        path: path.to_path_buf(),
        committed: false,
    };
    write(&staged.tmp).map_err(|message| OutputError {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(staged)
}

/// Writes `path` through a temporary file: `write` fills the temporary file, which is
/// renamed over `path` only if it succeeded.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), OutputError> {
    stage(path, write)?.commit()
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
    stage_exr(path, img, attributes)?.commit()
}

/// [`write_exr`], staged: the file is in place once committed.
pub fn stage_exr(
    path: &Path,
    img: &Image,
    attributes: &[(String, String)],
) -> Result<Staged, OutputError> {
    use exr::prelude::*;
    stage(path, |tmp| {
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
    stage_png(path, img, stops)?.commit()
}

/// [`write_png`], staged: the file is in place once committed.
pub fn stage_png(path: &Path, img: &Image, stops: f32) -> Result<Staged, OutputError> {
    let scale = 2f32.powf(stops);
    stage(path, |tmp| {
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
