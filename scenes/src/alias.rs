//! Vose's alias method: a table from which one uniform number picks item `i` with
//! probability `p[i]` in constant time (next-event estimation's light choice, the
//! environment map's texel cells).

/// One entry per item: keep the item with probability `prob`, else take `alias`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AliasEntry {
    pub prob: f32,
    pub alias: u32,
}

/// The alias table of `weights` (non-negative, not all zero; normalised here). A uniform
/// `u` in [0, 1) picks entry `j = floor(u n)`, then `j` itself if `u n - j < prob`, else
/// its `alias`.
pub fn alias_table(weights: &[f64]) -> Vec<AliasEntry> {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    let mut scaled: Vec<f64> = weights.iter().map(|&w| w / total * n as f64).collect();
    let mut entries: Vec<AliasEntry> = (0..n)
        .map(|i| AliasEntry {
            prob: 1.0,
            alias: i as u32,
        })
        .collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        entries[s].prob = scaled[s] as f32;
        entries[s].alias = l as u32;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left is 1 up to rounding.
    entries
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table picks each item with its probability: summed over entries.
    #[test]
    fn alias_table_reproduces_the_probabilities() {
        let weights = [8.0, 4.0, 2.0, 1.0, 1.0, 0.0];
        let t = alias_table(&weights);
        let n = t.len() as f64;
        for (k, w) in weights.iter().enumerate() {
            let got: f64 = t
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    (if i == k { e.prob as f64 } else { 0.0 })
                        + if e.alias as usize == k {
                            1.0 - e.prob as f64
                        } else {
                            0.0
                        }
                })
                .sum::<f64>()
                / n;
            assert!(
                (got - w / 16.0).abs() < 1e-6,
                "item {k}: {got} vs {}",
                w / 16.0
            );
        }
    }
}
