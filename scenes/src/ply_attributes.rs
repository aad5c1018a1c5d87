//! Which properties of a PLY element become which of Mitsuba's mesh attributes, grouped as
//! Mitsuba 3.9's PLY loader groups them (`find_other_fields` in `src/shapes/ply.h`):
//!
//! - `r`, `g`, `b` (or `red`, `green`, `blue`; `a` / `alpha` joins them) become
//!   `{vertex|face}_color`;
//! - every other scalar property named `{prefix}_{postfix}` starts or continues an attribute
//!   `{vertex|face}_{prefix}`: consecutive properties with one prefix and postfixes in one of
//!   the sequences `x y z w`, `r g b a`, `0 1 2 3`, `1 2 3 4`. An attribute of the `r g b a`
//!   sequence is named `{vertex|face}_{prefix}_color`. Only attributes of 1 or 3 properties are
//!   kept.
//!
//! What Mitsuba skips with a warning is skipped here with the same warning.

/// A mesh attribute of an element: its name (with the `vertex_` / `face_` prefix) and the
/// indices of its properties, in channel order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AttributeFields {
    pub name: String,
    pub fields: Vec<usize>,
}

/// Each postfix sequence, by position: sequence `s` is `POSTFIXES[0][s]`, `POSTFIXES[1][s]`, ...
const POSTFIXES: [&[u8; 4]; 4] = [b"xr01", b"yg12", b"zb23", b"wa34"];
/// The sequence whose attributes Mitsuba names `..._color`.
const COLOR_SEQUENCE: usize = 1;

/// The mesh attributes among `names` (the element's scalar properties, in file order; `None`
/// for a list property) for an element of `kind` (`"vertex_"` or `"face_"`), skipping
/// `reserved` names (positions, normals, texture coordinates). Warnings go to `warn`.
pub fn group_attributes(
    kind: &str,
    names: &[Option<&str>],
    reserved: &[&str],
    mut warn: impl FnMut(String),
) -> Vec<AttributeFields> {
    let find = |n: &str| names.iter().position(|&p| p == Some(n));
    let mut out = Vec::new();
    let mut colour_names: &[&str] = &["r", "g", "b", "a"];
    let mut rgb = ["r", "g", "b"].map(find);
    if rgb.iter().any(Option::is_none) {
        rgb = ["red", "green", "blue"].map(find);
        colour_names = &["red", "green", "blue", "alpha"];
    }
    if rgb.iter().all(Option::is_some) {
        let mut fields: Vec<usize> = rgb.iter().flatten().copied().collect();
        if let Some(a) = find(colour_names[3]) {
            fields.push(a);
        }
        out.push(AttributeFields {
            name: format!("{kind}color"),
            fields,
        });
    }

    // Mitsuba's scan, state for state.
    let mut scan = Scan {
        kind,
        out,
        encountered: Vec::new(),
        prefix: String::new(),
        sequence: 0,
        level: 0,
        reading: false,
        fields: Vec::new(),
    };
    let mut i = 0;
    while i < names.len() {
        let Some(name) = names[i] else {
            i += 1;
            continue;
        };
        // Mitsuba reserves r, g, b, a, and renames red, green, blue, alpha to them when it
        // takes those as the colour.
        let taken_as_colour = colour_names[0] == "red"
            && colour_names.contains(&name)
            && rgb.iter().all(Option::is_some);
        if reserved.contains(&name) || ["r", "g", "b", "a"].contains(&name) || taken_as_colour {
            i += 1;
            continue;
        }
        let Some(pos) = name.rfind('_').filter(|&p| name.len() - p == 2) else {
            warn(format!(
                "attribute '{name}' ignored: attributes need a one-letter postfix after '_'"
            ));
            scan.flush_if_reading(&mut warn);
            i += 1;
            continue;
        };
        let this_prefix = &name[..pos];
        let ch = name.as_bytes()[pos + 1];
        if scan.reading && this_prefix != scan.prefix {
            scan.flush(&mut warn);
        }
        let same_prefix = |j: usize| names[j].is_some_and(|n| n.starts_with(this_prefix));
        if !scan.reading && scan.encountered.iter().any(|e| e == this_prefix) {
            warn(format!(
                "attribute '{name}' ignored: prefix '{this_prefix}' has already been encountered"
            ));
            while i < names.len() && same_prefix(i) {
                i += 1;
            }
            // Mitsuba's loop then steps past the next property too.
            i += 1;
            continue;
        }
        if !scan.reading {
            let Some(s) = POSTFIXES[0].iter().position(|&c| c == ch) else {
                warn(format!(
                    "attribute '{name}' ignored: an attribute can't start with postfix '{}'",
                    ch as char
                ));
                i += 1;
                continue;
            };
            scan.reading = true;
            scan.sequence = s;
            scan.prefix = this_prefix.to_string();
        } else if scan.level >= 4 || ch != POSTFIXES[scan.level][scan.sequence] {
            warn(format!(
                "attribute '{kind}{}' ignored: its postfix sequence is invalid",
                scan.prefix
            ));
            scan.reset();
            while i < names.len() && same_prefix(i) {
                i += 1;
            }
            // Mitsuba then counts the next property as one field already read, and steps
            // past it.
            scan.level = 1;
            i += 1;
            continue;
        }
        scan.fields.push(i);
        scan.level += 1;
        i += 1;
    }
    scan.flush_if_reading(&mut warn);
    scan.out
}

