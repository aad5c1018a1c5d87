//! `cohort view --script FILE`: the viewer driven by a file of commands, one per line,
//! through the same actions as the keyboard and mouse (so a test exercises what a
//! person's input does). `#` starts a comment.
//!
//! | command | meaning |
//! |---|---|
//! | `key K` | press key K, as on the keyboard (`w`, `1`, `N`, `[`, `escape`, `tab`, ...) |
//! | `drag DX DY` | drag with the left button by (DX, DY) pixels: orbit |
//! | `pan DX DY` | drag with the right button: pan |
//! | `scroll LINES` | mouse wheel: dolly toward the pivot (positive) or away |
//! | `set NAME VALUE` | set a render option of the focused side (`set algorithm grid`) |
//! | `wait-paths N` | until every side has N paths per pixel since the last restart, on screen |
//! | `sleep MS` | wait MS milliseconds |
//! | `wait-file PATH` | until PATH exists |
//! | `screenshot PATH` | write the window as it is on screen (image and panel) as a PNG |
//! | `notify TEXT` | print one JSON line to stdout: TEXT, the window id, restart count, and each side's paths per pixel and paths per second of kernel time |
//! | `quit` | close the viewer |

use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a `wait-*` command waits before the script fails.
pub const WAIT_LIMIT: Duration = Duration::from_secs(600);

#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    Key(String),
    Drag(f32, f32),
    Pan(f32, f32),
    Scroll(f32),
    Set(String, String),
    WaitPaths(f64),
    Sleep(Duration),
    WaitFile(PathBuf),
    Screenshot(PathBuf),
    Notify(String),
    Quit,
}

/// A parsed script: each step with its line number, for error messages.
pub struct Script {
    pub path: PathBuf,
    pub steps: Vec<(usize, Step)>,
}

impl Script {
    pub fn load(path: &Path) -> Result<Script, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read the script: {e}", path.display()))?;
        let steps = parse(&text).map_err(|(line, e)| format!("{}:{line}: {e}", path.display()))?;
        Ok(Script {
            path: path.to_path_buf(),
            steps,
        })
    }
}

fn num<T: std::str::FromStr>(word: Option<&str>, what: &str) -> Result<T, String> {
    let w = word.ok_or_else(|| format!("missing {what}"))?;
    w.parse()
        .map_err(|_| format!("{what}: `{w}` is not a number"))
}

/// Parses a script's text; an error names the line (1-based).
pub fn parse(text: &str) -> Result<Vec<(usize, Step)>, (usize, String)> {
    let mut steps = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let (cmd, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        let mut words = rest.split_whitespace();
        let step = (|| -> Result<Step, String> {
            let step = match cmd {
                "key" if !rest.is_empty() && !rest.contains(char::is_whitespace) => {
                    Step::Key(rest.to_string())
                }
                "key" => return Err("expected one key: `key K`".into()),
                "drag" => Step::Drag(num(words.next(), "DX")?, num(words.next(), "DY")?),
                "pan" => Step::Pan(num(words.next(), "DX")?, num(words.next(), "DY")?),
                "scroll" => Step::Scroll(num(words.next(), "LINES")?),
                "set" => {
                    let name = words.next().ok_or("expected `set NAME VALUE`")?;
                    let value = words.next().ok_or("expected `set NAME VALUE`")?;
                    Step::Set(name.to_string(), value.to_string())
                }
                "wait-paths" => Step::WaitPaths(num(words.next(), "N")?),
                "sleep" => Step::Sleep(Duration::from_millis(num(words.next(), "MS")?)),
                "wait-file" if !rest.is_empty() => Step::WaitFile(PathBuf::from(rest)),
                "wait-file" => return Err("expected `wait-file PATH`".into()),
                "screenshot" if !rest.is_empty() => Step::Screenshot(PathBuf::from(rest)),
                "screenshot" => return Err("expected `screenshot PATH`".into()),
                "notify" => Step::Notify(rest.to_string()),
                "quit" => Step::Quit,
                other => {
                    return Err(format!(
                        "unknown command `{other}` (key, drag, pan, scroll, set, wait-paths, sleep, wait-file, screenshot, notify, quit)"
                    ))
                }
            };
            if matches!(cmd, "drag" | "pan" | "scroll" | "set" | "wait-paths" | "sleep" | "quit")
                && words.next().is_some()
            {
                return Err(format!("`{cmd}`: too many arguments"));
            }
            Ok(step)
        })()
        .map_err(|e| (line_no, e))?;
        steps.push((line_no, step));
    }
    Ok(steps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command_and_names_the_bad_line() {
        let s = parse(
            "# a comment\nkey r\ndrag 10 -5\npan 1 2\nscroll -1.5\nset algorithm grid\n\
             wait-paths 8\nsleep 20\nwait-file /tmp/x y\nscreenshot a.png\nnotify ready now\nquit # done\n",
        )
        .unwrap();
        let steps: Vec<Step> = s.into_iter().map(|(_, s)| s).collect();
        assert_eq!(
            steps,
            vec![
                Step::Key("r".into()),
                Step::Drag(10.0, -5.0),
                Step::Pan(1.0, 2.0),
                Step::Scroll(-1.5),
                Step::Set("algorithm".into(), "grid".into()),
                Step::WaitPaths(8.0),
                Step::Sleep(Duration::from_millis(20)),
                Step::WaitFile(PathBuf::from("/tmp/x y")),
                Step::Screenshot(PathBuf::from("a.png")),
                Step::Notify("ready now".into()),
                Step::Quit,
            ]
        );
        assert_eq!(parse("key r\n\ndrag 1\n").unwrap_err().0, 3);
        assert!(parse("jump 3")
            .unwrap_err()
            .1
            .contains("unknown command `jump`"));
        assert!(parse("wait-paths many")
            .unwrap_err()
            .1
            .contains("not a number"));
        assert!(parse("quit now").unwrap_err().1.contains("too many"));
        assert!(parse("key a b").is_err());
    }
}
