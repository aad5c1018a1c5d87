//! Which Russian roulette ends paths: the paper's fixed continuation probability, or the
//! throughput-based roulette of Mitsuba's `path` integrator, for scenes that ask for it.

use cohort_scenes::Scene;

/// A Russian roulette rule (`RenderOptions::roulette`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Roulette {
    /// The paper's (§3): after every bounce a path continues with the fixed
    /// probability `RenderOptions::rr_continue` (0.8), whatever its throughput.
    #[default]
    Fixed,
    /// Mitsuba's `path`: from the scene's `rr_depth` on (counted in vertices, as Mitsuba
    /// counts), a path continues with probability min(max component of its throughput,
    /// 0.95), so bright paths go on and dim ones end. (Mitsuba multiplies the throughput by
    /// the squared relative IOR of the refractions so far; the kernels' dielectric leaves
    /// the 1/eta^2 radiance scaling out of the throughput, so their throughput already is
    /// that product for closed dielectric objects.)
    Mitsuba,
}

impl Roulette {
    pub fn name(self) -> &'static str {
        match self {
            Roulette::Fixed => "fixed",
            Roulette::Mitsuba => "mitsuba",
        }
    }

    pub fn parse(s: &str) -> Option<Roulette> {
        match s {
            "fixed" | "paper" => Some(Roulette::Fixed),
            "mitsuba" => Some(Roulette::Mitsuba),
            _ => None,
        }
    }

    /// (first bounce index at which the roulette plays, throughput-based) for the kernels'
    /// `Frame::rr_depth` and `Frame::roulette_throughput`.
    pub fn frame_fields(self, scene: &Scene) -> (u32, u32) {
        match self {
            Roulette::Fixed => (0, 0),
            Roulette::Mitsuba => (scene.integrator.rr_depth.max(1) as u32, 1),
        }
    }
}

/// The kernels' depth fields for the scene's Mitsuba `max_depth`: (`Frame::max_depth`, 0 =
/// unlimited; `Frame::zero_depth`, 1 for max_depth 0, where Mitsuba renders black).
pub fn depth_fields(scene: &Scene) -> (u32, u32) {
    match scene.integrator.max_depth {
        0 => (0, 1),
        d if d < 0 => (0, 0),
        d => (d as u32, 0),
    }
}

/// What the options cannot render of `scene` as its author meant, for the user to read.
pub fn warnings(scene: &Scene, opts: &crate::RenderOptions) -> Vec<String> {
    let mut w = Vec::new();
    if opts.integrator == crate::IntegratorKind::Path && !scene.lights.is_empty() {
        w.push(format!(
            "the scene has {} point, spot or directional light(s), which only light sampling reaches: \
             --integrator path (implicit path tracing) renders them black; use --integrator nee",
            scene.lights.len()
        ));
    }
    w
}
