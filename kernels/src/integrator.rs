//! Which light transport estimator `extend` runs, chosen by type when the kernel is built
//! (an associated constant, so the implicit kernel contains no light sampling at all).

/// An estimator of the rendering equation.
pub trait Integrator: 'static {
    /// Next-event estimation: an emitter sample at every non-delta vertex, combined with
    /// BSDF sampling by the power heuristic (Mitsuba's `path`). Without it, a path
    /// contributes only when it hits an emitter or escapes (implicit path tracing, the
    /// paper's renderer).
    const NEE: bool;
}

/// Implicit path tracing (the paper's §3): `--integrator path`.
pub struct Implicit;
impl Integrator for Implicit {
    const NEE: bool = false;
}

/// Next-event estimation with multiple importance sampling: `--integrator nee`.
pub struct NextEvent;
impl Integrator for NextEvent {
    const NEE: bool = true;
}
