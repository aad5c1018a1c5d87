//! The kernels read the scene crate's GPU bytes through their own types
//! (`cohort_kernels::layout`, which derive `GpuType`): each field of each pair is at the
//! same offset with the same meaning, and the material kinds and flags have the same
//! values. A distinct value is written into every field on the scene side, and each is
//! read back through the kernel type's field of the same name.

use cohort_kernels::layout::{self as k, BvhNode, Material, Triangle};
use cohort_scenes::{GpuBvhNode, GpuMaterial, GpuTriangle};

/// A value that differs per field and per component: `seed + component`.
fn v3(seed: f32) -> [f32; 3] {
    [seed, seed + 0.25, seed + 0.5]
}

#[test]
fn material_fields_match_one_by_one() {
    let g = GpuMaterial {
        color: v3(1.0),
        kind: 2,
        emission: v3(3.0),
        flags: 4,
        transmittance: v3(5.0),
        param: 6.0,
        conductor_k: v3(7.0),
        texture: 8,
        opacity: 9.0,
        opacity_texture: 10,
        table: 11,
        blend: 12,
        blend_weight: 13.0,
        perturb_texture: 14,
        bump_scale: 15.0,
        blend_texture: 16,
        emission_texture: 17,
        pad: [18, 19, 20],
    };
    let m: Material = bytemuck::cast(g);
    assert_eq!(m.color.to_array(), g.color);
    assert_eq!(m.kind, g.kind);
    assert_eq!(m.emission.to_array(), g.emission);
    assert_eq!(m.flags, g.flags);
    assert_eq!(m.transmittance.to_array(), g.transmittance);
    assert_eq!(m.param, g.param);
    assert_eq!(m.conductor_k.to_array(), g.conductor_k);
    assert_eq!(m.texture, g.texture);
    assert_eq!(m.opacity, g.opacity);
    assert_eq!(m.opacity_texture, g.opacity_texture);
    assert_eq!(m.table, g.table);
    assert_eq!(m.blend, g.blend);
    assert_eq!(m.blend_weight, g.blend_weight);
    assert_eq!(m.perturb_texture, g.perturb_texture);
    assert_eq!(m.bump_scale, g.bump_scale);
    assert_eq!(m.blend_texture, g.blend_texture);
    assert_eq!(m.emission_texture, g.emission_texture);
    assert_eq!([m.pad_a, m.pad_b, m.pad_c], g.pad);
}

#[test]
fn material_kinds_and_flags_match() {
    let kinds = [
        (k::DIFFUSE, GpuMaterial::DIFFUSE),
        (k::CONDUCTOR, GpuMaterial::CONDUCTOR),
        (k::ROUGH_CONDUCTOR, GpuMaterial::ROUGH_CONDUCTOR),
        (k::DIELECTRIC, GpuMaterial::DIELECTRIC),
        (k::PLASTIC, GpuMaterial::PLASTIC),
        (k::ROUGH_PLASTIC, GpuMaterial::ROUGH_PLASTIC),
        (k::ROUGH_DIELECTRIC, GpuMaterial::ROUGH_DIELECTRIC),
        (k::PRINCIPLED, GpuMaterial::PRINCIPLED),
        (k::PRINCIPLED_THIN, GpuMaterial::PRINCIPLED_THIN),
    ];
    for (kernel, scene) in kinds {
        assert_eq!(kernel, scene);
    }
    // Every kind the scene crate writes has a name in the shading table, which is what
    // `extend` is specialised on: a kind missing there would shade as black.
    let table: Vec<u32> = cohort_kernels::shading::KINDS
        .iter()
        .map(|(k, _)| *k)
        .collect();
    for (kernel, _) in kinds {
        assert!(
            table.contains(&kernel),
            "kind {kernel} is not in shading::KINDS"
        );
    }
    let flags = [
        (k::TWO_SIDED, GpuMaterial::FLAG_TWO_SIDED),
        (k::EMITTER, GpuMaterial::FLAG_EMITTER),
        (k::NONLINEAR, GpuMaterial::FLAG_NONLINEAR),
        (k::BECKMANN, GpuMaterial::FLAG_BECKMANN),
        (k::MASKED, GpuMaterial::FLAG_MASKED),
        (k::NORMAL_MAP, GpuMaterial::FLAG_NORMAL_MAP),
        (k::BUMP_MAP, GpuMaterial::FLAG_BUMP_MAP),
        (k::NO_SHADOWING, GpuMaterial::FLAG_NO_SHADOWING),
        (k::NO_FLIP, GpuMaterial::FLAG_NO_FLIP),
        (k::PERTURB_PER_SIDE, GpuMaterial::FLAG_PERTURB_PER_SIDE),
        (k::READS_UV, GpuMaterial::FLAG_READS_UV),
    ];
    for (kernel, scene) in flags {
        assert_eq!(kernel, scene);
    }
}

#[test]
fn triangle_and_node_fields_match_one_by_one() {
    let g = GpuTriangle {
        v0: v3(1.0),
        material: 2,
        v1: v3(3.0),
        original: 4,
        v2: v3(5.0),
        pad: 6,
    };
    let t: Triangle = bytemuck::cast(g);
    assert_eq!(t.v0.to_array(), g.v0);
    assert_eq!(t.material, g.material);
    assert_eq!(t.v1.to_array(), g.v1);
    assert_eq!(t.original, g.original);
    assert_eq!(t.v2.to_array(), g.v2);
    assert_eq!(t.light_pdf.to_bits(), g.pad);
    let g = GpuBvhNode {
        lmin: v3(1.0),
        left: 2,
        lmax: v3(3.0),
        right: 4,
        rmin: v3(5.0),
        pad0: 6,
        rmax: v3(7.0),
        pad1: 8,
    };
    let n: BvhNode = bytemuck::cast(g);
    assert_eq!(n.lmin.to_array(), g.lmin);
    assert_eq!(n.left, g.left);
    assert_eq!(n.lmax.to_array(), g.lmax);
    assert_eq!(n.right, g.right);
    assert_eq!(n.rmin.to_array(), g.rmin);
    assert_eq!(n.pad0, g.pad0);
    assert_eq!(n.rmax.to_array(), g.rmax);
    assert_eq!(n.pad1, g.pad1);
}
