//! Mitsuba `roughplastic` as the kernels evaluate it, loaded from scene XML through the
//! whole chain (parsing, the precomputed transmittance table as a texture, the GPU
//! material), against Mitsuba 3.9.1 itself: f·cos and the density for a few directions
//! (`scripts/roughplastic_oracle.py` printed the values below).

// Values as Mitsuba printed them.
#![allow(clippy::excessive_precision, clippy::approx_constant)]

use cohort_kernels::bsdf::rough_plastic::{eval, transmittance};
use cohort_kernels::layout::Material;
use glam::{Vec3, Vec4};

type Case = ([f32; 3], [f32; 3], [f32; 3], f32);

fn material(bsdf: &str) -> (Material, Vec<Vec4>) {
    let dir = std::env::temp_dir().join(format!("cohort-roughplastic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(
        &path,
        format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="rectangle">{bsdf}</shape></scene>"#
        ),
    )
    .unwrap();
    let scene = cohort_scenes::load_mitsuba(&path).unwrap().scene;
    let m: Material = bytemuck::cast(scene.gpu_materials()[0]);
    let textures = scene.gpu_textures().into_iter().map(Vec4::from).collect();
    (m, textures)
}

#[test]
fn rough_plastic_is_mitsubas() {
    let cases: [(&str, &[Case]); 4] = [
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.6, 0.3, 0.1"/><boolean name="nonlinear" value="false"/></bsdf>"#,
            &[
                (
                    [0.1736482, 0.0, 0.9848078],
                    [-0.1736482, 2.126577e-17, 0.9848078],
                    [1.6551432e-01, 1.0069570e-01, 5.7483293e-02],
                    3.8929808e-01,
                ),
                (
                    [0.6123724, 0.3535534, 0.7071068],
                    [-0.6123724, -0.3535534, 0.7071068],
                    [1.4846069e-01, 1.0430265e-01, 7.4863955e-02],
                    4.1384065e-01,
                ),
                (
                    [0.8660254, 0.0, 0.5],
                    [2.094269e-17, 0.3420201, 0.9396926],
                    [1.1920404e-01, 6.1785191e-02, 2.3505956e-02],
                    2.4518944e-01,
                ),
                (
                    [0.9848078, 0.0, 0.1736482],
                    [-0.9659258, 1.182918e-16, 0.258819],
                    [8.4513199e-01, 8.3376354e-01, 8.2618457e-01],
                    1.6575283e+00,
                ),
                (
                    [0.5, 0.0, 0.8660254],
                    [0.704416, 0.704416, 0.08715574],
                    [8.7373974e-03, 4.5185755e-03, 1.7060274e-03],
                    2.6044155e-02,
                ),
            ],
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.05"/><float name="int_ior" value="1.49"/><float name="ext_ior" value="1.000277"/><rgb name="diffuse_reflectance" value="0.5, 0.5, 0.5"/><boolean name="nonlinear" value="true"/></bsdf>"#,
            &[
                (
                    [0.1736482, 0.0, 0.9848078],
                    [-0.1736482, 2.126577e-17, 0.9848078],
                    [1.3416973e+00, 1.3416973e+00, 1.3416973e+00],
                    2.7024734e+00,
                ),
                (
                    [0.6123724, 0.3535534, 0.7071068],
                    [-0.6123724, -0.3535534, 0.7071068],
                    [2.2575052e+00, 2.2575052e+00, 2.2575052e+00],
                    4.4725533e+00,
                ),
                (
                    [0.8660254, 0.0, 0.5],
                    [2.094269e-17, 0.3420201, 0.9396926],
                    [8.2691237e-02, 8.2691237e-02, 8.2691237e-02],
                    2.5097346e-01,
                ),
                (
                    [0.9848078, 0.0, 0.1736482],
                    [-0.9659258, 1.182918e-16, 0.258819],
                    [1.7868584e+01, 1.7868584e+01, 1.7868584e+01],
                    3.0577129e+01,
                ),
                (
                    [0.5, 0.0, 0.8660254],
                    [0.704416, 0.704416, 0.08715574],
                    [4.1204067e-03, 4.1204067e-03, 4.1204067e-03],
                    2.5616828e-02,
                ),
            ],
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="beckmann"/><float name="alpha" value="0.2"/><float name="int_ior" value="1.7"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.2, 0.7, 0.4"/><boolean name="nonlinear" value="true"/></bsdf>"#,
            &[
                (
                    [0.1736482, 0.0, 0.9848078],
                    [-0.1736482, 2.126577e-17, 0.9848078],
                    [1.5756647e-01, 2.5880426e-01, 1.8713462e-01],
                    5.5740857e-01,
                ),
                (
                    [0.6123724, 0.3535534, 0.7071068],
                    [-0.6123724, -0.3535534, 0.7071068],
                    [2.3715706e-01, 3.0756584e-01, 2.5772110e-01],
                    6.6817027e-01,
                ),
                (
                    [0.8660254, 0.0, 0.5],
                    [2.094269e-17, 0.3420201, 0.9396926],
                    [1.9453779e-02, 1.0995094e-01, 4.5884944e-02],
                    2.2464830e-01,
                ),
                (
                    [0.9848078, 0.0, 0.1736482],
                    [-0.9659258, 1.182918e-16, 0.258819],
                    [3.5658216e+00, 3.5814867e+00, 3.5703967e+00],
                    5.4733276e+00,
                ),
                (
                    [0.5, 0.0, 0.8660254],
                    [0.704416, 0.704416, 0.08715574],
                    [1.2626573e-03, 7.1412395e-03, 2.9795927e-03],
                    2.3625543e-02,
                ),
            ],
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="beckmann"/><float name="alpha" value="0.6"/><float name="int_ior" value="1.33"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.9, 0.9, 0.9"/><boolean name="nonlinear" value="false"/></bsdf>"#,
            &[
                (
                    [0.1736482, 0.0, 0.9848078],
                    [-0.1736482, 2.126577e-17, 0.9848078],
                    [2.1323796e-01, 2.1323796e-01, 2.1323796e-01],
                    3.1123921e-01,
                ),
                (
                    [0.6123724, 0.3535534, 0.7071068],
                    [-0.6123724, -0.3535534, 0.7071068],
                    [1.5166318e-01, 1.5166318e-01, 1.5166318e-01],
                    2.2944610e-01,
                ),
                (
                    [0.8660254, 0.0, 0.5],
                    [2.094269e-17, 0.3420201, 0.9396926],
                    [1.9497508e-01, 1.9497508e-01, 1.9497508e-01],
                    2.9692987e-01,
                ),
                (
                    [0.9848078, 0.0, 0.1736482],
                    [-0.9659258, 1.182918e-16, 0.258819],
                    [2.1954663e-01, 2.1954663e-01, 2.1954663e-01],
                    2.0985357e-01,
                ),
                (
                    [0.5, 0.0, 0.8660254],
                    [0.704416, 0.704416, 0.08715574],
                    [1.5046265e-02, 1.5046265e-02, 1.5046265e-02],
                    2.7033810e-02,
                ),
            ],
        ),
    ];
    for (bsdf, directions) in cases {
        let (m, textures) = material(bsdf);
        let beckmann = bsdf.contains("beckmann");
        for &(wi, wo, value, pdf) in directions {
            // Mitsuba's wi (towards the viewer) is the kernels' wo.
            let (view, light) = (Vec3::from(wi), Vec3::from(wo));
            let t_i = transmittance(&textures, m, view.z);
            let t_o = transmittance(&textures, m, light.z);
            let e = eval(view, light, m, m.color, t_i, t_o);
            let mitsuba = Vec3::from(value);
            let err =
                ((e.truncate() - mitsuba).abs() / mitsuba.max(Vec3::splat(1e-3))).max_element();
            // 0.3 %: the two transmittance tables' quadratures differ by up to 0.2 % at
            // grazing angles (scenes/tests/rough_plastic_tables.rs compares them).
            assert!(
                err < 3e-3,
                "{bsdf}\n{wi:?} -> {wo:?}: f cos {} vs Mitsuba's {mitsuba} ({err})",
                e.truncate()
            );
            // The densities agree where both sample visible normals (GGX); Beckmann's
            // coating is sampled by D(m) cos here, a different (also unbiased) density.
            // They depend on 1 - t_i (the coating's share), which near normal incidence is
            // a few percent and so magnifies the two quadratures' differences: 1 % here.
            // (Only the variance depends on the density; the value is the image.)
            if !beckmann {
                assert!(
                    (e.w - pdf).abs() / pdf < 1e-2,
                    "{bsdf}\n{wi:?} -> {wo:?}: pdf {} vs Mitsuba's {pdf}",
                    e.w
                );
            }
        }
    }
}
