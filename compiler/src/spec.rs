//! What one kernel specialisation is: the kernel's static description (from the
//! `#[kernel]` attribute) plus the choices made at build time (coherence group level,
//! workgroup size, how a warp is realised on this device). A `(kernel, Spec)` pair is
//! the cache key of a compiled artifact.

/// What a specialisation may assume about the device it will run on: its subgroups and
/// how it prefers uniform parameters. The runtime describes each device this way
/// (`DeviceInfo::target`); the compiler knows no device API.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Target {
    /// The subgroup width a kernel gets when it does not require one.
    pub subgroup_size: u32,
    pub subgroup_size_min: u32,
    pub subgroup_size_max: u32,
    /// Whether a kernel may require a subgroup width in `[min, max]` (Vulkan subgroup size
    /// control).
    pub supports_required_subgroup_size: bool,
    /// Whether uniform parameters should be read-only storage buffers
    /// ([`Spec::uniforms_as_storage`]).
    pub uniforms_as_storage: bool,
    /// Whether each invocation should compute its group's `group_share` value itself
    /// ([`Spec::recompute_group_share`]).
    pub recompute_group_share: bool,
}

/// The coherence group level: which invocations share a `group_share` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Group {
    /// Every invocation is its own group (the value is computed by each invocation).
    Thread,
    /// 32 consecutive invocations, on every device.
    Warp,
    /// The whole workgroup of `n` invocations.
    Block(u32),
    /// Every invocation of the dispatch: each computes the value of group 0 (its closure
    /// reads only uniform values, so all agree), on the device.
    Grid,
}

impl Group {
    /// Parses the names used on the command line and in the attribute:
    /// `thread`, `warp`, `block_256` / `block256`, `grid`.
    pub fn parse(s: &str) -> Option<Group> {
        let s = s.trim().to_ascii_lowercase();
        match s.as_str() {
            "thread" => Some(Group::Thread),
            "warp" => Some(Group::Warp),
            "grid" => Some(Group::Grid),
            _ => {
                let n = s.strip_prefix("block")?.trim_start_matches('_');
                let n: u32 = n.parse().ok()?;
                (n > 0 && n <= 1024).then_some(Group::Block(n))
            }
        }
    }

    pub fn label(self) -> String {
        match self {
            Group::Thread => "thread".into(),
            Group::Warp => "warp".into(),
            Group::Block(n) => format!("block_{n}"),
            Group::Grid => "grid".into(),
        }
    }
}

/// Static facts about a kernel, written by `#[kernel]`.
#[derive(Debug)]
pub struct KernelInfo {
    pub name: &'static str,
    /// Where the kernel is defined, for error messages (compiler bugs are reported here).
    pub file: &'static str,
    pub line: u32,
    pub column: u32,
    /// Workgroup size from the attribute (used unless the group level is `Block(n)`).
    pub workgroup_size: u32,
    /// Group level from the attribute, used when the caller does not choose one.
    pub group: Group,
    /// `loops = finite` in the attribute: the author promises that every loop the kernel
    /// runs (its helpers' included) ends, so the GPU backends omit naga's loop-bound
    /// counters (docs/LANGUAGE.md, "Loops").
    pub finite_loops: bool,
}

