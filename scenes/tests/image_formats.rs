//! The image formats of bitmap textures: JPEG, BMP and Radiance HDR decode to the texels
//! the same picture has as a PNG (BMP, exactly), or to their RGBE values (HDR); malformed
//! files are errors, never panics.

use cohort_scenes::image_file::{read_image, Image};
use glam::Vec3;
use std::path::PathBuf;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-images-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/images")
        .join(name)
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// 3 x 2 RGB pixels, rows from the top.
const PIXELS: [[u8; 3]; 6] = [
    [255, 0, 0],
    [0, 255, 0],
    [0, 0, 255],
    [10, 128, 250],
    [0, 0, 0],
    [255, 255, 255],
];

fn png_of_pixels() -> Image {
    let mut bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut bytes, 3, 2);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.write_header()
            .unwrap()
            .write_image_data(&PIXELS.concat())
            .unwrap();
    }
    read_image(&write("pixels.png", &bytes), false).unwrap()
}

/// A BITMAPINFOHEADER BMP of `PIXELS`: `bpp` 24 (BGR) or 32 (BGRA), rows bottom-up unless
/// `top_down`.
fn bmp(bpp: u16, top_down: bool) -> Vec<u8> {
    let (w, h) = (3usize, 2usize);
    let row_bytes = (w * bpp as usize).div_ceil(32) * 4;
    let mut px = Vec::new();
    for y in 0..h {
        let src = if top_down { y } else { h - 1 - y };
        let mut row = Vec::new();
        for x in 0..w {
            let [r, g, b] = PIXELS[src * w + x];
            row.extend([b, g, r]);
            if bpp == 32 {
                row.push(255);
            }
        }
        row.resize(row_bytes, 0);
        px.extend(row);
    }
    let mut f = Vec::new();
    f.extend(b"BM");
    f.extend(((54 + px.len()) as u32).to_le_bytes());
    f.extend([0u8; 4]);
    f.extend(54u32.to_le_bytes());
    f.extend(40u32.to_le_bytes());
    f.extend((w as i32).to_le_bytes());
    f.extend((if top_down { -(h as i32) } else { h as i32 }).to_le_bytes());
    f.extend(1u16.to_le_bytes());
    f.extend(bpp.to_le_bytes());
    f.extend([0u8; 24]);
    f.extend(px);
    f
}

#[test]
fn bmp_reads_as_the_same_png() {
    let png = png_of_pixels();
    for (bpp, top_down) in [(24, false), (24, true), (32, false)] {
        let img = read_image(&write("p.bmp", &bmp(bpp, top_down)), false).unwrap();
        assert_eq!((img.width, img.height), (3, 2));
        assert_eq!(img.texels, png.texels, "{bpp} bits, top-down {top_down}");
    }
    // `raw`: the stored values, not sRGB-decoded.
    let raw = read_image(&write("p.bmp", &bmp(24, false)), true).unwrap();
    assert_eq!(raw.texels[3], Vec3::new(10.0, 128.0, 250.0) / 255.0);
}

