//! Point, spot and directional emitters read with Mitsuba 3.9's parameters and defaults.

use cohort_scenes::{load_mitsuba_str, Light};
use glam::{Mat4, Vec3};

fn lights(body: &str) -> Result<Vec<Light>, String> {
    let xml = format!(r#"<scene version="3.0.0">{body}</scene>"#);
    load_mitsuba_str(&xml, ".")
        .map(|l| l.scene.lights)
        .map_err(|e| e.to_string())
}

#[test]
fn point_light_position_from_either_parameter() {
    let l = lights(r#"<emitter type="point"><point name="position" value="1, 2, 3"/><rgb name="intensity" value="4, 5, 6"/></emitter>"#).unwrap();
    assert_eq!(
        l,
        vec![Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity: Vec3::new(4.0, 5.0, 6.0)
        }]
    );
    let l = lights(r#"<emitter type="point"><transform name="to_world"><translate x="-1" y="0.5"/></transform></emitter>"#).unwrap();
    assert_eq!(
        l,
        vec![Light::Point {
            position: Vec3::new(-1.0, 0.5, 0.0),
            intensity: Vec3::ONE
        }]
    );
    let e = lights(r#"<emitter type="point"><point name="position" value="1, 2, 3"/><transform name="to_world"><translate x="1"/></transform></emitter>"#).unwrap_err();
    assert!(e.contains("not both") && e.contains(":1:"), "{e}");
    let e = lights(r#"<emitter type="point"><float name="intensity" value="-1"/></emitter>"#)
        .unwrap_err();
    assert!(e.contains("intensity must be finite and >= 0"), "{e}");
}

#[test]
fn spot_defaults_are_mitsubas() {
    let l = lights(r#"<emitter type="spot"><transform name="to_world"><lookat origin="0, 1, 0" target="0, 0, 0" up="0, 0, 1"/></transform></emitter>"#).unwrap();
    let [Light::Spot {
        to_world,
        intensity,
        cutoff_angle,
        beam_width,
        texture: None,
    }] = l.as_slice()
    else {
        panic!("{l:?}")
    };
    assert_eq!(*intensity, Vec3::ONE);
    assert!((cutoff_angle - 20f32.to_radians()).abs() < 1e-6);
    assert!((beam_width - 15f32.to_radians()).abs() < 1e-6);
    // The spot looks along its +z: here, down.
    let axis = to_world.transform_vector3(Vec3::Z);
    assert!((axis - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5, "{axis}");
    assert_eq!(
        to_world.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 1.0, 0.0)
    );
    let e = lights(r#"<emitter type="spot"><float name="cutoff_angle" value="10"/><float name="beam_width" value="12"/></emitter>"#).unwrap_err();
    assert!(e.contains("beam_width 12"), "{e}");
    let e = lights(r#"<emitter type="spot"><rgb name="texture" value="1, 0, 0"/></emitter>"#)
        .unwrap_err();
    assert!(e.contains("must be spatially varying"), "{e}");
}

/// A spot's texture and a projector's image, scale and field of view (along y here: its
/// x angle follows from the image's aspect, as Mitsuba's `parse_fov` converts it).
#[test]
fn textured_spot_and_projector() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../render/tests/scenes/mitsuba/textures");
    let xml = r#"<scene version="3.0.0">
        <emitter type="spot"><texture type="checkerboard" name="texture"/></emitter>
        <emitter type="projector">
            <texture type="bitmap" name="irradiance"><string name="filename" value="stripes.png"/></texture>
            <float name="scale" value="2"/><float name="fov" value="30"/><string name="fov_axis" value="y"/>
        </emitter>
        <emitter type="projector"><rgb name="irradiance" value="1, 2, 3"/></emitter>
    </scene>"#;
    let s = load_mitsuba_str(xml, &dir).unwrap().scene;
    let [Light::Spot {
        texture: Some(_), ..
    }, Light::Projector {
        irradiance,
        texture: Some(t),
        tan_half_fov,
        aspect,
        ..
    }, Light::Projector {
        irradiance: constant,
        texture: None,
        aspect: square,
        tan_half_fov: default_fov,
        ..
    }] = s.lights.as_slice()
    else {
        panic!("{:?}", s.lights)
    };
    assert!(matches!(
        s.textures[*t as usize],
        cohort_scenes::Texture::Bitmap {
            width: 16,
            height: 12,
            ..
        }
    ));
    assert_eq!(*irradiance, Vec3::splat(2.0));
    assert!((aspect - 16.0 / 12.0).abs() < 1e-6);
    // tan(fov_x / 2) = tan(fov_y / 2) * aspect.
    assert!((tan_half_fov - 15f32.to_radians().tan() * aspect).abs() < 1e-5);
    assert_eq!(*constant, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(*square, 1.0);
    // Mitsuba's default: a 50 mm lens, diagonal, on a square image.
    // (tan of half the diagonal angle: half the 43.27 mm film diagonal over 50 mm.)
    let half_diagonal = (36f32 * 36.0 + 24.0 * 24.0).sqrt() / 100.0;
    assert!(
        (default_fov - half_diagonal / 2f32.sqrt()).abs() < 1e-4,
        "{default_fov}"
    );
}

#[test]
fn directional_light_direction() {
    let l = lights(r#"<emitter type="directional"><vector name="direction" value="0, -2, 0"/><rgb name="irradiance" value="3, 3, 3"/></emitter>"#).unwrap();
    assert_eq!(
        l,
        vec![Light::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::splat(3.0)
        }]
    );
    let l = lights(r#"<emitter type="directional"><transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>"#).unwrap();
    let Light::Directional { direction, .. } = l[0] else {
        panic!()
    };
    let want = Mat4::from_rotation_x(90f32.to_radians()).transform_vector3(Vec3::Z);
    assert!((direction - want).length() < 1e-5, "{direction} vs {want}");
    assert!(lights(
        r#"<emitter type="directional"><vector name="direction" value="0, 0, 0"/></emitter>"#
    )
    .is_err());
}

/// Mitsuba `envmap`: the image decoded (an 8-bit PNG is sRGB), times `scale`, under
/// `to_world`; a second environment emitter is refused, or added under `--lenient`.
#[test]
fn envmap_reads_image_scale_and_transform() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../render/tests/scenes/mitsuba/textures");
    let image = cohort_scenes::image_file::read_image(&dir.join("stripes.png"), false).unwrap();
    let envmap = r#"<emitter type="envmap"><string name="filename" value="stripes.png"/><float name="scale" value="2"/><transform name="to_world"><rotate y="1" angle="90"/></transform></emitter>"#;
    let xml = |body: &str| format!("<scene version=\"3.0.0\">\n{body}\n</scene>");
    let scene = load_mitsuba_str(&xml(envmap), &dir).unwrap().scene;
    let map = scene.environment_map.expect("an environment map");
    assert_eq!((map.width, map.height), (image.width, image.height));
    for (got, want) in map.texels.iter().zip(&image.texels) {
        assert!((*got - *want * 2.0).abs().max_element() < 1e-6);
    }
    assert!((map.to_world * Vec3::Z - Vec3::X).length() < 1e-6);
    assert_eq!(scene.environment, Vec3::ZERO);

    let constant =
        r#"<emitter type="constant"><rgb name="radiance" value="0.5, 0.25, 1"/></emitter>"#;
    let both = xml(&format!("{constant}\n{envmap}"));
    let e = load_mitsuba_str(&both, &dir).unwrap_err().to_string();
    assert!(
        e.contains("a second environment emitter") && e.contains(":3:"),
        "{e}"
    );
    let lenient = cohort_scenes::LoadOptions {
        lenient: true,
        ..Default::default()
    };
    let l = cohort_scenes::load_mitsuba_str_with(&both, &dir, &lenient).unwrap();
    let map = l.scene.environment_map.unwrap();
    let want = image.texels[0] * 2.0 + Vec3::new(0.5, 0.25, 1.0);
    assert!((map.texels[0] - want).abs().max_element() < 1e-6);

    let e = load_mitsuba_str(&xml(r#"<emitter type="envmap"/>"#), &dir)
        .unwrap_err()
        .to_string();
    assert!(e.contains("needs a 'filename'") && e.contains(":2:"), "{e}");
    let e = load_mitsuba_str(
        &xml(r#"<emitter type="envmap"><string name="filename" value="nowhere.exr"/></emitter>"#),
        &dir,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("nowhere.exr"), "{e}");
}
