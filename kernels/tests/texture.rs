//! The kernels' texture lookup (`texture::texture_eval`, run here on the host) agrees with
//! `cohort_scenes::Texture::eval` for every filter and wrap mode, inside and outside [0, 1]^2.

use cohort_kernels::texture::texture_eval;
use cohort_scenes::texture::{gpu_textures, Filter, Texture, UvTransform, Wrap};
use glam::{Vec2, Vec3, Vec4};

#[test]
fn kernel_lookup_matches_the_scene_texture() {
    let texels: Vec<Vec3> = (0..12)
        .map(|i| {
            Vec3::new(
                i as f32 / 11.0,
                (i % 3) as f32 / 2.0,
                ((i * 7) % 5) as f32 / 4.0,
            )
        })
        .collect();
    let to_uv = UvTransform {
        x: Vec2::new(1.5, 0.25),
        y: Vec2::new(-0.5, 2.0),
        offset: Vec2::new(0.1, -0.3),
    };
    let mut textures = vec![Texture::Checkerboard {
        color0: Vec3::new(0.9, 0.1, 0.2),
        color1: Vec3::new(0.1, 0.8, 0.3),
        to_uv,
    }];
    for filter in [Filter::Nearest, Filter::Bilinear] {
        for wrap in [Wrap::Repeat, Wrap::Mirror, Wrap::Clamp] {
            textures.push(Texture::Bitmap {
                width: 4,
                height: 3,
                texels: texels.clone(),
                filter,
                wrap,
                to_uv,
            });
        }
    }
    let (data, starts) = gpu_textures(&textures, 0);
    let data: Vec<Vec4> = data.into_iter().map(Vec4::from_array).collect();
    for (t, &start) in textures.iter().zip(&starts) {
        for i in 0..40 {
            for j in 0..40 {
                let uv = Vec2::new(-1.3 + i as f32 * 0.071, -0.9 + j as f32 * 0.067);
                let kernel = texture_eval(&data, start, uv);
                let host = t.eval(uv);
                assert!(
                    (kernel - host).abs().max_element() < 1e-5,
                    "{t:?} at {uv}: kernel {kernel}, host {host}"
                );
            }
        }
    }
}
