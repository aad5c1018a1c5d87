//! Morton codes of pixels: round trip, Z-order locality, and the pixel order for any image size.

use cohort_scenes::{morton2d_decode, morton2d_encode, morton_pixel_order};

#[test]
fn round_trip() {
    for y in (0..65536u32).step_by(251).chain([0, 1, 65535]) {
        for x in (0..65536u32).step_by(239).chain([0, 1, 65535]) {
            assert_eq!(morton2d_decode(morton2d_encode(x, y)), (x, y));
        }
    }
    for code in (0..u32::MAX).step_by(65_537).chain([u32::MAX]) {
        let (x, y) = morton2d_decode(code);
        assert_eq!(morton2d_encode(x, y), code);
    }
}

#[test]
fn bit_layout_and_z_order() {
    // x in the even bits, y in the odd bits.
    assert_eq!(morton2d_encode(1, 0), 1);
    assert_eq!(morton2d_encode(0, 1), 2);
    assert_eq!(morton2d_encode(3, 3), 15);
    assert_eq!(morton2d_encode(0xffff, 0), 0x5555_5555);
    // The first 16 codes cover the 4 x 4 top-left block, 2 x 2 quads first.
    let first: Vec<(u32, u32)> = (0..4).map(morton2d_decode).collect();
    assert_eq!(first, [(0, 0), (1, 0), (0, 1), (1, 1)]);
    let mut block: Vec<(u32, u32)> = (0..16).map(morton2d_decode).collect();
    block.sort();
    let expected: Vec<(u32, u32)> = (0..4).flat_map(|x| (0..4).map(move |y| (x, y))).collect();
    assert_eq!(block, expected);
}

#[test]
fn pixel_order_is_a_permutation_in_z_order() {
    let order = morton_pixel_order(8, 8);
    let decoded: Vec<u32> = (0..64)
        .map(|g| {
            let (x, y) = morton2d_decode(g);
            y * 8 + x
        })
        .collect();
    assert_eq!(order, decoded);
    for (w, h) in [
        (5, 3),
        (640, 480),
        (1, 7),
        (1, 1),
        (7, 1),
        (3, 1000),
        (1000, 3),
        (257, 129),
        (64, 64),
        (1024, 1),
    ] {
        let mut order = morton_pixel_order(w, h);
        let codes: Vec<u32> = order
            .iter()
            .map(|&p| morton2d_encode(p % w, p / w))
            .collect();
        assert!(codes.windows(2).all(|c| c[0] < c[1]));
        order.sort();
        assert_eq!(order, (0..w * h).collect::<Vec<_>>());
    }
}
