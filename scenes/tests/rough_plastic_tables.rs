//! Mitsuba `roughplastic`'s external transmittance table as `cohort_scenes::rough_plastic`
//! computes it, against the entries Mitsuba 3.9.1's own algorithm gives
//! (`scripts/roughplastic_oracle.py`, last lines); its internal reflectance enters the
//! kernels' BSDF values, which kernels/tests/rough_plastic.rs compares with Mitsuba's.

use cohort_scenes::rough_plastic::tables;

/// (Beckmann, alpha, eta, [(entry, Mitsuba's value)]).
type Table = (bool, f32, f32, [(usize, f32); 6]);

#[test]
fn transmittance_tables_are_mitsubas() {
    let mitsuba: [Table; 2] = [
        (
            false,
            0.3,
            1.5,
            [
                (0, 0.6365177),
                (5, 0.7007966),
                (10, 0.7492967),
                (32, 0.8885616),
                (50, 0.9385873),
                (63, 0.9531594),
            ],
        ),
        (
            true,
            0.2,
            1.7,
            [
                (0, 0.5424017),
                (5, 0.6073419),
                (10, 0.6721851),
                (32, 0.8768983),
                (50, 0.9258656),
                (63, 0.9327263),
            ],
        ),
    ];
    for (beckmann, alpha, eta, entries) in mitsuba {
        let t = tables(alpha, beckmann, eta);
        for (k, m) in entries {
            let ours = t.external_transmittance[k];
            // The two quadratures (Mitsuba's 32 x 32 Gauss-Legendre nodes over its
            // visible-normal sampling, a 256 x 128 grid over the normal here) differ by
            // well under 0.1 %.
            assert!(
                (ours - m).abs() / m < 1e-3,
                "beckmann {beckmann} alpha {alpha} eta {eta}: entry {k}: {ours} vs Mitsuba's {m}"
            );
        }
        // Light from inside is partly reflected back at every angle.
        assert!(t.internal_reflectance > 0.0 && t.internal_reflectance < 1.0);
    }
}
