//! Normal and bump maps as the kernels compute them (host Rust): the height gradient is the
//! derivative of the bilinear lookup, and the perturbed frame behaves as Mitsuba's.

use cohort_kernels::perturb::{perturb_weight, perturbed_normal, surface_tangents};
use cohort_kernels::texture::{luminance, texture_eval, texture_gradient};
use cohort_scenes::texture::{gpu_textures, Filter, Texture, UvTransform, Wrap};
use glam::{Vec2, Vec3, Vec4};

fn bitmap(filter: Filter, to_uv: UvTransform) -> Vec<Vec4> {
    let (w, h) = (7u32, 5u32);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            Vec3::new((x * 0.7).sin().abs(), (y * 0.9 + x).cos().abs(), 0.3)
        })
        .collect();
    let t = Texture::Bitmap {
        width: w,
        height: h,
        texels,
        filter,
        wrap: Wrap::Repeat,
        to_uv,
    };
    gpu_textures(&[t], 0)
        .0
        .into_iter()
        .map(Vec4::from)
        .collect()
}

/// Inside a texel cell the gradient is the derivative of the bilinear luminance.
#[test]
fn height_gradient_is_the_bilinear_derivative() {
    let t = bitmap(Filter::Bilinear, UvTransform::IDENTITY);
    let f = |uv: Vec2| luminance(texture_eval(&t, 0, uv));
    for uv in [
        Vec2::new(0.31, 0.47),
        Vec2::new(0.77, 0.12),
        Vec2::new(0.05, 0.83),
    ] {
        let e = 1e-3;
        let fd = Vec2::new(
            (f(uv + Vec2::new(e, 0.0)) - f(uv - Vec2::new(e, 0.0))) / (2.0 * e),
            (f(uv + Vec2::new(0.0, e)) - f(uv - Vec2::new(0.0, e))) / (2.0 * e),
        );
        let g = texture_gradient(&t, 0, uv);
        assert!(
            (g - fd).abs().max_element() < 0.02 * (1.0 + fd.abs().max_element()),
            "{uv}: {g} vs {fd}"
        );
    }
    // Nearest filtering is flat almost everywhere: Mitsuba's gradient is zero.
    let t = bitmap(Filter::Nearest, UvTransform::IDENTITY);
    assert_eq!(texture_gradient(&t, 0, Vec2::new(0.31, 0.47)), Vec2::ZERO);
}

/// dp/du and dp/dv map texture-coordinate steps to the surface steps of the triangle.
#[test]
fn tangents_follow_the_parameterisation() {
    let (v0, v1, v2) = (
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    );
    // u runs along v0 -> v1 over 0..0.5, v along v0 -> v2 over 0..0.25.
    let m = surface_tangents(
        v0,
        v1,
        v2,
        Vec4::new(0.0, 0.0, 0.5, 0.0),
        Vec2::new(0.0, 0.25),
        Vec3::Z,
    );
    assert!(
        (m.x_axis - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-5,
        "{}",
        m.x_axis
    );
    assert!(
        (m.y_axis - Vec3::new(0.0, 12.0, 0.0)).length() < 1e-5,
        "{}",
        m.y_axis
    );
}

/// A normal facing away from the viewer is mirrored about the shading normal; the weight
/// is 0 for directions on different sides of the two frames, 1 for the unperturbed normal
/// and below 1 (Estevez et al.) for a tilted one.
#[test]
fn flip_and_weight_as_mitsuba() {
    let (s, t, b) = (Vec3::X, Vec3::Y, Vec3::Z);
    let local = Vec3::new(0.8, 0.0, 0.6);
    let wi = Vec3::new(-0.9, 0.0, 0.1).normalize();
    let n = perturbed_normal(local, s, t, b, wi, true);
    assert!((n - Vec3::new(-0.8, 0.0, 0.6)).length() < 1e-6, "{n}");
    let n_kept = perturbed_normal(local, s, t, b, wi, false);
    assert!((n_kept - local).length() < 1e-6);
    assert_eq!(
        perturb_weight(b, b, Vec3::new(0.3, 0.0, 0.9).normalize(), true),
        1.0
    );
    let wo = Vec3::new(0.5, 0.0, 0.5).normalize();
    let w = perturb_weight(b, local, wo, true);
    assert!(w > 0.5 && w < 1.0, "{w}");
    assert_eq!(perturb_weight(b, local, wo, false), 1.0);
    // Above the shading plane but below the perturbed one.
    let under = Vec3::new(-0.9, 0.0, 0.2).normalize();
    assert_eq!(perturb_weight(b, local, under, true), 0.0);
}
