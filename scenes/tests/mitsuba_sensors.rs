//! Sensors read as Mitsuba 3 reads them: the camera rays at film corners equal the rays that
//! Mitsuba 3.9.1's `Sensor.sample_ray` returns for the same sensor (values read off the
//! `mitsuba` package, scalar_rgb).

use cohort_scenes::{load_mitsuba_str, Projection};
use glam::Vec3;

fn sensor(plugin_and_body: &str, w: u32, h: u32) -> cohort_scenes::Camera {
    let xml = format!(
        r#"<scene version="3.0.0"><integrator type="path"/>{plugin_and_body}
<film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film></sensor></scene>"#
    );
    load_mitsuba_str(&xml, ".")
        .unwrap_or_else(|e| panic!("{e}"))
        .scene
        .camera
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn orthographic_rays_are_mitsubas() {
    // mi.load_dict({'type': 'orthographic', 'to_world': look_at(origin=[0, 1, 5],
    // target=[0, 1, 0], up=[0, 1, 0]) @ scale([2, 2, 1]), film w x h}).sample_ray(...)
    let body = r#"<sensor type="orthographic"><transform name="to_world"><scale x="2" y="2"/><lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/></transform>"#;
    for ((w, h), film, origin) in [
        ((32, 32), (0.0, 0.0), Vec3::new(-2.0, 3.0, 4.99)),
        ((32, 32), (1.0, 0.0), Vec3::new(2.0, 3.0, 4.99)),
        ((32, 32), (0.0, 1.0), Vec3::new(-2.0, -1.0, 4.99)),
        ((32, 32), (0.5, 0.5), Vec3::new(0.0, 1.0, 4.99)),
        // A wide film keeps the width and narrows the height: y spans 2 / aspect.
        ((64, 32), (0.0, 0.0), Vec3::new(-2.0, 2.0, 4.99)),
        ((64, 32), (0.0, 1.0), Vec3::new(-2.0, 0.0, 4.99)),
    ] {
        let c = sensor(body, w, h);
        assert_eq!(c.projection, Projection::Orthographic);
        let (o, d) = c.ray(film.0, film.1);
        assert!(
            close(o, origin),
            "{w}x{h} at {film:?}: origin {o} vs Mitsuba's {origin}"
        );
        assert!(close(d, Vec3::new(0.0, 0.0, -1.0)), "direction {d}");
    }
}

#[test]
fn orthographic_sensor_parameters() {
    let c = sensor(
        r#"<sensor type="orthographic"><float name="near_clip" value="0.5"/>"#,
        8,
        8,
    );
    // Rays start on the near-clip plane (Mitsuba's default camera looks down +z).
    assert!(close(c.ray(0.5, 0.5).0, Vec3::new(0.0, 0.0, 0.5)));
    // Orthographic cameras take no field of view: Mitsuba refuses the unused property.
    let xml = r#"<scene version="3.0.0"><integrator type="path"/><sensor type="orthographic">
<float name="fov" value="45"/></sensor></scene>"#;
    let e = load_mitsuba_str(xml, ".").unwrap_err().to_string();
    assert!(e.contains("fov") && e.contains(":2:"), "{e}");
}

#[test]
fn thinlens_rays_are_mitsubas() {
    // mi.load_dict({'type': 'thinlens', 'aperture_radius': 0.2, 'focus_distance': 3,
    // 'fov': 40, film 32 x 32}).sample_ray(0, 0.5, (0.5, 0.5), aperture): the aperture
    // samples (0, 0.5) and (1, 1) map (concentrically) to the disk points (-1, 0) and
    // (sqrt(1/2), sqrt(1/2)). Mitsuba starts rays at the near clip plane (0.01): our origin
    // is that ray's point at z = 0.
    let c = sensor(
        r#"<sensor type="thinlens"><float name="aperture_radius" value="0.2"/><float name="focus_distance" value="3"/><float name="fov" value="40"/>"#,
        32,
        32,
    );
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for (lens, mitsuba_o, mitsuba_d) in [
        (
            glam::Vec2::new(-1.0, 0.0),
            Vec3::new(-0.199333, 0.0, 0.01),
            Vec3::new(0.066519, 0.0, 0.997785),
        ),
        (
            glam::Vec2::new(h, h),
            Vec3::new(0.14095, 0.14095, 0.01),
            Vec3::new(-0.047036, -0.047036, 0.997785),
        ),
    ] {
        let (o, d) = c.ray_through_lens(0.5, 0.5, lens);
        let at_z0 = mitsuba_o - mitsuba_d * (mitsuba_o.z / mitsuba_d.z);
        assert!(
            (o - at_z0).abs().max_element() < 1e-4,
            "origin {o} vs {at_z0}"
        );
        assert!(
            (d - mitsuba_d).abs().max_element() < 1e-5,
            "direction {d} vs {mitsuba_d}"
        );
    }
    // Mitsuba requires an aperture radius and focuses at the far clip plane by default.
    let e = load_mitsuba_str(
        r#"<scene version="3.0.0"><integrator type="path"/><sensor type="thinlens"/></scene>"#,
        ".",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("aperture_radius"), "{e}");
    let c = sensor(
        r#"<sensor type="thinlens"><float name="aperture_radius" value="0.1"/>"#,
        8,
        8,
    );
    assert_eq!(c.focus_distance, 1e4);
}

#[test]
fn crop_windows_render_part_of_the_film_as_mitsuba() {
    // Film 64 x 48, crop 32 x 32 at (22, 4); Mitsuba's sample_ray maps [0, 1]^2 onto the
    // crop window (its default camera: at the origin looking down +z, camera x left).
    let film = r#"<film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>
<integer name="crop_offset_x" value="22"/><integer name="crop_offset_y" value="4"/>
<integer name="crop_width" value="32"/><integer name="crop_height" value="32"/></film>"#;
    let load = |sensor: &str| {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="path"/>{sensor}{film}</sensor></scene>"#
        );
        load_mitsuba_str(&xml, ".")
            .unwrap_or_else(|e| panic!("{e}"))
            .scene
            .camera
    };
    let c = load(r#"<sensor type="perspective"><float name="fov" value="50"/>"#);
    assert_eq!((c.width, c.height), (32, 32));
    for (film_point, mitsuba_d) in [
        ((0.0, 0.0), Vec3::new(0.138551, 0.277103, 0.950798)),
        ((1.0, 1.0), Vec3::new(-0.301136, -0.164256, 0.939328)),
        ((0.5, 0.5), Vec3::new(-0.0869539, 0.0579693, 0.994524)),
    ] {
        let d = c.ray_direction(film_point.0, film_point.1);
        assert!(
            close(d, mitsuba_d),
            "{film_point:?}: {d} vs Mitsuba's {mitsuba_d}"
        );
    }
    let c = load(r#"<sensor type="orthographic">"#);
    for (film_point, mitsuba_o) in [
        ((0.0, 0.0), Vec3::new(0.3125, 0.625, 0.01)),
        ((1.0, 1.0), Vec3::new(-0.6875, -0.375, 0.01)),
    ] {
        let (o, _) = c.ray(film_point.0, film_point.1);
        assert!(
            close(o, mitsuba_o),
            "{film_point:?}: {o} vs Mitsuba's {mitsuba_o}"
        );
    }
    // A window that leaves the film is a located error.
    let xml = r#"<scene version="3.0.0"><integrator type="path"/><sensor type="perspective">
<film type="hdrfilm"><integer name="width" value="8"/><integer name="crop_offset_x" value="4"/><integer name="crop_width" value="8"/></film></sensor></scene>"#;
    let e = load_mitsuba_str(xml, ".").unwrap_err().to_string();
    assert!(e.contains("crop window") && e.contains(":2:"), "{e}");
}
