//! What a scene shades with: the set of BSDF kinds and shading features its materials and
//! lights use, one bit each. `extend` takes the set as a `#[specialize]` parameter, so that
//! each branch for a kind or feature the scene lacks is left out of the kernel when it is
//! built: a Cornell box compiles a diffuse shader, not every BSDF the renderer knows
//! (pipeline creation and the software driver's per-dispatch cost grow with the code).
//!
//! The host computes the set from the scene's GPU materials ([`shading_set`]); a material
//! whose kind is not in its kernel's set would shade as black, so the set is always
//! computed from the materials the kernel reads, never written by hand.

use crate::layout::*;

pub use crate::bsdf::KINDS;

/// The bit of material kind `kind` (one of [`KINDS`]).
pub const fn kind_bit(kind: u32) -> u32 {
    1 << kind
}

/// Some material is a `blendbsdf` (`Material::blend`).
pub const SHADES_BLEND: u32 = 1 << 16;
/// Some material has a `mask` (`MASKED`).
pub const SHADES_MASK: u32 = 1 << 17;
/// Some material has a normal or bump map (`Material::perturb_texture`).
pub const SHADES_PERTURB: u32 = 1 << 18;
/// Some material reads a texture or the hit's (u, v): a textured colour, opacity, blend
/// weight or radiance, or a parameter looked up at (u, v) (`READS_UV`).
pub const SHADES_TEXTURES: u32 = 1 << 19;
/// The scene has point, spot, directional or projector lights (`DeltaLight`).
pub const SHADES_DELTA_LIGHTS: u32 = 1 << 20;
/// The environment is a map (`Frame::env_map`), not a constant.
pub const SHADES_ENV_MAP: u32 = 1 << 21;

/// `extend` shades one material queue (`crate::queues`): it reads its rays from the
/// queue, whose index is in the bits from [`QUEUE_SHIFT`], not from the live list.
pub const SHADES_QUEUE: u32 = 1 << 22;
/// The frame reads group draws beyond the sampler's: `group_rr`, `coherent_glossy` or
/// `coherent_light` is set ([`group_draws`]). Without it, and without whole-group ends,
/// `extend` leaves those draws out.
pub const SHADES_GROUP_DRAWS: u32 = 1 << 23;
/// `extend` keys its group draws by the group of the slot it shades,
/// `slot / Frame::group_slots`, not by the invocation's (`crate::group_draw`): the frame's
/// `group_slots` is not 0 ([`group_draws`]).
pub const SHADES_SLOT_GROUPS: u32 = 1 << 24;
/// With [`SHADES_SLOT_GROUPS`], `extend` reads its group's draws from the group table
/// (`crate::group_draw`), rather than computing them, and writes the next iteration's:
/// where groups hold more than one slot (`Frame::group_slots` > 1), so that a group's
/// draws are computed once, not in each of its invocations.
pub const SHADES_GROUP_TABLE: u32 = 1 << 25;
/// The first bit of a queue's index in a set with [`SHADES_QUEUE`].
pub const QUEUE_SHIFT: u32 = 26;

/// The bits of frame `f`'s group draws, which the renderer adds to every set it builds
/// and records `extend` with: [`SHADES_GROUP_DRAWS`] where a frame flag reads the draws it
/// stands for, [`SHADES_SLOT_GROUPS`] where the frame keys them by slot, and
/// [`SHADES_GROUP_TABLE`] where such a group holds more than one slot.
pub fn group_draws(f: &Frame) -> u32 {
    let mut bits = 0;
    if f.group_rr != 0 || f.coherent_glossy != 0 || f.coherent_light != 0 {
        bits |= SHADES_GROUP_DRAWS;
    }
    if f.group_slots != 0 {
        bits |= SHADES_SLOT_GROUPS;
    }
    if f.group_slots > 1 {
        bits |= SHADES_GROUP_TABLE;
    }
    bits
}

/// The set of the `extend` that shades queue `queue` with `set`.
pub const fn queue_set(set: u32, queue: u32) -> u32 {
    set | SHADES_QUEUE | queue << QUEUE_SHIFT
}

/// The queue that an `extend` built with `set` shades (0 without [`SHADES_QUEUE`]).
pub const fn queue_index(set: u32) -> u32 {
    set >> QUEUE_SHIFT
}

/// The features of [`SHADES_BLEND`] and after, with their names in labels.
pub const FEATURES: [(u32, &str); 6] = [
    (SHADES_BLEND, "blend"),
    (SHADES_MASK, "mask"),
    (SHADES_PERTURB, "normal/bump map"),
    (SHADES_TEXTURES, "textures"),
    (SHADES_DELTA_LIGHTS, "delta lights"),
    (SHADES_ENV_MAP, "environment map"),
];

/// Every kind and feature: the kernel that shades any scene.
pub const SHADES_ALL: u32 = {
    let mut all = 0u32;
    let mut i = 0;
    while i < KINDS.len() {
        all |= kind_bit(KINDS[i].0);
        i += 1;
    }
    let mut i = 0;
    while i < FEATURES.len() {
        all |= FEATURES[i].0;
        i += 1;
    }
    all
};

/// The set of kinds and features that `materials` (every material the kernel can reach,
/// a blend's nested ones included), `delta_lights` and an environment map use.
pub fn shading_set(materials: &[Material], delta_lights: bool, env_map: bool) -> u32 {
    let mut set = 0u32;
    for m in materials {
        set |= kind_bit(m.kind);
        if m.blend != 0 {
            set |= SHADES_BLEND;
        }
        if m.flags & MASKED != 0 {
            set |= SHADES_MASK;
        }
        if m.perturb_texture != 0 {
            set |= SHADES_PERTURB;
        }
        if m.texture != 0
            || m.opacity_texture != 0
            || m.blend_texture != 0
            || m.emission_texture != 0
            || m.flags & READS_UV != 0
        {
            set |= SHADES_TEXTURES;
        }
    }
    if delta_lights {
        set |= SHADES_DELTA_LIGHTS;
    }
    if env_map {
        set |= SHADES_ENV_MAP;
    }
    set
}

/// The names of what `set` holds, `+`-separated (`diffuse+textures`); `none` when empty.
pub fn label(set: u32) -> String {
    let names: Vec<&str> = KINDS
        .iter()
        .map(|&(kind, name)| (kind_bit(kind), name))
        .chain(FEATURES.iter().copied())
        .filter(|(bit, _)| set & bit != 0)
        .map(|(_, name)| name)
        .collect();
    let names = if names.is_empty() {
        "none".into()
    } else {
        names.join("+")
    };
    if set & SHADES_QUEUE != 0 {
        format!("{names} (queue {})", queue_index(set))
    } else {
        names
    }
}
