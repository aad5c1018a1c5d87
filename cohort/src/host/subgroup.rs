//! The arithmetic of subgroup collectives (`subgroup_add`, `_min`, `_max` and the scans) in
//! their host form, for the types the GPU form accepts: integers wrap as on the GPU,
//! vectors work per component.

use glam::{IVec2, IVec3, IVec4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};

/// A value a subgroup collective can combine.
pub trait SubgroupArith: Copy + Default {
    fn add(a: Self, b: Self) -> Self;
    fn min(a: Self, b: Self) -> Self;
    fn max(a: Self, b: Self) -> Self;
}

macro_rules! arith {
    ($($t:ty: $add:expr, $min:expr, $max:expr;)*) => {$(
        impl SubgroupArith for $t {
            fn add(a: Self, b: Self) -> Self {
                ($add)(a, b)
            }
            fn min(a: Self, b: Self) -> Self {
                ($min)(a, b)
            }
            fn max(a: Self, b: Self) -> Self {
                ($max)(a, b)
            }
        }
    )*};
}
arith! {
    u32: u32::wrapping_add, Ord::min, Ord::max;
    i32: i32::wrapping_add, Ord::min, Ord::max;
    f32: |a: f32, b: f32| a + b, f32::min, f32::max;
    UVec2: UVec2::wrapping_add, UVec2::min, UVec2::max;
    UVec3: UVec3::wrapping_add, UVec3::min, UVec3::max;
    UVec4: UVec4::wrapping_add, UVec4::min, UVec4::max;
    IVec2: IVec2::wrapping_add, IVec2::min, IVec2::max;
    IVec3: IVec3::wrapping_add, IVec3::min, IVec3::max;
    IVec4: IVec4::wrapping_add, IVec4::min, IVec4::max;
    Vec2: |a: Vec2, b: Vec2| a + b, Vec2::min, Vec2::max;
    Vec3: |a: Vec3, b: Vec3| a + b, Vec3::min, Vec3::max;
    Vec4: |a: Vec4, b: Vec4| a + b, Vec4::min, Vec4::max;
}