/// One specialisation of a kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Spec {
    pub group: Group,
    pub workgroup_size: u32,
    /// Realise `Warp` with subgroup broadcasts (the subgroup is exactly 32 wide) instead of
    /// workgroup memory and a barrier.
    pub warp_via_subgroup: bool,
    /// Ask the driver for subgroups of exactly this size (Vulkan subgroup size control).
    pub required_subgroup_size: Option<u32>,
    /// Declare uniform parameters (`&T`) as read-only storage buffers: the same values and
    /// layout, bound as storage. For drivers where a uniform buffer costs more than its
    /// reads ([`Target::uniforms_as_storage`]).
    pub uniforms_as_storage: bool,
    /// Every invocation computes its warp's or block's `group_share` value itself, from
    /// its group index, instead of receiving the leader's through workgroup memory or a
    /// subgroup broadcast. The value is the same bits (the closure reads only the group
    /// index, uniform and specialised values, and constants), and no barrier is left. For
    /// the CPU backend, whose vector form runs a group's invocations as blocks of SIMD
    /// lanes and has no barrier; there the extra evaluations share the block's vector
    /// instructions.
    pub recompute_group_share: bool,
    /// The values of the kernel's `#[specialize]` parameters, in parameter order (the
    /// rest 0). They are literals in the built module, so that every branch they decide
    /// is left out of it (docs/LANGUAGE.md, "Specialisation constants").
    pub constants: [u32; MAX_CONSTANTS],
}

pub const WARP: u32 = 32;

/// How many `#[specialize]` parameters one kernel may have.
pub const MAX_CONSTANTS: usize = 4;

impl Spec {
    /// A device-independent specialisation: warps go through workgroup memory.
    pub fn portable(info: &KernelInfo, group: Group) -> Spec {
        let workgroup_size = match group {
            Group::Block(n) => n,
            _ => info.workgroup_size,
        };
        Spec {
            group,
            workgroup_size,
            warp_via_subgroup: false,
            required_subgroup_size: None,
            uniforms_as_storage: false,
            recompute_group_share: false,
            constants: [0; MAX_CONSTANTS],
        }
    }

    /// This specialisation with its `#[specialize]` parameters set to `values` (the
    /// launch functions that `#[kernel]` generates call it with their arguments).
    pub fn with_constants(mut self, values: &[u32]) -> Spec {
        assert!(
            values.len() <= MAX_CONSTANTS,
            "a kernel has at most {MAX_CONSTANTS} #[specialize] parameters"
        );
        self.constants = [0; MAX_CONSTANTS];
        self.constants[..values.len()].copy_from_slice(values);
        self
    }

    /// The best specialisation for `device`: warps use subgroup broadcasts where the
    /// device's subgroups are (or can be made) exactly 32 wide.
    pub fn for_device(info: &KernelInfo, device: &Target, group: Group) -> Spec {
        let mut spec = Spec::portable(info, group);
        spec.uniforms_as_storage = device.uniforms_as_storage;
        spec.recompute_group_share =
            device.recompute_group_share && matches!(group, Group::Warp | Group::Block(_));
        // Subgroups serve `group_share` and `group_any` at warp level; a target that
        // recomputes shares has no use for them there (its `group_any` keeps the portable
        // lowering).
        if group == Group::Warp && !spec.recompute_group_share {
            if device.subgroup_size == WARP && device.subgroup_size_min == device.subgroup_size_max
            {
                spec.warp_via_subgroup = true;
            } else if device.supports_required_subgroup_size
                && (device.subgroup_size_min..=device.subgroup_size_max).contains(&WARP)
            {
                spec.warp_via_subgroup = true;
                spec.required_subgroup_size = Some(WARP);
            } else if device.subgroup_size == WARP {
                spec.warp_via_subgroup = true;
            }
        }
        spec
    }

    /// Suffix that names this specialisation in artifact and snapshot names.
    pub fn suffix(&self) -> String {
        let mut s = self.group.label();
        if self.group == Group::Warp && !self.recompute_group_share {
            s.push_str(if self.warp_via_subgroup {
                "_subgroup"
            } else {
                "_shared"
            });
        }
        if !matches!(self.group, Group::Block(_)) {
            s.push_str(&format!("_wg{}", self.workgroup_size));
        }
        if self.uniforms_as_storage {
            s.push_str("_ustorage");
        }
        if self.recompute_group_share {
            s.push_str("_recompute");
        }
        for (i, c) in self.constants.iter().enumerate() {
            if *c != 0 {
                s.push_str(&format!("_c{i}x{c:x}"));
            }
        }
        s
    }
}