/// The state of Mitsuba's scan over an element's properties.
struct Scan<'k> {
    kind: &'k str,
    out: Vec<AttributeFields>,
    encountered: Vec<String>,
    prefix: String,
    sequence: usize,
    /// Properties counted for the attribute being read (Mitsuba's `current_postfix_level_index`).
    level: usize,
    reading: bool,
    fields: Vec<usize>,
}

impl Scan<'_> {
    fn reset(&mut self) {
        self.prefix.clear();
        self.level = 0;
        self.reading = false;
        self.fields.clear();
    }

    fn flush_if_reading(&mut self, warn: &mut impl FnMut(String)) {
        if self.reading {
            self.flush(warn);
        }
    }

    /// Ends the attribute being read: kept if it has 1 or 3 properties.
    fn flush(&mut self, warn: &mut impl FnMut(String)) {
        let (kind, prefix) = (self.kind, &self.prefix);
        if (self.level == 1 || self.level == 3) && self.fields.len() == self.level {
            let suffix = if self.sequence == COLOR_SEQUENCE {
                "_color"
            } else {
                ""
            };
            self.out.push(AttributeFields {
                name: format!("{kind}{prefix}{suffix}"),
                fields: std::mem::take(&mut self.fields),
            });
            self.encountered.push(prefix.clone());
        } else {
            warn(format!(
                "attribute '{kind}{prefix}' ignored: it must have either 1 or 3 fields (had {})",
                self.level
            ));
        }
        self.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn group(names: &[&str]) -> (Vec<(String, Vec<usize>)>, usize) {
        let names: Vec<Option<&str>> = names.iter().map(|&n| Some(n)).collect();
        let mut warnings = 0;
        let g = group_attributes("vertex_", &names, &["x", "y", "z"], |_| warnings += 1);
        (
            g.into_iter().map(|a| (a.name, a.fields)).collect(),
            warnings,
        )
    }

    #[test]
    fn colours_and_prefixed_attributes() {
        let (g, w) = group(&["x", "y", "z", "red", "green", "blue", "weight_x"]);
        assert_eq!(
            g,
            vec![
                ("vertex_color".into(), vec![3, 4, 5]),
                ("vertex_weight".into(), vec![6])
            ]
        );
        assert_eq!(w, 0);
        let (g, _) = group(&[
            "x", "y", "z", "tint_r", "tint_g", "tint_b", "v_0", "v_1", "v_2",
        ]);
        assert_eq!(
            g,
            vec![
                ("vertex_tint_color".into(), vec![3, 4, 5]),
                ("vertex_v".into(), vec![6, 7, 8])
            ]
        );
    }

    #[test]
    fn what_mitsuba_ignores() {
        // No postfix, two fields, a postfix that starts no sequence, a repeated prefix.
        let (g, w) = group(&["x", "y", "z", "quality", "uv_x", "uv_y", "k_q"]);
        assert!(g.is_empty(), "{g:?}");
        assert_eq!(w, 3);
        let (g, w) = group(&["x", "y", "z", "w_x", "q_x", "w_x"]);
        assert_eq!(
            g,
            vec![("vertex_w".into(), vec![3]), ("vertex_q".into(), vec![4])]
        );
        assert_eq!(w, 1);
    }
}
