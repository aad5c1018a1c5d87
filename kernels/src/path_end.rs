//! What a coherence group does when one of its paths ends: the extension kernel is
//! generic over it, and the choice is made when the kernel is built (an associated
//! constant), so grid-level kernels, which cannot vote, never contain the vote.
//!
//! Whole-group termination (the paper's §5: "terminating the whole group whenever one ray
//! must terminate") ending the other paths outright would truncate them, which is
//! biased. Here it is a Russian roulette that the ending path triggers: when any path of
//! the group ends (escapes, is absorbed, loses its own roulette or reaches the depth
//! limit), the group's other paths share one draw and all end, with probability
//! 1 - q, or all continue with their throughput divided by q
//! (`Frame::group_end_continue`). The trigger depends only on what already happened at
//! this bounce and the draw is fresh, so for every path E[1{continue} / q] = 1 and the
//! estimator stays unbiased; ended groups then restart together with coherent camera
//! rays.

/// A policy for paths ending, chosen by type.
pub trait PathEnd: 'static {
    /// Whether the group votes (`group_any`) and plays a shared roulette when any of its
    /// paths ends.
    const WHOLE_GROUP: bool;
}

/// Every path ends on its own (the paper).
pub struct EachPath;
impl PathEnd for EachPath {
    const WHOLE_GROUP: bool = false;
}

/// Whole-group termination as an unbiased triggered roulette (see the module docs).
/// Needs group = Warp or Block(n): the grid cannot vote within one dispatch.
pub struct WholeGroup;
impl PathEnd for WholeGroup {
    const WHOLE_GROUP: bool = true;
}
