//! What `cohort render` says of the CPU backend's kernel forms: how many of each kernel's
//! dispatches ran its vector form and how many its host form, and why. A first render
//! runs host forms while the vector forms compile (they are cached for the next run), so
//! the same command can report different paths/s; this line says which case a run was.

use cohort::runtime::cpu::simd::FormCount;
use cohort::runtime::Device;

/// The form counts of `devices` (CPU devices; none on the GPU backends), summed by kernel.
pub fn counts(devices: &[Device]) -> Vec<FormCount> {
    let mut all: Vec<FormCount> = Vec::new();
    for c in devices.iter().flat_map(Device::form_counts) {
        match all.iter_mut().find(|a| a.kernel == c.kernel) {
            Some(a) => {
                a.vector += c.vector;
                a.host += c.host;
                a.pending += c.pending;
                a.host_only += c.host_only;
                a.whole += c.whole;
            }
            None => all.push(c),
        }
    }
    all
}

/// One line: each kernel, by its function's name (the artifact name up to its
/// specialisation), with its dispatches per form.
pub fn line(counts: &[FormCount]) -> String {
    counts
        .iter()
        .map(|c| {
            let name = c.kernel.split("__").next().unwrap_or(&c.kernel);
            let parts: Vec<String> = c
                .by_form()
                .into_iter()
                .filter(|&(_, n)| n > 0)
                .map(|(form, n)| {
                    let what = match form {
                        "pending" => "host while the vector form was not compiled yet",
                        "host_only" => "host (no vector form)",
                        "whole" => "whole-dispatch",
                        other => other,
                    };
                    format!("{n} {what}")
                })
                .collect();
            format!("{name} {}", parts.join(" + "))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The counts for `--stats`, by full kernel name.
pub fn json(counts: &[FormCount]) -> serde_json::Value {
    counts
        .iter()
        .map(|c| {
            let forms = c
                .by_form()
                .into_iter()
                .map(|(f, n)| (f.to_string(), n.into()));
            (c.kernel.clone(), serde_json::Map::from_iter(forms).into())
        })
        .collect::<serde_json::Map<_, _>>()
        .into()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(kernel: &str, vector: u64, host: u64, pending: u64, host_only: u64) -> FormCount {
        FormCount {
            kernel: kernel.into(),
            vector,
            host,
            pending,
            host_only,
            whole: 0,
        }
    }

    #[test]
    fn the_line_names_each_kernel_and_the_forms_it_ran() {
        let c = [
            count("extend__thread_wg64_c0xf___x", 230, 8, 0, 0),
            count("traverse8__thread_wg64", 0, 0, 238, 0),
            count("bin_offsets__thread_wg256", 0, 0, 0, 3),
        ];
        assert_eq!(
            line(&c),
            "extend 230 vector + 8 host, traverse8 238 host while the vector form was not compiled yet, bin_offsets 3 host (no vector form)"
        );
        let j = json(&c);
        assert_eq!(j["traverse8__thread_wg64"]["pending"], 238);
        assert_eq!(j["extend__thread_wg64_c0xf___x"]["vector"], 230);
    }
}
