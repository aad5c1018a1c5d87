//! Morton (Z-order) codes of pixels. The renderer stores its rays in the Morton order of their
//! pixels (the paper's §3) so that neighbouring threads trace neighbouring primary rays; thread `g`
//! starts on pixel `morton2d_decode(g)`.

/// Spreads the low 16 bits of `v` to the even bit positions.
fn part1by1(v: u32) -> u32 {
    let mut x = v & 0x0000_ffff;
    x = (x | (x << 8)) & 0x00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333;
    x = (x | (x << 1)) & 0x5555_5555;
    x
}

fn compact1by1(v: u32) -> u32 {
    let mut x = v & 0x5555_5555;
    x = (x | (x >> 1)) & 0x3333_3333;
    x = (x | (x >> 2)) & 0x0f0f_0f0f;
    x = (x | (x >> 4)) & 0x00ff_00ff;
    x = (x | (x >> 8)) & 0x0000_ffff;
    x
}

/// Interleaves x (even bits) and y (odd bits). Only the low 16 bits of each are used: images up to
/// 65536 x 65536.
pub fn morton2d_encode(x: u32, y: u32) -> u32 {
    part1by1(x) | (part1by1(y) << 1)
}

/// Inverse of [`morton2d_encode`]: `(x, y)`.
pub fn morton2d_decode(code: u32) -> (u32, u32) {
    (compact1by1(code), compact1by1(code >> 1))
}

/// Row-major pixel indices (`y * width + x`) of a `width` x `height` image, sorted by Morton code.
/// For square power-of-two images this equals decoding 0, 1, 2, ...; for other sizes it skips the
/// codes that fall outside the image, keeping the Z-order locality.
///
/// The quadtree of the codes is walked in code order, so that a square wholly inside the image is
/// listed by decoding consecutive codes and one wholly outside is skipped: linear in the pixels
/// (a sort of every pixel's code took 10-15 ms of a 512x512 render's startup on four copies).
pub fn morton_pixel_order(width: u32, height: u32) -> Vec<u32> {
    if width > 1 << 16 || height > 1 << 16 {
        // Beyond the codes' 16 bits per axis, the order of the codes as they are.
        let mut pixels: Vec<(u32, u32)> = (0..height)
            .flat_map(|y| (0..width).map(move |x| (morton2d_encode(x, y), y * width + x)))
            .collect();
        pixels.sort_unstable();
        return pixels.into_iter().map(|(_, p)| p).collect();
    }
    let mut out = Vec::with_capacity(width as usize * height as usize);
    let side = width.max(height).max(1).next_power_of_two();
    quadrant(0, 0, side, width, height, &mut out);
    out
}

/// Appends the pixels of the `side` x `side` square at (`x0`, `y0`) that lie in the image, in
/// Morton order: x in the even bits, so the quadrants go (0, 0), (1, 0), (0, 1), (1, 1).
fn quadrant(x0: u32, y0: u32, side: u32, width: u32, height: u32, out: &mut Vec<u32>) {
    if x0 >= width || y0 >= height {
        return;
    }
    if x0 + side <= width && y0 + side <= height {
        out.extend((0..side * side).map(|c| {
            let (dx, dy) = morton2d_decode(c);
            (y0 + dy) * width + x0 + dx
        }));
        return;
    }
    let h = side / 2;
    for (dx, dy) in [(0, 0), (h, 0), (0, h), (h, h)] {
        quadrant(x0 + dx, y0 + dy, h, width, height, out);
    }
}
