//! Which of the two designs of shading shades a run's iterations
//! (`RenderOptions::shading`): one `extend` built with the scene's kinds over every ray,
//! or material queues (`crate::queues`). Neither wins everywhere: on an H200, queues are
//! 1.1-2.7x faster on scenes whose one kernel is large (textured blends, textured
//! principled, bump maps) and 0.7-0.98x on the others (BENCHMARKS.md). So
//! [`Shading::Auto`](crate::Shading::Auto) measures both on the render itself: batches
//! alternate between them, and once each has two batches measured after the first batch
//! of the run, the design with less shading time per iteration shades the rest.
//!
//! The choice does not change the image: a trial runs only where every draw is keyed by
//! path (`RenderOptions::per_path_sampling`), and then the two designs give the same image
//! bit for bit. With coherent groups, which form over the queues, the choice is fixed.

use std::time::Duration;

/// Batches each design is measured over before the choice.
const MEASURED: u32 = 2;

/// The design of a renderer's batches.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Choice {
    /// Material queues (`true`) or one kernel, for every batch.
    Fixed(bool),
    Trial(Trial),
}

/// Batches alternating between the designs, the first (a warm-up) with one kernel.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Trial {
    recorded: u32,
    /// Shading time (queue and extend stages) and iterations measured, by design (index 1:
    /// queues), and the batches they came from.
    time: [Duration; 2],
    iterations: [u32; 2],
    batches: [u32; 2],
}

impl Choice {
    /// The design of the next batch recorded, and its index in the run's trial.
    pub(crate) fn next_batch(&mut self) -> (bool, u32) {
        match self {
            Choice::Fixed(queued) => (*queued, 0),
            Choice::Trial(t) => {
                let index = t.recorded;
                t.recorded += 1;
                (index % 2 == 1, index)
            }
        }
    }

    /// A completed batch: its design, index, shading time and iterations. Once both
    /// designs are measured, the faster one is fixed.
    pub(crate) fn observe(&mut self, queued: bool, index: u32, time: Duration, iterations: u32) {
        let Choice::Trial(t) = self else {
            return;
        };
        if index == 0 || iterations == 0 {
            return;
        }
        let d = queued as usize;
        t.time[d] += time;
        t.iterations[d] += iterations;
        t.batches[d] += 1;
        if t.batches.iter().all(|&b| b >= MEASURED) {
            let per = |d: usize| t.time[d].as_secs_f64() / t.iterations[d] as f64;
            *self = Choice::Fixed(per(1) < per(0));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(m: u64) -> Duration {
        Duration::from_millis(m)
    }

    /// Runs a trial where an iteration takes `kernel` or `queues` ms, batches of 4.
    fn trial(kernel: u64, queues: u64) -> (Choice, u32) {
        let mut c = Choice::Trial(Trial::default());
        let mut batches = 0;
        while let Choice::Trial(_) = c {
            let (queued, index) = c.next_batch();
            let per = if queued { queues } else { kernel };
            // The warm-up batch is slow whatever the design; it must not count.
            let time = if index == 0 { ms(1000) } else { ms(4 * per) };
            c.observe(queued, index, time, 4);
            batches += 1;
            assert!(batches < 100, "the trial never ends");
        }
        (c, batches)
    }

    #[test]
    fn the_faster_design_is_kept() {
        assert_eq!(trial(10, 6).0, Choice::Fixed(true));
        assert_eq!(trial(6, 10).0, Choice::Fixed(false));
        // One warm-up batch, then two of each design.
        assert_eq!(trial(6, 10).1, 1 + 2 * MEASURED);
    }

    #[test]
    fn designs_alternate_from_one_kernel_and_a_fixed_choice_stays() {
        let mut c = Choice::Trial(Trial::default());
        let designs: Vec<bool> = (0..4).map(|_| c.next_batch().0).collect();
        assert_eq!(designs, [false, true, false, true]);
        let mut fixed = Choice::Fixed(true);
        fixed.observe(false, 3, ms(1), 4);
        assert_eq!(fixed.next_batch(), (true, 0));
    }

    #[test]
    fn batches_in_flight_when_the_choice_is_made_do_not_undo_it() {
        let (mut c, _) = trial(10, 6);
        c.observe(false, 7, ms(1), 4);
        assert_eq!(c, Choice::Fixed(true));
    }
}
