//! Textures as Mitsuba reads them: `checkerboard` and `bitmap` on a BSDF's colour, and the
//! texture coordinates of every shape, against what the `mitsuba` package (3.9.1,
//! scalar_rgb) reports for the same ray (`scene.ray_intersect(ray).uv`).

use cohort_scenes::texture::{Filter, Texture, Wrap};
use cohort_scenes::{load_mitsuba, load_mitsuba_str, Scene};
use glam::{Vec2, Vec3};

fn scene(shape: &str) -> Scene {
    let xml = format!(r#"<scene version="3.0.0"><integrator type="path"/>{shape}</scene>"#);
    load_mitsuba_str(&xml, ".").unwrap().scene
}

/// The interpolated texture coordinates where the ray (o, d) first hits `s`.
fn uv_at(s: &Scene, o: Vec3, d: Vec3) -> Vec2 {
    let uvs = s.triangles.uvs.as_ref().expect("texture coordinates");
    let mut best = (f32::INFINITY, Vec2::ZERO);
    for i in 0..s.triangles.len() {
        let [a, b, c] = s.triangles.vertices(i);
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let t0 = o - a;
        let u = t0.dot(p) / det;
        let q = t0.cross(e1);
        let v = d.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < best.0 {
            let w = &uvs[3 * i..3 * i + 3];
            best = (t, w[0] * (1.0 - u - v) + w[1] * u + w[2] * v);
        }
    }
    assert!(best.0.is_finite(), "the ray misses");
    best.1
}

#[test]
fn texture_coordinates_of_every_shape_are_mitsubas() {
    let dir = std::env::temp_dir().join(format!("cohort-uv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.1 0.7\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0.1 0.2\n1 0 0 0.9 0.2\n0 1 0 0.1 0.7\n3 0 1 2\n",
    )
    .unwrap();
    let file = |shape: &str| {
        let xml = format!(r#"<scene version="3.0.0"><integrator type="path"/>{shape}</scene>"#);
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        load_mitsuba(&path).unwrap().scene
    };
    let z = Vec3::NEG_Z;
    // (scene, ray origin, direction, Mitsuba's uv, tolerance)
    let cases: Vec<(Scene, Vec3, Vec3, Vec2, f32)> = vec![
        (
            scene(r#"<shape type="rectangle"/>"#),
            Vec3::new(0.5, 0.25, 1.0),
            z,
            Vec2::new(0.75, 0.625),
            1e-6,
        ),
        // An OBJ's v is flipped (flip_tex_coords), a PLY's is not.
        (
            file(r#"<shape type="obj"><string name="filename" value="tri.obj"/></shape>"#),
            Vec3::new(0.25, 0.25, 1.0),
            z,
            Vec2::new(0.3, 0.675),
            1e-6,
        ),
        (
            file(
                r#"<shape type="obj"><string name="filename" value="tri.obj"/><boolean name="flip_tex_coords" value="false"/></shape>"#,
            ),
            Vec3::new(0.25, 0.25, 1.0),
            z,
            Vec2::new(0.3, 0.325),
            1e-6,
        ),
        (
            file(r#"<shape type="ply"><string name="filename" value="tri.ply"/></shape>"#),
            Vec3::new(0.25, 0.25, 1.0),
            z,
            Vec2::new(0.3, 0.325),
            1e-6,
        ),
        // Tessellated analytic shapes: close to Mitsuba's exact coordinates.
        (
            scene(r#"<shape type="sphere"/>"#),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::NEG_Y,
            Vec2::new(0.25, 0.5),
            2e-3,
        ),
        (
            scene(r#"<shape type="sphere"/>"#),
            Vec3::new(0.3, 0.1, 2.0),
            z,
            Vec2::new(0.051_208_2, 0.102_416),
            5e-3,
        ),
        (
            scene(r#"<shape type="disk"/>"#),
            Vec3::new(0.0, 0.5, 1.0),
            z,
            Vec2::new(0.5, 0.25),
            2e-3,
        ),
        (
            scene(r#"<shape type="cylinder"/>"#),
            Vec3::new(0.0, 2.0, 0.25),
            Vec3::NEG_Y,
            Vec2::new(0.25, 0.25),
            2e-3,
        ),
        // Each face of the cube.
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(0.5, 0.25, 2.0),
            z,
            Vec2::new(0.625, 0.75),
            1e-6,
        ),
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(0.5, 0.25, -2.0),
            Vec3::Z,
            Vec2::new(0.375, 0.75),
            1e-6,
        ),
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(2.0, 0.5, 0.25),
            Vec3::NEG_X,
            Vec2::new(0.75, 0.375),
            1e-6,
        ),
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(-2.0, 0.5, 0.25),
            Vec3::X,
            Vec2::new(0.75, 0.625),
            1e-6,
        ),
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(0.5, 2.0, 0.25),
            Vec3::NEG_Y,
            Vec2::new(0.25, 0.375),
            1e-6,
        ),
        (
            scene(r#"<shape type="cube"/>"#),
            Vec3::new(0.5, -2.0, 0.25),
            Vec3::Y,
            Vec2::new(0.625, 0.75),
            1e-6,
        ),
    ];
    for (i, (s, o, d, mitsuba, tol)) in cases.iter().enumerate() {
        let uv = uv_at(s, *o, *d);
        assert!(
            (uv - *mitsuba).abs().max_element() <= *tol,
            "case {i}: {uv} vs Mitsuba's {mitsuba}"
        );
    }
}

#[test]
fn textures_are_read_as_mitsuba_reads_them() {
    let s = scene(
        r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance"><rgb name="color0" value="1, 0, 0"/><transform name="to_uv"><scale x="2" y="3"/><translate x="0.5"/></transform></texture></bsdf></shape>"#,
    );
    assert_eq!(s.materials[0].texture, Some(0));
    let Texture::Checkerboard {
        color0,
        color1,
        to_uv,
    } = &s.textures[0]
    else {
        panic!("not a checkerboard")
    };
    assert_eq!((*color0, *color1), (Vec3::X, Vec3::splat(0.2)));
    assert_eq!(to_uv.apply(Vec2::new(1.0, 1.0)), Vec2::new(2.5, 3.0));

    let dir = std::env::temp_dir().join(format!("cohort-tex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A 2 x 1 8-bit PNG: sRGB 255 and 128.
    let mut png_bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut png_bytes, 2, 1);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.write_header()
            .unwrap()
            .write_image_data(&[255, 255, 255, 128, 128, 128])
            .unwrap();
    }
    std::fs::write(dir.join("t.png"), &png_bytes).unwrap();
    let load = |params: &str| {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="t.png"/>{params}</texture></bsdf></shape></scene>"#
        );
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        load_mitsuba(&path)
    };
    let s = load("").unwrap().scene;
    let Texture::Bitmap {
        width,
        height,
        texels,
        filter,
        wrap,
        ..
    } = &s.textures[0]
    else {
        panic!("not a bitmap")
    };
    assert_eq!(
        (*width, *height, *filter, *wrap),
        (2, 1, Filter::Bilinear, Wrap::Repeat)
    );
    // sRGB 128 is linear 0.2158605.
    assert!((texels[1].x - 0.215_860_5).abs() < 1e-5, "{}", texels[1]);
    let s = load(r#"<boolean name="raw" value="true"/><string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/>"#)
        .unwrap()
        .scene;
    let Texture::Bitmap {
        texels,
        filter,
        wrap,
        ..
    } = &s.textures[0]
    else {
        panic!("not a bitmap")
    };
    assert_eq!((*filter, *wrap), (Filter::Nearest, Wrap::Mirror));
    assert!((texels[1].x - 128.0 / 255.0).abs() < 1e-6);
    for (bad, needle) in [
        (r#"<string name="wrap_mode" value="tile"/>"#, "wrap_mode"),
        (
            r#"<string name="filter_type" value="cubic"/>"#,
            "filter_type",
        ),
    ] {
        let e = load(bad).unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }
    let xml = r#"<scene version="3.0.0"><integrator type="path"/><shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="missing.png"/></texture></bsdf></shape></scene>"#;
    let path = dir.join("missing.xml");
    std::fs::write(&path, xml).unwrap();
    let e = load_mitsuba(&path).unwrap_err().to_string();
    assert!(e.contains("image file 'missing.png' not found"), "{e}");
    // Formats other than PNG, JPEG, BMP, OpenEXR and HDR are refused at the texture, by
    // name; a broken file of a supported format says what is wrong with it.
    std::fs::write(dir.join("t.tga"), b"not really").unwrap();
    std::fs::write(&path, xml.replace("missing.png", "t.tga")).unwrap();
    let e = load_mitsuba(&path).unwrap_err().to_string();
    assert!(e.contains("'tga' is not supported"), "{e}");
    std::fs::write(dir.join("t.jpg"), b"not really").unwrap();
    std::fs::write(&path, xml.replace("missing.png", "t.jpg")).unwrap();
    let e = load_mitsuba(&path).unwrap_err().to_string();
    assert!(e.contains("t.jpg': cannot read it as JPEG"), "{e}");
}

/// Mitsuba `mask`: its opacity as a number, a colour (its luminance) or a texture; a
/// checkerboard opacity follows Mitsuba's `eval_1`, which takes `color0` where the parities
/// differ; exactly one nested BSDF.
#[test]
fn masks_are_read_as_mitsuba_reads_them() {
    use cohort_scenes::{Bsdf, Mask};
    let m = |opacity: &str| {
        let s = scene(&format!(
            r#"<shape type="rectangle"><bsdf type="mask">{opacity}<bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf></shape>"#
        ));
        (s.materials[0], s.textures)
    };
    let (mat, _) = m(r#"<float name="opacity" value="0.3"/>"#);
    assert_eq!(
        mat.mask,
        Some(Mask {
            opacity: 0.3,
            texture: None
        })
    );
    assert!(mat.two_sided);
    assert_eq!(
        mat.bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.5)
        }
    );
    let (mat, _) = m("");
    assert_eq!(mat.mask.unwrap().opacity, 0.5);
    let (mat, _) = m(r#"<rgb name="opacity" value="1, 0, 0"/>"#);
    assert!((mat.mask.unwrap().opacity - 0.212_671).abs() < 1e-6);
    let (mat, textures) = m(
        r#"<texture type="checkerboard" name="opacity"><float name="color0" value="0.9"/><float name="color1" value="0.1"/></texture>"#,
    );
    let t = &textures[mat.mask.unwrap().texture.unwrap() as usize];
    // u, v in the same half: color0 for a colour, color1 for an opacity (Mitsuba's eval_1).
    assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Vec3::splat(0.1));
    assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Vec3::splat(0.9));
    for (bad, needle) in [
        (r#"<bsdf type="mask"/>"#, "nested"),
        (
            r#"<bsdf type="mask"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "one nested",
        ),
    ] {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="rectangle">{bad}</shape></scene>"#
        );
        let e = load_mitsuba_str(&xml, ".").unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }
}

/// `normalmap` and `bumpmap` wrap one BSDF with their texture and options; a `twosided`
/// around the map applies it per side; malformed ones are located errors.
#[test]
fn normal_and_bump_maps_are_read_as_mitsuba_reads_them() {
    use cohort_scenes::{Bsdf, PerturbKind};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../render/tests/scenes/mitsuba/textures");
    let load = |bsdf: &str| {
        load_mitsuba_str(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n{bsdf}\n</shape>\n</scene>"
            ),
            &dir,
        )
    };
    let s = load(r#"<bsdf type="normalmap"><texture type="bitmap" name="normalmap"><string name="filename" value="stripes.png"/><boolean name="raw" value="true"/></texture><bsdf type="diffuse"/></bsdf>"#)
        .unwrap()
        .scene;
    let m = s.materials[0];
    let p = m.perturb.expect("a normal map");
    assert_eq!(p.kind, PerturbKind::Normal);
    assert!(p.shadowing && p.flip_invalid && !p.per_side);
    assert!(matches!(
        s.textures[p.texture as usize],
        Texture::Bitmap { .. }
    ));
    assert!(matches!(m.bsdf, Bsdf::Diffuse { .. }));

    let s = load(r#"<bsdf type="twosided"><bsdf type="bumpmap"><float name="scale" value="0.25"/><boolean name="use_shadowing_function" value="false"/><texture type="bitmap"><string name="filename" value="stripes.png"/></texture><bsdf type="roughplastic"/></bsdf></bsdf>"#)
        .unwrap()
        .scene;
    let m = s.materials[0];
    let p = m.perturb.expect("a bump map");
    assert_eq!(p.kind, PerturbKind::Bump { scale: 0.25 });
    assert!(!p.shadowing && p.per_side && m.two_sided);
    assert!(matches!(m.bsdf, Bsdf::RoughPlastic { .. }));

    // A constant normal is a one-colour texture.
    let s = load(r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/><bsdf type="diffuse"/></bsdf>"#)
        .unwrap()
        .scene;
    let p = s.materials[0].perturb.unwrap();
    assert_eq!(
        s.textures[p.texture as usize].eval(Vec2::new(0.3, 0.7)),
        Vec3::new(0.5, 0.5, 1.0)
    );

    for (bsdf, message) in [
        (
            r#"<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>"#,
            "needs a nested <texture>",
        ),
        (
            r#"<bsdf type="bumpmap"><texture type="checkerboard"/><bsdf type="diffuse"/></bsdf>"#,
            "no gradient for 'checkerboard'",
        ),
        (
            r#"<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>"#,
            "needs a 'normalmap'",
        ),
        (
            r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/></bsdf>"#,
            "needs a nested <bsdf>",
        ),
    ] {
        let e = load(bsdf).unwrap_err().to_string();
        assert!(e.contains(message) && e.contains(":3"), "{bsdf}: {e}");
    }
}

/// `mesh_attribute`: a PLY's r, g, b reach the triangles' corners as `vertex_color`; a mesh
/// without the attribute, a name Mitsuba refuses, or the texture where an image is needed
/// are errors.
#[test]
fn vertex_colors_are_read_as_mitsuba_reads_them() {
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../render/tests/scenes/mitsuba");
    let shape = |mesh: &str, attribute: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<shape type=\"{mesh}\">\n<string name=\"filename\" value=\"meshes/{}\"/>\n<bsdf type=\"diffuse\"><texture type=\"mesh_attribute\" name=\"reflectance\"><string name=\"name\" value=\"{attribute}\"/><float name=\"scale\" value=\"2\"/></texture></bsdf>\n</shape>\n</scene>",
            if mesh == "ply" { "colored.ply" } else { "textured_quad.obj" }
        )
    };
    let s = load_mitsuba_str(&shape("ply", "vertex_color"), &dir)
        .unwrap()
        .scene;
    let (name, colors) = &s.triangles.attributes[0];
    assert_eq!(name, "vertex_color");
    assert_eq!(colors.len(), 3 * s.triangles.len());
    // The first grid triangle's first corner: x = -1, y = -1 in the file: (0.9, 0, 0).
    assert!(
        (colors[0] - Vec3::new(0.9, 0.0, 0.0)).length() < 1e-6,
        "{}",
        colors[0]
    );
    let t = s.materials[0].texture.unwrap();
    assert!(
        matches!(&s.textures[t as usize], Texture::MeshAttribute { name, scale } if name == "vertex_color" && *scale == 2.0)
    );

    let e = load_mitsuba_str(&shape("obj", "vertex_color"), &dir).unwrap_err();
    assert!(
        e.message.contains("no mesh attribute 'vertex_color'")
            && e.location.line_number() == Some(2),
        "{e}"
    );
    let e = load_mitsuba_str(&shape("ply", "face_normal"), &dir).unwrap_err();
    assert!(
        e.message.contains("no mesh attribute 'face_normal'") && e.message.contains("vertex_color"),
        "{e}"
    );
    let e = load_mitsuba_str(&shape("ply", "color"), &dir).unwrap_err();
    assert!(e.message.contains("start with 'vertex_' or 'face_'"), "{e}");
    let e = load_mitsuba_str(
        "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n<emitter type=\"area\"><texture type=\"mesh_attribute\" name=\"radiance\"><string name=\"name\" value=\"vertex_color\"/></texture></emitter>\n</shape>\n</scene>",
        &dir,
    )
    .unwrap_err();
    assert!(
        e.message.contains("no mesh attribute 'vertex_color'")
            && e.location.line_number() == Some(2),
        "{e}"
    );
}

/// Mitsuba's other mesh attributes: per-face colours (a polygon's for each triangle of its
/// fan), one-channel attributes (`{prefix}_x`) read as grey or as a number (a mask's
/// opacity, a blend's weight), and the errors Mitsuba's scalar variants raise: a
/// three-channel attribute read as a number.
#[test]
fn face_and_one_channel_attributes() {
    let dir = std::env::temp_dir().join(format!("cohort-attributes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("quad.ply"),
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty float weight_x\nelement face 2\nproperty list uchar int vertex_indices\nproperty float red\nproperty float green\nproperty float blue\nend_header\n\
         0 0 0 0.25\n1 0 0 0.5\n1 1 0 0.75\n0 1 0 1\n2 0 0 0\n\
         4 0 1 2 3 0.1 0.2 0.3\n3 1 4 2 0.4 0.5 0.6\n",
    )
    .unwrap();
    let load = |bsdf: &str| {
        load_mitsuba_str(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"ply\">\n<string name=\"filename\" value=\"quad.ply\"/>\n{bsdf}\n</shape>\n</scene>"
            ),
            &dir,
        )
    };
    let attribute = |name: &str| {
        format!("<texture type=\"mesh_attribute\" name=\"reflectance\"><string name=\"name\" value=\"{name}\"/></texture>")
    };
    let s = load(&format!(
        "<bsdf type=\"diffuse\">{}</bsdf>",
        attribute("face_color")
    ))
    .unwrap()
    .scene;
    assert_eq!(s.triangles.len(), 3);
    let faces = &s
        .triangles
        .attributes
        .iter()
        .find(|(n, _)| n == "face_color")
        .unwrap()
        .1;
    let quad = Vec3::new(0.1, 0.2, 0.3);
    let triangle = Vec3::new(0.4, 0.5, 0.6);
    assert_eq!(
        faces[..6],
        [quad; 6],
        "the quad's colour for both of its triangles"
    );
    assert_eq!(faces[6..], [triangle; 3]);
    let weights = &s
        .triangles
        .attributes
        .iter()
        .find(|(n, _)| n == "vertex_weight")
        .unwrap()
        .1;
    assert_eq!(
        weights[..3],
        [Vec3::splat(0.25), Vec3::splat(0.5), Vec3::splat(0.75)]
    );

    // One channel, as a number: a mask's opacity and a blend's weight.
    let opacity = attribute("vertex_weight").replace("reflectance", "opacity");
    let s = load(&format!(
        "<bsdf type=\"mask\">{opacity}<bsdf type=\"diffuse\"/></bsdf>"
    ))
    .unwrap()
    .scene;
    let mask = s.materials[0].mask.unwrap();
    assert!(
        matches!(&s.textures[mask.texture.unwrap() as usize], Texture::MeshAttribute { name, .. } if name == "vertex_weight")
    );
    let weight = attribute("vertex_weight").replace("reflectance", "weight");
    load(&format!("<bsdf type=\"blendbsdf\">{weight}<bsdf type=\"diffuse\"/><bsdf type=\"conductor\"/></bsdf>")).unwrap();

    // Three channels read as a number: Mitsuba's eval_1 throws.
    let opacity = attribute("face_color").replace("reflectance", "opacity");
    let e = load(&format!(
        "<bsdf type=\"mask\">{opacity}<bsdf type=\"diffuse\"/></bsdf>"
    ))
    .unwrap_err();
    assert!(
        e.message.contains("has 3 channels")
            && e.message.contains("read as a number")
            && e.location.line_number() == Some(2),
        "{e}"
    );
    // The second BSDF of a blend is checked too.
    let e = load(&format!(
        "<bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.5\"/><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\">{}</bsdf></bsdf>",
        attribute("face_weight")
    ))
    .unwrap_err();
    assert!(e.message.contains("no mesh attribute 'face_weight'"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `blendbsdf` weights given as textures: their luminance per hit (a checkerboard read as a
/// number, as Mitsuba's `eval_1` reads it); a textured weight with the nested blend first
/// and a weight outside [0, 1] are errors.
#[test]
fn textured_blend_weights_are_read() {
    let load = |bsdf: &str| {
        load_mitsuba_str(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n{bsdf}\n</shape>\n</scene>"
            ),
            ".",
        )
    };
    let s = load(r#"<bsdf type="blendbsdf"><texture type="checkerboard" name="weight"/><bsdf type="diffuse"/><bsdf type="roughplastic"/></bsdf>"#)
        .unwrap()
        .scene;
    let b = s.materials.iter().find_map(|m| m.blend).expect("a blend");
    let t = b.texture.expect("a textured weight");
    // Read as a number, the checkerboard's colours swap (Mitsuba's eval_1).
    assert!(
        matches!(s.textures[t as usize], Texture::Checkerboard { color0, .. } if color0 == Vec3::splat(0.2))
    );
    let e = load(r#"<bsdf type="blendbsdf"><texture type="checkerboard" name="weight"/><bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf><bsdf type="diffuse"/></bsdf>"#)
        .unwrap_err();
    assert!(e.message.contains("nest the blend second"), "{e}");
    let e = load(r#"<bsdf type="blendbsdf"><float name="weight" value="1.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#)
        .unwrap_err();
    assert!(
        e.message.contains("must be in [0, 1]") && e.location.line_number() == Some(3),
        "{e}"
    );
}

/// Mitsuba's `rawconstant`: a float or a vector, as given (Mitsuba's own test scenes use one
/// as an identity normal map).
#[test]
fn rawconstant_textures_are_their_value() {
    let load = |bsdf: &str| {
        load_mitsuba_str(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n{bsdf}\n</shape>\n</scene>"
            ),
            ".",
        )
    };
    let s = load(r#"<bsdf type="normalmap"><texture name="normalmap" type="rawconstant"><vector name="value" value="0.5, 0.5, 1.0"/></texture><bsdf type="diffuse"/></bsdf>"#)
        .unwrap()
        .scene;
    let p = s.materials[0].perturb.expect("a normal map");
    assert_eq!(
        s.textures[p.texture as usize].mean(),
        Vec3::new(0.5, 0.5, 1.0)
    );
    let s = load(r#"<bsdf type="diffuse"><texture name="reflectance" type="rawconstant"><float name="value" value="0.25"/></texture></bsdf>"#)
        .unwrap()
        .scene;
    assert!(
        matches!(s.materials[0].bsdf, cohort_scenes::Bsdf::Diffuse { reflectance } if reflectance == Vec3::splat(0.25))
    );
    let e = load(r#"<bsdf type="diffuse"><texture name="reflectance" type="rawconstant"/></bsdf>"#)
        .unwrap_err();
    assert!(e.message.contains("needs a 'value'"), "{e}");
}

/// `principled`'s numbers as textures (Mitsuba reads each with `get_texture` and `eval_1`):
/// each textured parameter's texture (a checkerboard read as a number: its colours swap),
/// its mean luminance standing for it; a constant texture is its value; out of range as a
/// number is still an error.
#[test]
fn principled_parameters_as_textures() {
    let load = |bsdf: &str| {
        load_mitsuba_str(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n{bsdf}\n</shape>\n</scene>"
            ),
            ".",
        )
    };
    let s = load(r#"<bsdf type="principled"><texture type="checkerboard" name="metallic"><float name="color0" value="0.7"/><float name="color1" value="0.1"/></texture><texture type="uniform" name="sheen"><float name="value" value="0.3"/></texture><texture type="checkerboard" name="anisotropic"/></bsdf>"#)
        .unwrap()
        .scene;
    let cohort_scenes::Bsdf::Principled(p) = s.materials[0].bsdf else {
        panic!("not principled")
    };
    let metallic = cohort_scenes::Principled::TEXTURED
        .iter()
        .position(|n| *n == "metallic")
        .unwrap();
    let t = p.textures[metallic].expect("a textured metallic");
    assert!(
        matches!(s.textures[t as usize], Texture::Checkerboard { color0, .. } if color0 == Vec3::splat(0.1))
    );
    assert!((p.metallic - 0.4).abs() < 1e-6, "{}", p.metallic);
    assert!((p.sheen - 0.3).abs() < 1e-6 && p.textures[5].is_none());
    assert!(p.textures[1].is_some() && p.reads_tex_coords());
    let block = p.gpu_block(&cohort_scenes::texture::gpu_texture_starts(&s.textures));
    assert_eq!(block[0][1], 1.0, "a textured anisotropy turns the frame");
    assert_ne!(block[4][2].to_bits(), 0, "metallic's texture header");
    let e =
        load(r#"<bsdf type="principled"><float name="metallic" value="1.5"/></bsdf>"#).unwrap_err();
    assert!(e.message.contains("must lie in [0, 1]"), "{e}");
}

/// An `area` emitter's `radiance` as a texture (Mitsuba evaluates it per point): the
/// material keeps the texture and its mean colour (which weighs the light among the others).
#[test]
fn area_emitter_radiance_texture() {
    let s = load_mitsuba_str(
        r#"<scene version="3.0.0"><shape type="rectangle"><emitter type="area"><texture type="checkerboard" name="radiance"><rgb name="color0" value="4, 2, 1"/><rgb name="color1" value="0, 0, 0"/></texture></emitter></shape></scene>"#,
        ".",
    )
    .unwrap()
    .scene;
    let m = &s.materials[0];
    let t = m.emission_texture.expect("a textured radiance");
    assert!(matches!(
        s.textures[t as usize],
        Texture::Checkerboard { color0, .. } if color0 == Vec3::new(4.0, 2.0, 1.0)
    ));
    assert_eq!(m.emission, Some(Vec3::new(2.0, 1.0, 0.5)));
    assert_ne!(s.gpu_materials()[0].emission_texture, 0);
}