#[test]
fn paletted_bmp_reads_its_palette() {
    // 8-bit, 2 x 1, palette of two entries (BGRx): index 1 then 0.
    let mut f = Vec::new();
    f.extend(b"BM");
    f.extend(0u32.to_le_bytes());
    f.extend([0u8; 4]);
    f.extend((54u32 + 8).to_le_bytes());
    f.extend(40u32.to_le_bytes());
    f.extend(2i32.to_le_bytes());
    f.extend(1i32.to_le_bytes());
    f.extend(1u16.to_le_bytes());
    f.extend(8u16.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    f.extend([0u8; 12]);
    f.extend(2u32.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    f.extend([0, 0, 255, 0, 255, 0, 0, 0]);
    f.extend([1, 0, 0, 0]);
    let img = read_image(&write("pal.bmp", &f), true).unwrap();
    assert_eq!(img.texels, vec![Vec3::Z, Vec3::X]);
}

#[test]
fn jpeg_reads_its_colours_within_rounding() {
    let img = read_image(&data("halves.jpg"), true).unwrap();
    assert_eq!((img.width, img.height), (16, 8));
    let close = |a: Vec3, b: [u8; 3]| {
        (a * 255.0 - Vec3::from(b.map(f32::from)))
            .abs()
            .max_element()
            <= 2.0
    };
    assert!(
        close(img.texels[0], [200, 100, 50]),
        "{}",
        img.texels[0] * 255.0
    );
    assert!(
        close(img.texels[15], [30, 60, 90]),
        "{}",
        img.texels[15] * 255.0
    );
    let grey = read_image(&data("grey.jpg"), true).unwrap();
    assert!(grey
        .texels
        .iter()
        .all(|t| (t.x * 255.0 - 128.0).abs() <= 2.0 && t.x == t.y && t.y == t.z));
    // Not raw: sRGB-decoded, as Mitsuba 3.9.1 reads the same files (`mi.Bitmap(path).convert(
    // RGB, Float32, srgb_gamma=False)`, scalar_rgb).
    let lin = read_image(&data("halves.jpg"), false).unwrap();
    let mitsuba = [
        (0, Vec3::new(0.577581, 0.127438, 0.031896)),
        (15, Vec3::new(0.0129831, 0.043735, 0.0998988)),
    ];
    for (i, m) in mitsuba {
        assert!(
            (lin.texels[i] - m).abs().max_element() < 1e-5,
            "{i}: {} vs {m}",
            lin.texels[i]
        );
    }
    let lin = read_image(&data("grey.jpg"), false).unwrap();
    assert!(
        (lin.texels[0].x - 0.2158605).abs() < 0.01,
        "{}",
        lin.texels[0].x
    );
}

fn hdr(header_extra: &str, w: usize, h: usize, body: &[u8]) -> Vec<u8> {
    let mut header = String::from("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n");
    if !header_extra.is_empty() {
        header += &format!("{header_extra}\n");
    }
    let mut f = format!("{header}\n-Y {h} +X {w}\n").into_bytes();
    f.extend(body);
    f
}

#[test]
fn hdr_reads_flat_and_run_length_scanlines() {
    // Flat: 2 x 1, (128, 64, 32, e=129) = (1, 0.5, 0.25); (0, 0, 0, 0) = 0.
    let img = read_image(
        &write("flat.hdr", &hdr("", 2, 1, &[128, 64, 32, 129, 9, 9, 9, 0])),
        false,
    )
    .unwrap();
    assert_eq!(img.texels, vec![Vec3::new(1.0, 0.5, 0.25), Vec3::ZERO]);
    // New RLE, width 8: channel by channel, a run of 8 or literals.
    let mut body = vec![2, 2, 0, 8];
    body.extend([128 + 8, 128]); // R: eight times 128
    body.extend([8, 0, 16, 32, 48, 64, 80, 96, 112]); // G: literals
    body.extend([128 + 4, 64, 128 + 4, 0]); // B: four 64, four 0
    body.extend([128 + 8, 130]); // E: 2^(130 - 136) = 1/64
    let img = read_image(&write("rle.hdr", &hdr("EXPOSURE=1", 8, 1, &body)), false).unwrap();
    let f = 1.0 / 64.0;
    for x in 0..8 {
        let b = if x < 4 { 64.0 } else { 0.0 };
        assert_eq!(
            img.texels[x],
            Vec3::new(128.0, 16.0 * x as f32, b) * f,
            "pixel {x}"
        );
    }
}

#[test]
fn malformed_images_are_errors_not_panics() {
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("a.bmp", b"BM".to_vec()),
        ("b.bmp", bmp(24, false)[..60].to_vec()),
        ("c.bmp", b"XX not a bmp at all, really not".to_vec()),
        (
            "d.hdr",
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n\x01".to_vec(),
        ),
        (
            "e.hdr",
            b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0".to_vec(),
        ),
        ("f.hdr", b"#?RADIANCE\n\n+Y 1 +X 1\n\0\0\0\0".to_vec()),
        ("g.hdr", hdr("", 8, 1, &[2, 2, 0, 8, 200, 1])),
        ("h.jpg", b"\xff\xd8\xff garbage".to_vec()),
        ("i.tga", vec![0; 20]),
    ];
    for (name, bytes) in cases {
        let r = read_image(&write(name, &bytes), false);
        assert!(r.is_err(), "{name} decoded");
    }
}
