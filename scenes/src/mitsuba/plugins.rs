//! The plugins Mitsuba 3.9.1 knows, per element tag, so that the loader can tell a plugin the
//! renderer does not implement ("bsdf 'plastic' is not supported") from a name Mitsuba itself
//! would reject ("unknown bsdf plugin 'plastik'"). Lists taken from the plugins of the mitsuba
//! 3.9.1 wheel (one shared library each) plus the integrators its Python package registers.

const KNOWN: &[(&str, &[&str])] = &[
    (
        "bsdf",
        &[
            "blendbsdf",
            "bumpmap",
            "circular",
            "conductor",
            "dielectric",
            "diffuse",
            "hair",
            "mask",
            "measured",
            "measured_polarized",
            "normalmap",
            "null",
            "plastic",
            "polarizer",
            "pplastic",
            "principled",
            "principledthin",
            "retarder",
            "roughconductor",
            "roughdielectric",
            "roughplastic",
            "thindielectric",
            "twosided",
        ],
    ),
    (
        "shape",
        &[
            "blender",
            "bsplinecurve",
            "cube",
            "cylinder",
            "disk",
            "ellipsoids",
            "ellipsoidsmesh",
            "instance",
            "linearcurve",
            "merge",
            "obj",
            "ply",
            "rectangle",
            "sdfgrid",
            "serialized",
            "shapegroup",
            "sphere",
        ],
    ),
    (
        "emitter",
        &[
            "area",
            "constant",
            "directional",
            "directionalarea",
            "envmap",
            "point",
            "projector",
            "spot",
            "sunsky",
            "timed_sunsky",
        ],
    ),
    (
        "sensor",
        &[
            "batch",
            "distant",
            "irradiancemeter",
            "orthographic",
            "perspective",
            "radiancemeter",
            "thinlens",
        ],
    ),
    ("film", &["hdrfilm", "specfilm"]),
    (
        "sampler",
        &[
            "independent",
            "ldsampler",
            "multijitter",
            "orthogonal",
            "stratified",
        ],
    ),
    (
        "rfilter",
        &[
            "box",
            "catmullrom",
            "gaussian",
            "lanczos",
            "mitchell",
            "tent",
        ],
    ),
    (
        "integrator",
        &[
            "aov",
            "depth",
            "direct",
            "direct_projective",
            "moment",
            "path",
            "prb",
            "prb_basic",
            "prb_projective",
            "prbvolpath",
            "ptracer",
            "stokes",
            "volpath",
            "volpathmis",
        ],
    ),
    (
        "texture",
        &[
            "bitmap",
            "blackbody",
            "checkerboard",
            "d65",
            "irregular",
            "mesh_attribute",
            "rawconstant",
            "regular",
            "srgb",
            "uniform",
            "volume",
        ],
    ),
    ("medium", &["heterogeneous", "homogeneous"]),
    (
        "phase",
        &[
            "blendphase",
            "hg",
            "isotropic",
            "rayleigh",
            "sggx",
            "tabphase",
        ],
    ),
    ("volume", &["constvolume", "gridvolume"]),
];

/// Whether Mitsuba 3 has a `<tag type="plugin">`.
pub(crate) fn is_known(tag: &str, plugin: &str) -> bool {
    KNOWN
        .iter()
        .any(|(t, names)| *t == tag && names.contains(&plugin))
}

/// "bsdf 'plastic' is not supported by the renderer", or why Mitsuba itself would reject it.
pub(crate) fn describe(tag: &str, plugin: &str) -> String {
    if is_known(tag, plugin) {
        return format!("{tag} '{plugin}' is not supported by the renderer");
    }
    match KNOWN.iter().find(|(_, names)| names.contains(&plugin)) {
        Some((other, _)) => format!(
            "unknown {tag} plugin '{plugin}' (Mitsuba's '{plugin}' is a <{other}>, not a <{tag}>)"
        ),
        None => format!("unknown {tag} plugin '{plugin}' (Mitsuba 3 has no plugin of that name)"),
    }
}
