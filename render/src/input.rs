//! Reading back an EXR that [`crate::output::write_exr`] wrote: the mean per pixel, the
//! path count per pixel (channel `paths`) and the header's text attributes, which is
//! what a merge needs. Other EXRs read too (their path counts are then absent).

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;

use crate::Image;

/// An EXR image with what its header says.
pub struct ExrRender {
    /// R, G, B per pixel; `paths` from the `paths` channel, zero where it is absent.
    pub image: Image,
    /// Whether the file has a `paths` channel (Cohort's renders do).
    pub has_path_counts: bool,
    /// The header's text attributes, by name.
    pub attributes: BTreeMap<String, String>,
}

/// Reads the first layer of `path`; the error names the file.
pub fn read_exr(path: &Path) -> Result<ExrRender, String> {
    use exr::prelude::*;
    let err = |m: String| format!("{}: {m}", path.display());
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| err(format!("cannot read it as OpenEXR: {e}")))?;
    let layer = img.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
    };
    let rgb: Vec<Vec<f32>> = ["R", "G", "B"]
        .iter()
        .map(|&name| {
            channel(name)
                .map(|c| c.sample_data.values_as_f32().collect())
                .ok_or_else(|| err(format!("has no {name} channel")))
        })
        .collect::<std::result::Result<_, _>>()?;
    let pixels = (0..w * h)
        .map(|i| Vec3::new(rgb[0][i], rgb[1][i], rgb[2][i]))
        .collect();
    let paths = channel("paths").map(|c| match &c.sample_data {
        FlatSamples::U32(v) => v.clone(),
        other => other
            .values_as_f32()
            .map(|v| v.max(0.0).round() as u32)
            .collect(),
    });
    let mut attributes = BTreeMap::new();
    for (key, value) in &layer.attributes.other {
        if let AttributeValue::Text(t) = value {
            attributes.insert(
                String::from_utf8_lossy(key.bytes()).into_owned(),
                String::from_utf8_lossy(t.bytes()).into_owned(),
            );
        }
    }
    Ok(ExrRender {
        has_path_counts: paths.is_some(),
        image: crate::Image {
            width: w as u32,
            height: h as u32,
            pixels,
            paths: paths.unwrap_or_else(|| vec![0; w * h]),
        },
        attributes,
    })
}
