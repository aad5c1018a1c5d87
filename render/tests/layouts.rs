//! The GPU data layouts are declared once (`cohort-layout`): the scene builder writes those
//! types and the kernels read them. What is left to check is that each declaration is a
//! valid GPU struct as the kernels see it: every type, as the compiler gives it to naga
//! (member by member, at the host's offsets), in a storage array, passes naga's validator,
//! which checks each member's offset against its WGSL/SPIR-V alignment and the stride
//! against the size; and every material kind the scene crate writes is in the shading
//! table `extend` is specialised on.

use cohort::ir::GpuType;
use cohort::naga;
use cohort_kernels::layout::{self as k, *};

/// Validates `T` as the element of a read-only storage array and returns its members'
/// names and offsets as naga has them.
fn validate<T: GpuType>() -> Vec<(String, u32)> {
    let mut m = naga::Module::default();
    let ty = T::naga_type(&mut m);
    let stride = std::mem::size_of::<T>() as u32;
    let array = m.types.insert(
        naga::Type {
            name: None,
            inner: naga::TypeInner::Array {
                base: ty,
                size: naga::ArraySize::Dynamic,
                stride,
            },
        },
        naga::Span::UNDEFINED,
    );
    m.global_variables.append(
        naga::GlobalVariable {
            name: Some("data".into()),
            space: naga::AddressSpace::Storage {
                access: naga::StorageAccess::LOAD,
            },
            binding: Some(naga::ResourceBinding {
                group: 0,
                binding: 0,
            }),
            ty: array,
            init: None,
            memory_decorations: Default::default(),
        },
        naga::Span::UNDEFINED,
    );
    if let Err(e) = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&m)
    {
        panic!(
            "{}: not a valid GPU struct: {:?}",
            std::any::type_name::<T>(),
            e.into_inner()
        );
    }
    match &m.types[ty].inner {
        naga::TypeInner::Struct { members, span } => {
            assert_eq!(*span, stride, "{}", std::any::type_name::<T>());
            members
                .iter()
                .map(|mb| (mb.name.clone().unwrap_or_default(), mb.offset))
                .collect()
        }
        other => panic!("not a struct: {other:?}"),
    }
}

#[test]
fn every_layout_type_is_a_valid_gpu_struct() {
    validate::<BvhNode>();
    validate::<WideNode>();
    validate::<CwNode>();
    validate::<Principled>();
    validate::<Frame>();
    validate::<LightEntry>();
    validate::<DeltaLight>();
    // Offsets are the host's: spot-check the ones the scene builder's documentation
    // tables give.
    let material = validate::<Material>();
    let at = |name: &str| material.iter().find(|(n, _)| n == name).unwrap().1;
    assert_eq!(at("kind"), 12);
    assert_eq!(at("flags"), 28);
    assert_eq!(at("table"), 72);
    assert_eq!(at("emission_texture"), 96);
    assert_eq!(std::mem::size_of::<Material>(), 112);
    let triangle = validate::<Triangle>();
    assert_eq!(
        triangle,
        [
            ("v0", 0),
            ("material", 12),
            ("v1", 16),
            ("original", 28),
            ("v2", 32),
            ("light_pdf", 44)
        ]
        .map(|(n, o)| (n.to_string(), o))
    );
}

#[test]
fn every_material_kind_is_in_the_shading_table() {
    let kinds = [
        k::DIFFUSE,
        k::CONDUCTOR,
        k::ROUGH_CONDUCTOR,
        k::DIELECTRIC,
        k::PLASTIC,
        k::ROUGH_PLASTIC,
        k::ROUGH_DIELECTRIC,
        k::PRINCIPLED,
        k::PRINCIPLED_THIN,
    ];
    // `extend` is specialised on the scene's kinds: a kind missing from the table would
    // shade as black.
    let table: Vec<u32> = cohort_kernels::shading::KINDS
        .iter()
        .map(|(k, _)| *k)
        .collect();
    for kind in kinds {
        assert!(
            table.contains(&kind),
            "kind {kind} is not in shading::KINDS"
        );
    }
}
