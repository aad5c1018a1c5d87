//! The Mitsuba loader against a record of what mitsuba 3.9.1 (scalar_rgb, `mi.load_file`) did with
//! the same files: each case is a scene file (plus the helper files below), Mitsuba's outcome
//! (loaded, or the end of its error message), and the loader must agree (strictly), except for
//! the deliberate differences listed with their reason. The record was made by loading every
//! case with mitsuba 3.9.1 from Python; re-run that to extend it.

use std::path::Path;

/// (name, scene file, Mitsuba's outcome: None = loaded, Some(end of its error message)).
const CASES: &[(&str, &str, Option<&str>)] = &[
    (
        "empty",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>

</scene>"#,
        None,
    ),
    (
        "env_only",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="constant"/>
</scene>"#,
        None,
    ),
    (
        "path_ok",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<path value="extra"/><shape type="obj"><string name="filename" value="a.obj"/></shape>
</scene>"#,
        None,
    ),
    (
        "path_missing",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<path value="nosuch"/>
</scene>"#,
        Some(
            r#"cpp:451] Error while loading aux/path_missing.xml (line 4, col 2): <path>: folder "nosuch" not found"#,
        ),
    ),
    (
        "path_nested",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><path value="extra"/></shape>
</scene>"#,
        Some(
            r#"51] Error while loading aux/path_nested.xml (line 4, col 23): <path>: path can only be child of root"#,
        ),
    ),
    (
        "include_leaf",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<include filename="leaf.xml"/>
</scene>"#,
        None,
    ),
    (
        "include_twice",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<include filename="leaf.xml"/><include filename="leaf.xml"/>
</scene>"#,
        None,
    ),
    (
        "include_bsdf",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><include filename="bsdf.xml"/></shape>
</scene>"#,
        None,
    ),
    (
        "include_missing",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<include filename="nope.xml"/>
</scene>"#,
        Some(
            r#"451] Error while loading aux/include_missing.xml (line 4, col 2): included file "nope.xml" not found"#,
        ),
    ),
    (
        "include_cycle",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<include filename="cyc1.xml"/>
</scene>"#,
        Some(r#"[parser.cpp:1073] Exceeded maximum include recursion depth of 15"#),
    ),
    (
        "ref_forward",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><ref id="b"/></shape><bsdf type="diffuse" id="b"/>
</scene>"#,
        None,
    ),
    (
        "ref_unresolved",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><ref id="zz"/></shape>
</scene>"#,
        Some(
            r#"col 2): unresolved reference to "zz" in property "_arg_0". Make sure the object with id="zz" exists."#,
        ),
    ),
    (
        "dup_id",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<bsdf type="diffuse" id="b"/><bsdf type="diffuse" id="b"/>
</scene>"#,
        Some(
            r#"aux/dup_id.xml (line 4, col 31): duplicate ID: "b" (previous was at aux/dup_id.xml (line 4, col 2))"#,
        ),
    ),
    (
        "ref_cycle",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<bsdf type="twosided" id="a"><ref id="b"/></bsdf><bsdf type="twosided" id="b"><ref id="a"/></bsdf>
</scene>"#,
        Some(
            r#"451] Error while loading aux/ref_cycle.xml (line 4, col 2): circular reference detected: a -> b -> a"#,
        ),
    ),
    (
        "twosided_ref",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<bsdf type="diffuse" id="b"/><shape type="sphere"><bsdf type="twosided"><ref id="b"/></bsdf></shape>
</scene>"#,
        None,
    ),
    (
        "texture_srgb_ref",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<texture type="srgb" id="t"><rgb name="color" value="0.2"/></texture><shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>
</scene>"#,
        None,
    ),
    (
        "texture_checker",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<texture type="checkerboard" id="t"/><shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>
</scene>"#,
        None,
    ),
    (
        "emitter_ref",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="area" id="e"/><shape type="sphere"><ref id="e"/></shape>
</scene>"#,
        None,
    ),
    (
        "emitter_shared",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="area" id="e"/><shape type="sphere"><ref id="e"/></shape><shape type="sphere"><ref id="e"/></shape>
</scene>"#,
        Some(
            r#"ate shape plugin of type "sphere": [Endpoint] An endpoint can be only be attached to a single shape."#,
        ),
    ),
    (
        "top_ref_shape",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere" id="s"/><ref id="s"/>
</scene>"#,
        None,
    ),
    (
        "moment_without_nested_integrator",
        r#"<scene version="3.0.0">

<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<integrator type="moment"></integrator>
</scene>"#,
        None,
    ),
    (
        "unknown_bsdf",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="nosuch"/></shape>
</scene>"#,
        Some(
            r#"23): failed to instantiate bsdf plugin of type "nosuch": [PluginManager] Plugin "nosuch" not found!"#,
        ),
    ),
    (
        "unknown_top_bsdf",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<bsdf type="nosuch" id="x"/>
</scene>"#,
        Some(
            r#"l 2): failed to instantiate bsdf plugin of type "nosuch": [PluginManager] Plugin "nosuch" not found!"#,
        ),
    ),
    (
        "unknown_shape",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="nosuch"/>
</scene>"#,
        Some(
            r#"2): failed to instantiate shape plugin of type "nosuch": [PluginManager] Plugin "nosuch" not found!"#,
        ),
    ),
    (
        "unknown_emitter",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="nosuch"/>
</scene>"#,
        Some(
            r#"): failed to instantiate emitter plugin of type "nosuch": [PluginManager] Plugin "nosuch" not found!"#,
        ),
    ),
    (
        "unknown_texture",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<texture type="nosuch"/>
</scene>"#,
        Some(
            r#"): failed to instantiate texture plugin of type "nosuch": [PluginManager] Plugin "nosuch" not found!"#,
        ),
    ),
    (
        "unknown_tag",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<wibble/>
</scene>"#,
        Some(
            r#"while loading aux/unknown_tag.xml (line 4, col 2): encountered an unsupported XML element: <wibble>"#,
        ),
    ),
    (
        "unknown_attr",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere" foo="1"/>
</scene>"#,
        Some(
            r#"or while loading aux/unknown_attr.xml (line 4, col 2): unexpected attribute "foo" in element <shape>"#,
        ),
    ),
    (
        "unused_prop",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"><float name="roughness" value="1"/></bsdf></shape>
</scene>"#,
        Some(r#"- float "roughness": 1"#),
    ),
    (
        "dup_prop",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><float name="radius" value="1"/><float name="radius" value="2"/></shape>
</scene>"#,
        Some(
            r#"451] Error while loading aux/dup_prop.xml (line 4, col 55): could not parse floating point value "2""#,
        ),
    ),
    (
        "two_bsdfs",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"/><bsdf type="diffuse"/></shape>
</scene>"#,
        Some(
            r#"e shape plugin of type "sphere": [Shape] Only a single BSDF child object can be specified per shape."#,
        ),
    ),
    (
        "two_envs",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="constant"/><emitter type="constant"/>
</scene>"#,
        Some(
            r#"tiate scene plugin of type "scene": [Scene] Only one environment emitter can be specified per scene."#,
        ),
    ),
    (
        "default_ok",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<default name="r" value="2"/><shape type="sphere"><float name="radius" value="$r"/></shape>
</scene>"#,
        None,
    ),
    (
        "default_late",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><float name="radius" value="$r"/></shape><default name="r" value="2"/>
</scene>"#,
        Some(
            r#"[parser.cpp:451] Error while loading aux/default_late.xml (line 4, col 23): undefined parameter: $r"#,
        ),
    ),
    (
        "escaped",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere" id="a\$b"/>
</scene>"#,
        None,
    ),
    (
        "point_missing_z",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><point name="center" x="1" y="2"/></shape>
</scene>"#,
        Some(
            r#"or while loading aux/point_missing_z.xml (line 4, col 23): missing required attribute "z" in <point>"#,
        ),
    ),
    (
        "translate_value1",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><transform name="to_world"><translate value="1"/></transform></shape>
</scene>"#,
        None,
    ),
    (
        "shear",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><transform name="to_world"><shear/></transform></shape>
</scene>"#,
        Some(
            r#"1] Error while loading aux/shear.xml (line 4, col 23): unexpected <shear> element inside <transform>"#,
        ),
    ),
    (
        "top_translate",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<translate x="1"/>
</scene>"#,
        Some(
            r#"nslate.xml (line 4, col 2): transform operation <translate> can only appear inside a <transform> tag"#,
        ),
    ),
    (
        "top_float",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<float name="x" value="1"/>
</scene>"#,
        Some(r#"- float "x": 1"#),
    ),
    (
        "rr0",
        r#"<scene version="3.0.0">
<integrator type="path"><integer name="rr_depth" value="0"/></integrator>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>

</scene>"#,
        Some(
            r#"r plugin of type "path": [MonteCarloIntegrator] "rr_depth" must be set to a value greater than zero!"#,
        ),
    ),
    (
        "max_depth_m2",
        r#"<scene version="3.0.0">
<integrator type="path"><integer name="max_depth" value="-2"/></integrator>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>

</scene>"#,
        Some(
            r#"ugin of type "path": [MonteCarloIntegrator] "max_depth" must be set to -1 (infinite) or a value >= 0"#,
        ),
    ),
    (
        "rgb2",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.1 0.2"/></bsdf></shape>
</scene>"#,
        Some(
            r#"rser.cpp:451] Error while loading aux/rgb2.xml (line 4, col 44): could not parse RGB value "0.1 0.2""#,
        ),
    ),
    (
        "spectrum3",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.1 0.2 0.3"/></bsdf></shape>
</scene>"#,
        Some(
            r#"line 4, col 44): [properties.cpp:839] Invalid spectrum value "0.1" (expected wavelength:value pairs)"#,
        ),
    ),
    (
        "spectrum_sampled",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="constant"><spectrum name="radiance" value="400:1, 500:2"/></emitter>
</scene>"#,
        None,
    ),
    (
        "twosided_dielectric",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="twosided"><bsdf type="dielectric"/></bsdf></shape>
</scene>"#,
        Some(
            r#"in of type "twosided": [TwoSidedBRDF] Only materials without a transmission component can be nested!"#,
        ),
    ),
    (
        "twosided_3",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf></shape>
</scene>"#,
        Some(
            r#"nstantiate bsdf plugin of type "twosided": [TwoSidedBRDF] At most two nested BSDFs can be specified!"#,
        ),
    ),
    (
        "ior_name",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="water"/></bsdf></shape>
</scene>"#,
        None,
    ),
    (
        "ior_bad",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="zz"/></bsdf></shape>
</scene>"#,
        Some(
            r#"er ice, fused quartz, pyrex, acrylic glass, polypropylene, bk7, sodium chloride, amber, pet, diamond"#,
        ),
    ),
    (
        "alpha_u_only",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf></shape>
</scene>"#,
        Some(
            r#""roughconductor": [RoughConductor] Microfacet model: both 'alpha_u' and 'alpha_v' must be specified."#,
        ),
    ),
    (
        "distribution_bad",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf></shape>
</scene>"#,
        Some(
            r#"conductor": [RoughConductor] Specified an invalid distribution "phong", must be "beckmann" or "ggx"!"#,
        ),
    ),
    (
        "cylinder",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="cylinder"/>
</scene>"#,
        None,
    ),
    (
        "disk",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="disk"/>
</scene>"#,
        None,
    ),
    (
        "area_top",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="area"/>
</scene>"#,
        None,
    ),
    (
        "top_medium",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<medium type="homogeneous"/>
</scene>"#,
        None,
    ),
    (
        "top_film",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<film type="hdrfilm"/>
</scene>"#,
        None,
    ),
    (
        "alias_ok",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<bsdf type="diffuse" id="a"/><alias id="a" as="b"/><shape type="sphere"><ref id="b"/></shape>
</scene>"#,
        None,
    ),
    (
        "fov_axis_no_fov",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><string name="fov_axis" value="y"/><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>

</scene>"#,
        Some(r#"- string "fov_axis": "y""#),
    ),
    (
        "integer_for_float",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><integer name="radius" value="2"/></shape>
</scene>"#,
        None,
    ),
    (
        "bool_upper",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<shape type="sphere"><boolean name="flip_normals" value="TRUE"/></shape>
</scene>"#,
        None,
    ),
    (
        "lookat_no_up",
        r#"<scene version="3.0.0">
<integrator type="path"/>
<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,0" target="0,0,1"/></transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>

</scene>"#,
        None,
    ),
];

/// Cases where the loader deliberately refuses what Mitsuba renders, and why.
const DELIBERATE: &[(&str, &str)] = &[
    ("moment_without_nested_integrator", "an aov/moment integrator without a nested integrator renders only extra channels, which the renderer cannot write"),
];

fn write(dir: &Path, name: &str, text: &str) {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, text).unwrap();
}

#[test]
fn loader_agrees_with_mitsuba() {
    let dir = std::env::temp_dir().join(format!("cohort-oracle-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let tri = |x: f32| format!("v {x} 0 0\nv {} 0 0\nv {x} 1 0\nf 1 2 3\n", x + 1.0);
    write(&dir, "a.obj", &tri(0.0));
    write(&dir, "extra/a.obj", &tri(10.0));
    write(
        &dir,
        "leaf.xml",
        r#"<scene version="3.0.0"><shape type="sphere"/></scene>"#,
    );
    write(
        &dir,
        "bsdf.xml",
        r#"<bsdf version="3.0.0" type="diffuse"/>"#,
    );
    write(
        &dir,
        "cyc1.xml",
        r#"<scene version="3.0.0"><include filename="cyc2.xml"/></scene>"#,
    );
    write(
        &dir,
        "cyc2.xml",
        r#"<scene version="3.0.0"><include filename="cyc1.xml"/></scene>"#,
    );
    let mut disagree = Vec::new();
    for (name, text, mitsuba) in CASES {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, text).unwrap();
        let ours = cohort_scenes::load_mitsuba(&path);
        let deliberate = DELIBERATE.iter().find(|(n, _)| n == name);
        let agree = ours.is_ok() == mitsuba.is_none();
        match (agree, deliberate) {
            (true, None) | (false, Some(_)) => {}
            (true, Some(_)) => disagree.push(format!(
                "{name}: listed as a deliberate difference but agrees now"
            )),
            (false, None) => disagree.push(format!(
                "{name}: mitsuba {}, cohort {}",
                mitsuba.map_or("loaded".to_string(), |e| format!("failed ({e})")),
                match &ours {
                    Ok(_) => "loaded".to_string(),
                    Err(e) => format!("failed ({e})"),
                }
            )),
        }
    }
    assert!(disagree.is_empty(), "{}", disagree.join("\n"));
}
