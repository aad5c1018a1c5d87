//! What the viewer's keys and mouse do, as actions: the window maps key presses and
//! drags to them, and a script (`--script`) names the same keys, so both take one path.

/// One user action on the viewer.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Drag with the left button by (dx, dy) pixels.
    Orbit(f32, f32),
    /// Drag with the right button.
    Pan(f32, f32),
    /// Mouse wheel lines: toward the pivot when positive.
    Dolly(f32),
    /// A step along the camera's (right, up, forward).
    Fly(f32, f32, f32),
    ResetCamera,
    /// A render option of the focused side, by its command-line name.
    Set(String, String),
    /// The n-th of the algorithms `--algorithm` lists.
    Algorithm(usize),
    /// N of the N x 4N patches times this factor.
    ScaleN(f32),
    /// The next value of a cycled option (`next_in_cycle`).
    Cycle(&'static str),
    /// Exposure change in stops.
    Exposure(f32),
    Save,
    /// Write the window as presented (image and panel) as a PNG.
    Screenshot(std::path::PathBuf),
    TogglePanel,
    /// Which side the configuration keys change (with `--compare`).
    SwitchSide,
    Quit,
}

/// The values of an option the keys cycle through, in order: the names of a choice (as the
/// command line lists them), off and on, or interleave factors. `None`: not a cycled option.
fn cycle(name: &str) -> Option<Vec<String>> {
    use crate::choices::{names, InPatchChoice, IntegratorChoice, RrChoice};
    Some(match name {
        "interleave" => ["1", "3", "5", "7", "9"].map(String::from).to_vec(),
        "compact" | "coherent-light" => vec!["off".into(), "on".into()],
        "rr" => names::<RrChoice>(),
        "integrator" => names::<IntegratorChoice>(),
        "in-patch" => names::<InPatchChoice>(),
        _ => return None,
    })
}

/// The value after `current` in the cycle of `name` (the first one if `current` is not
/// in it).
pub fn next_in_cycle(name: &str, current: &str) -> Option<String> {
    let values = cycle(name)?;
    let i = values.iter().position(|v| v == current);
    Some(values[i.map_or(0, |i| (i + 1) % values.len())].clone())
}

/// The action of a key, by the name a script uses: the character it types (`w`, `N`,
/// `[`), or `escape`, `tab`, `left`, `right`, `up`, `down`.
pub fn key_action(key: &str) -> Option<Action> {
    Some(match key {
        "w" => Action::Fly(0.0, 0.0, 1.0),
        "s" => Action::Fly(0.0, 0.0, -1.0),
        "a" => Action::Fly(-1.0, 0.0, 0.0),
        "d" => Action::Fly(1.0, 0.0, 0.0),
        "e" => Action::Fly(0.0, 1.0, 0.0),
        "q" => Action::Fly(0.0, -1.0, 0.0),
        "left" => Action::Orbit(-20.0, 0.0),
        "right" => Action::Orbit(20.0, 0.0),
        "up" => Action::Orbit(0.0, -20.0),
        "down" => Action::Orbit(0.0, 20.0),
        "r" => Action::ResetCamera,
        "1" | "2" | "3" | "4" | "5" | "6" => Action::Algorithm(key.parse::<usize>().ok()? - 1),
        "n" => Action::ScaleN(2.0),
        "N" | "m" => Action::ScaleN(0.5),
        "i" => Action::Cycle("interleave"),
        "g" => Action::Cycle("rr"),
        "c" => Action::Cycle("compact"),
        "l" => Action::Cycle("integrator"),
        "k" => Action::Cycle("coherent-light"),
        "u" => Action::Cycle("in-patch"),
        "[" => Action::Exposure(-0.5),
        "]" => Action::Exposure(0.5),
        "p" => Action::Save,
        "h" => Action::TogglePanel,
        "tab" => Action::SwitchSide,
        "escape" => Action::Quit,
        _ => return None,
    })
}

/// The keys, as the panel lists them.
pub const HELP: &[&str] = &[
    "drag: orbit  right-drag: pan  wheel: dolly",
    "W A S D Q E: fly   arrows: orbit   R: reset",
    "1-6: normal warp block_256/512/1024 grid",
    "n / N: N x2 / x0.5   i: interleave D",
    "g: roulette path/group/whole  c: compaction",
    "l: integrator  k: coherent light  u: in-patch",
    "[ ]: exposure   p: save EXR+PNG   h: panel",
    "tab: side the keys change   Esc: quit",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cycle_wraps_and_every_listed_key_acts() {
        let next = |name, current| next_in_cycle(name, current).unwrap();
        assert_eq!(next("interleave", "9"), "1");
        assert_eq!(next("rr", "path"), "group");
        assert_eq!(next("in-patch", "equal-area"), "uniform");
        assert_eq!(next("compact", "true"), "off");
        assert_eq!(next_in_cycle("colour", "red"), None);
        for k in [
            "w", "a", "s", "d", "q", "e", "r", "1", "6", "n", "N", "i", "g", "c", "l", "k", "u",
            "[", "]", "p", "h", "tab", "escape", "left",
        ] {
            assert!(key_action(k).is_some(), "{k}");
        }
        assert_eq!(key_action("7"), None);
        assert_eq!(key_action("3"), Some(Action::Algorithm(2)));
    }
}
