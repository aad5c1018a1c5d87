//! The documentation names only what exists (the clean-up that came with the CPU backend;
//! the newcomer's README and docs):
//!
//! - every repository file the README, `docs/*.md` and BENCHMARKS.md name in backticks or
//!   link to exists (placeholders such as `DIR/figures.csv`, an all-capitals component, are
//!   not checked; a backticked path is relative to the repository or to the `tests` crate,
//!   the compile-fail cases; a link is relative to its document);
//! - the README and `docs/*.md` point nowhere outside the repository: no `../` path that
//!   leaves it, and no mention of PAPER.md, ARCHITECTURE.md or TOOLCHAIN.md, which are not
//!   in it;
//! - every `cohort SUBCOMMAND ... --flag` they show (in backticks or in a code block, also
//!   as `cargo run -p cohort-cli -- SUBCOMMAND ...`) uses a flag that subcommand has, and
//!   every backticked span that starts with a flag (`--paths P`) names a flag of some
//!   subcommand. The flags are read from the CLI's sources (`cli/src/**/*.rs`: the clap
//!   derive attributes, `#[arg(long)]` on a field `foo_bar` is `--foo-bar`) when the test
//!   runs, so the check follows the CLI as it is edited, without building it.
//!
//! BENCHMARKS.md is a dated log: its commands are what ran then, so only its paths are
//! checked. Each failure names the file, the line and the path or flag.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Component, Path, PathBuf};

const EXTENSIONS: &[&str] = &[
    "rs", "md", "py", "sh", "toml", "xml", "json", "yaml", "yml", "exr", "csv", "png", "gz",
];

/// Files outside the repository that earlier documentation cited.
const OUTSIDE_FILES: &[&str] = &["PAPER.md", "ARCHITECTURE.md", "TOOLCHAIN.md"];

/// Flags of other programs that documentation shows on their own in backticks (cargo,
/// the test harness, scripts).
const OTHER_PROGRAMS_FLAGS: &[&str] = &[
    "release",
    "workspace",
    "locked",
    "test",
    "tests",
    "example",
    "examples",
    "package",
    "path",
    "bin",
    "lib",
    "all-targets",
    "no-run",
    "features",
    "nocapture",
    "test-threads",
    "ignored",
    "include-ignored",
    "exact",
    "message-format",
    "manifest-path",
];

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

// ---------------------------------------------------------------------------------------
// Markdown: code spans, code blocks and links, with their lines.

/// A piece of code in a Markdown file: an inline code span (newlines inside it read as
/// spaces) or one line of a fenced block (lines ending in `\` joined with the next).
#[derive(Debug, PartialEq)]
struct Code {
    line: usize,
    text: String,
    block: bool,
}

fn code_pieces(text: &str) -> Vec<Code> {
    let mut out = Vec::new();
    // Prose is gathered paragraph by paragraph (a code span does not cross a blank line
    // or a fence), with the line number of each character's line.
    let mut prose = String::new();
    let mut prose_lines: Vec<usize> = Vec::new();
    let mut fence: Option<(char, usize)> = None;
    let mut pending: Option<(usize, String)> = None;
    let flush = |prose: &mut String, lines: &mut Vec<usize>, out: &mut Vec<Code>| {
        inline_spans(prose, lines, out);
        prose.clear();
        lines.clear();
    };
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let trimmed = line.trim_start();
        let fence_here = ['`', '~'].into_iter().find_map(|c| {
            let run = trimmed.chars().take_while(|&x| x == c).count();
            (run >= 3).then_some((c, run))
        });
        match (fence, fence_here) {
            (None, Some(f)) => {
                flush(&mut prose, &mut prose_lines, &mut out);
                fence = Some(f);
                continue;
            }
            (Some((c, len)), Some((c2, len2))) if c == c2 && len2 >= len => {
                if let Some((l, t)) = pending.take() {
                    out.push(Code {
                        line: l,
                        text: t,
                        block: true,
                    });
                }
                fence = None;
                continue;
            }
            _ => {}
        }
        if fence.is_some() {
            let (start, mut joined) = pending.take().unwrap_or((n, String::new()));
            match line.strip_suffix('\\') {
                Some(head) => {
                    joined.push_str(head);
                    joined.push(' ');
                    pending = Some((start, joined));
                }
                None => {
                    joined.push_str(line);
                    out.push(Code {
                        line: start,
                        text: joined,
                        block: true,
                    });
                }
            }
            continue;
        }
        if line.trim().is_empty() {
            flush(&mut prose, &mut prose_lines, &mut out);
            continue;
        }
        for _ in line.chars() {
            prose_lines.push(n);
        }
        prose.push_str(line);
        prose.push('\n');
        prose_lines.push(n);
    }
    flush(&mut prose, &mut prose_lines, &mut out);
    out
}

/// The code spans of one paragraph: a run of k backticks up to the next run of exactly k.
fn inline_spans(prose: &str, lines: &[usize], out: &mut Vec<Code>) {
    let chars: Vec<char> = prose.chars().collect();
    let run_at = |i: usize| chars[i..].iter().take_while(|&&c| c == '`').count();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            i += 1;
            continue;
        }
        let k = run_at(i);
        let mut j = i + k;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let r = run_at(j);
                if r == k {
                    close = Some(j);
                    break;
                }
                j += r;
            } else {
                j += 1;
            }
        }
        match close {
            Some(j) => {
                let body: String = chars[i + k..j]
                    .iter()
                    .map(|&c| if c == '\n' { ' ' } else { c })
                    .collect();
                out.push(Code {
                    line: lines[i],
                    text: body.trim().to_string(),
                    block: false,
                });
                i = j + k;
            }
            None => i += k,
        }
    }
}

/// The targets of the Markdown links and images outside code blocks, with their lines:
/// `[text](target)`, `![alt](target "title")`.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") || line.trim_start().starts_with("~~~") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let tail = &rest[at + 2..];
            let end = tail.find(')').unwrap_or(tail.len());
            let target = tail[..end].split_whitespace().next().unwrap_or("");
            out.push((i + 1, target.to_string()));
            rest = &tail[end..];
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Paths.

/// `span` when the whole backticked span is a repository path (`path:line` and
/// `path:line-line` name a place in the file).
fn named_path(span: &str) -> Option<String> {
    let path = span.split(':').next().unwrap_or("");
    let plausible = path.contains('/')
        && !path.starts_with("../")
        && !path.starts_with("...")
        && !path.starts_with('/')
        && path
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_./-".contains(c))
        && EXTENSIONS.iter().any(|e| path.ends_with(&format!(".{e}")));
    let placeholder = path.split('/').any(|c| {
        let stem = c.split('.').next().unwrap_or("");
        !stem.is_empty() && stem.chars().all(|ch| ch.is_ascii_uppercase() || ch == '_')
    });
    (plausible && !placeholder).then(|| path.to_string())
}

/// The backticked spans of `text` that look like repository paths.
fn named_paths(text: &str) -> Vec<String> {
    code_pieces(text)
        .into_iter()
        .filter(|c| !c.block)
        .filter_map(|c| named_path(&c.text))
        .collect()
}

/// `rel` joined to `base` with `..` resolved; `None` when it climbs above `root`.
fn resolve_inside(root: &Path, base: &Path, rel: &str) -> Option<PathBuf> {
    let mut parts: Vec<String> = base
        .strip_prefix(root)
        .ok()?
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    for c in Path::new(rel).components() {
        match c {
            Component::ParentDir => {
                parts.pop()?;
            }
            Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
            Component::CurDir => {}
            _ => return None,
        }
    }
    Some(parts.iter().fold(root.to_path_buf(), |p, s| p.join(s)))
}

fn is_external_link(target: &str) -> bool {
    target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:")
}

struct Doc {
    path: PathBuf,
    /// The path relative to the repository, for messages.
    name: String,
    text: String,
    /// README.md and docs/*.md, for users: held to the outside-reference and flag checks.
    user: bool,
}

fn docs() -> Vec<Doc> {
    let root = repo();
    let mut paths = vec![
        (root.join("README.md"), true),
        (root.join("BENCHMARKS.md"), false),
    ];
    let mut in_docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    in_docs.sort();
    paths.extend(in_docs.into_iter().map(|p| (p, true)));
    paths
        .into_iter()
        .map(|(path, user)| Doc {
            name: path.strip_prefix(&root).unwrap().display().to_string(),
            text: std::fs::read_to_string(&path).unwrap(),
            path,
            user,
        })
        .collect()
}

#[test]
fn documented_paths_exist() {
    let root = repo();
    let mut missing = Vec::new();
    let mut checked = 0;
    for doc in docs() {
        for code in code_pieces(&doc.text).into_iter().filter(|c| !c.block) {
            let Some(path) = named_path(&code.text) else {
                continue;
            };
            checked += 1;
            if !root.join(&path).exists() && !root.join("tests").join(&path).exists() {
                missing.push(format!("{}:{}: `{path}`", doc.name, code.line));
            }
        }
        let dir = doc.path.parent().unwrap();
        for (line, target) in link_targets(&doc.text) {
            if is_external_link(&target) {
                continue;
            }
            let file = target.split('#').next().unwrap();
            checked += 1;
            match resolve_inside(&root, dir, file) {
                Some(p) if p.exists() => {}
                Some(_) => missing.push(format!("{}:{line}: link to `{target}`", doc.name)),
                None => missing.push(format!(
                    "{}:{line}: link to `{target}` leaves the repository",
                    doc.name
                )),
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} paths found: is the scan broken?"
    );
    assert!(
        missing.is_empty(),
        "documentation names files that do not exist:\n{}",
        missing.join("\n")
    );
}

/// What in `doc` points outside the repository: `../` that leaves it (a link from `docs/`
/// to `../deploy/README.md` stays inside), and the files of [`OUTSIDE_FILES`].
fn outside_references(root: &Path, doc: &Doc) -> Vec<String> {
    let dir = doc.path.parent().unwrap();
    let inside_links: BTreeSet<(usize, String)> = link_targets(&doc.text)
        .into_iter()
        .filter(|(_, t)| {
            !is_external_link(t)
                && resolve_inside(root, dir, t.split('#').next().unwrap()).is_some()
        })
        .collect();
    let mut bad = Vec::new();
    for (i, line) in doc.text.lines().enumerate() {
        let n = i + 1;
        for name in OUTSIDE_FILES {
            if line.contains(name) {
                bad.push(format!(
                    "{}:{n}: names {name}, which is not in the repository",
                    doc.name
                ));
            }
        }
        let mut from = 0;
        while let Some(at) = line[from..].find("../") {
            let at = from + at;
            from = at + 3;
            // `.../NAME` is an ellipsis, not a parent folder.
            if line[..at].ends_with('.') {
                continue;
            }
            let word_start = line[..at]
                .rfind(|c: char| c.is_whitespace() || "`(\"'<[".contains(c))
                .map_or(0, |s| s + 1);
            let word: String = line[word_start..]
                .chars()
                .take_while(|c| !c.is_whitespace() && !"`)\"'>]".contains(*c))
                .collect();
            if inside_links.contains(&(n, word.clone())) {
                continue;
            }
            bad.push(format!(
                "{}:{n}: `{word}` is a path outside the repository",
                doc.name
            ));
        }
    }
    bad
}

#[test]
fn user_docs_point_nowhere_outside_the_repository() {
    let root = repo();
    let bad: Vec<String> = docs()
        .iter()
        .filter(|d| d.user)
        .flat_map(|d| outside_references(&root, d))
        .collect();
    assert!(
        bad.is_empty(),
        "README.md and docs/*.md must cite only what the repository holds:\n{}",
        bad.join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// The CLI's flags, read from its sources.

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Punct(char),
    /// A string or char literal's contents.
    Lit(String),
}

/// Rust source as tokens, comments dropped (enough of Rust's lexical grammar for clap's
/// derive attributes and the items that carry them).
fn lex(src: &str) -> Vec<Tok> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            let mut s = String::new();
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                if i < c.len() {
                    s.push(c[i]);
                }
                i += 1;
            }
            i += 1;
            out.push(Tok::Lit(s));
        } else if (ch == 'r' || ch == 'b') && {
            let mut j = i + 1;
            if ch == 'b' && c.get(j) == Some(&'r') {
                j += 1;
            }
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            c.get(j) == Some(&'"') && (ch == 'r' || j > i + 1)
        } {
            // Raw (byte) string: r"..", r#".."#.
            let mut j = i + 1;
            if ch == 'b' && c.get(j) == Some(&'r') {
                j += 1;
            }
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            j += 1;
            let mut s = String::new();
            while j < c.len() {
                if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                s.push(c[j]);
                j += 1;
            }
            i = j;
            out.push(Tok::Lit(s));
        } else if ch == '\'' {
            // A char literal ('D', '\n') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                let mut j = i + 2;
                while j < c.len() && c[j] != '\'' {
                    j += 1;
                }
                out.push(Tok::Lit(c[i + 2..j].iter().collect()));
                i = j + 1;
            } else if c.get(i + 2) == Some(&'\'') {
                out.push(Tok::Lit(c[i + 1].to_string()));
                i += 3;
            } else {
                let mut j = i + 1;
                while j < c.len() && (c[j].is_alphanumeric() || c[j] == '_') {
                    j += 1;
                }
                out.push(Tok::Ident(c[i..j].iter().collect()));
                i = j;
            }
        } else if ch.is_alphanumeric() || ch == '_' {
            let mut j = i;
            while j < c.len() && (c[j].is_alphanumeric() || c[j] == '_') {
                j += 1;
            }
            out.push(Tok::Ident(c[i..j].iter().collect()));
            i = j;
        } else {
            out.push(Tok::Punct(ch));
            i += 1;
        }
    }
    out
}

fn is_punct(t: Option<&Tok>, p: char) -> bool {
    t == Some(&Tok::Punct(p))
}

fn ident(t: Option<&Tok>) -> Option<&str> {
    match t {
        Some(Tok::Ident(s)) => Some(s),
        _ => None,
    }
}

/// The index just past the group that opens at `open` (`(`, `[` or `{`).
fn group_end(toks: &[Tok], open: usize) -> usize {
    let mut depth = 0i32;
    let mut i = open;
    while i < toks.len() {
        match toks[i] {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => {
                depth -= 1;
                if depth == 0 {
                    return i + 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    toks.len()
}

/// Splits `toks` at the commas outside any group (and, with `angles`, outside `<..>`).
/// Angles count only outside brackets: inside an attribute, `<` is an operator
/// (`default_value_t = 1 << 17`), not a type's generics.
fn split_commas(toks: &[Tok], angles: bool) -> Vec<&[Tok]> {
    let mut out = Vec::new();
    let (mut depth, mut angle, mut start) = (0i32, 0i32, 0);
    for (i, t) in toks.iter().enumerate() {
        match t {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => depth -= 1,
            Tok::Punct('<') if angles && depth == 0 => angle += 1,
            Tok::Punct('>')
                if angles && depth == 0 && !(i > 0 && is_punct(toks.get(i - 1), '-')) =>
            {
                angle -= 1
            }
            Tok::Punct(',') if depth == 0 && angle == 0 => {
                out.push(&toks[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    if start < toks.len() {
        out.push(&toks[start..]);
    }
    out
}

/// One `#[...]` attribute: its path (`arg`, `command`, `derive`, ...) and the items of its
/// parenthesised list, each as tokens.
#[derive(Debug, Default)]
struct Attr {
    path: String,
    items: Vec<Vec<Tok>>,
}

impl Attr {
    fn parse(inner: &[Tok]) -> Attr {
        let path = ident(inner.first()).unwrap_or("").to_string();
        let items = match inner.iter().position(|t| is_punct(Some(t), '(')) {
            Some(open) => {
                let end = group_end(inner, open);
                split_commas(&inner[open + 1..end - 1], false)
                    .into_iter()
                    .map(<[Tok]>::to_vec)
                    .collect()
            }
            None => Vec::new(),
        };
        Attr { path, items }
    }

    /// `key` alone in the list.
    fn has(&self, key: &str) -> bool {
        self.items
            .iter()
            .any(|it| it.len() == 1 && ident(it.first()) == Some(key))
    }

    /// The literals of `key = "x"` or `key = ["x", "y"]`.
    fn values(&self, key: &str) -> Vec<String> {
        self.items
            .iter()
            .filter(|it| ident(it.first()) == Some(key) && is_punct(it.get(1), '='))
            .flat_map(|it| {
                it[2..].iter().filter_map(|t| match t {
                    Tok::Lit(s) => Some(s.clone()),
                    _ => None,
                })
            })
            .collect()
    }

    fn derives(&self, what: &str) -> bool {
        self.path == "derive"
            && self
                .items
                .iter()
                .any(|it| it.iter().rev().find_map(|t| ident(Some(t))) == Some(what))
    }
}

/// A field of a struct or enum variant: its name, attributes and type's path outside
/// `<..>` (`crate::RenderArgs` is `["crate", "RenderArgs"]`).
#[derive(Debug)]
struct Field {
    name: String,
    attrs: Vec<Attr>,
    ty: Vec<String>,
}

#[derive(Debug)]
struct Variant {
    name: String,
    attrs: Vec<Attr>,
    /// `Render(figures::FiguresArgs)`: `["figures", "FiguresArgs"]`.
    ty: Option<Vec<String>>,
    /// `Render { .. }`: inline fields.
    fields: Vec<Field>,
}

/// A struct or enum of clap's, and the module it is in (`figures::merge`; `` for the
/// crate's root).
#[derive(Debug)]
struct Def<T> {
    module: String,
    name: String,
    attrs: Vec<Attr>,
    body: Vec<T>,
}

#[derive(Debug, Default)]
struct Items {
    structs: Vec<Def<Field>>,
    enums: Vec<Def<Variant>>,
}

/// The definition a type path written in module `from` names: the one in the module the
/// path leads to, else the only one of that name, else the first.
fn resolve<'a, T>(defs: &'a [Def<T>], from: &str, path: &[String]) -> Option<&'a Def<T>> {
    let (name, prefix) = path.split_last()?;
    let join = |a: &[&str]| {
        a.iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join("::")
    };
    let mut module: Vec<&str> = from.split("::").filter(|s| !s.is_empty()).collect();
    for seg in prefix {
        match seg.as_str() {
            "crate" => module.clear(),
            "super" => {
                module.pop();
            }
            "self" => {}
            other => module.push(other),
        }
    }
    let wanted = join(&module);
    let absolute = join(&prefix.iter().map(String::as_str).collect::<Vec<_>>());
    let named: Vec<&Def<T>> = defs.iter().filter(|d| &d.name == name).collect();
    named
        .iter()
        .find(|d| d.module == wanted)
        .or_else(|| named.iter().find(|d| d.module == absolute))
        .or_else(|| named.first())
        .copied()
}

fn type_path(toks: &[Tok]) -> Vec<String> {
    let mut depth = 0;
    let mut path = Vec::new();
    for (i, t) in toks.iter().enumerate() {
        match t {
            Tok::Punct('<') => depth += 1,
            Tok::Punct('>') if !is_punct(i.checked_sub(1).and_then(|j| toks.get(j)), '-') => {
                depth -= 1
            }
            Tok::Ident(s)
                if depth == 0
                    && !["dyn", "impl", "mut"].contains(&s.as_str())
                    && !s.starts_with('\'') =>
            {
                path.push(s.clone())
            }
            _ => {}
        }
    }
    path
}

/// Leading `#[..]` attributes of `toks` from `i`, and the index after them (and after a
/// visibility).
fn take_attrs(toks: &[Tok], mut i: usize) -> (Vec<Attr>, usize) {
    let mut attrs = Vec::new();
    loop {
        if is_punct(toks.get(i), '#') && is_punct(toks.get(i + 1), '[') {
            let end = group_end(toks, i + 1);
            attrs.push(Attr::parse(&toks[i + 2..end - 1]));
            i = end;
        } else if ident(toks.get(i)) == Some("pub") {
            i += 1;
            if is_punct(toks.get(i), '(') {
                i = group_end(toks, i);
            }
        } else {
            return (attrs, i);
        }
    }
}

fn parse_fields(body: &[Tok]) -> Vec<Field> {
    split_commas(body, true)
        .into_iter()
        .filter_map(|f| {
            let (attrs, i) = take_attrs(f, 0);
            let name = ident(f.get(i))?.to_string();
            is_punct(f.get(i + 1), ':').then(|| Field {
                name,
                attrs,
                ty: type_path(&f[i + 2..]),
            })
        })
        .collect()
}

fn parse_items(src: &str, module: &str, items: &mut Items) {
    let toks = lex(src);
    let mut i = 0;
    while i < toks.len() {
        let (attrs, j) = take_attrs(&toks, i);
        let (kw, name) = (ident(toks.get(j)), ident(toks.get(j + 1)));
        match (kw, name) {
            (Some(kw @ ("struct" | "enum")), Some(name)) => {
                let Some(open) =
                    (j + 2..toks.len()).find(|&k| matches!(toks[k], Tok::Punct('{' | ';' | '(')))
                else {
                    break;
                };
                if !is_punct(toks.get(open), '{') {
                    i = open + 1;
                    continue;
                }
                let end = group_end(&toks, open);
                let body = &toks[open + 1..end - 1];
                // Only clap's types: other files have their own `Command`s.
                let clap = ["Parser", "Args", "Subcommand"]
                    .iter()
                    .any(|d| attrs.iter().any(|a| a.derives(d)));
                if !clap {
                    i = end;
                    continue;
                }
                let (module, name) = (module.to_string(), name.to_string());
                if kw == "struct" {
                    let body = parse_fields(body);
                    items.structs.push(Def {
                        module,
                        name,
                        attrs,
                        body,
                    });
                } else {
                    let variants = split_commas(body, true)
                        .into_iter()
                        .filter_map(|v| {
                            let (attrs, k) = take_attrs(v, 0);
                            let name = ident(v.get(k))?.to_string();
                            let (ty, fields) = if is_punct(v.get(k + 1), '(') {
                                let e = group_end(v, k + 1);
                                (Some(type_path(&v[k + 2..e - 1])), Vec::new())
                            } else if is_punct(v.get(k + 1), '{') {
                                let e = group_end(v, k + 1);
                                (None, parse_fields(&v[k + 2..e - 1]))
                            } else {
                                (None, Vec::new())
                            };
                            Some(Variant {
                                name,
                                attrs,
                                ty,
                                fields,
                            })
                        })
                        .collect();
                    items.enums.push(Def {
                        module,
                        name,
                        attrs,
                        body: variants,
                    });
                }
                // Items nested in the body (none in clap's types) are not looked for.
                i = end;
            }
            _ => i = j.max(i + 1),
        }
    }
}

/// `FiguresMerge` -> `figures-merge`, `end_continue` -> `end-continue`.
fn kebab(name: &str) -> String {
    let mut out = String::new();
    for (k, ch) in name.chars().enumerate() {
        if ch.is_uppercase() && k > 0 {
            out.push('-');
        }
        out.extend(ch.to_lowercase());
    }
    out.replace('_', "-")
}

/// The flags a field defines: `--long` names and `-s` short ones (with the dashes).
fn field_flags(f: &Field) -> Vec<String> {
    let mut out = Vec::new();
    for a in f
        .attrs
        .iter()
        .filter(|a| a.path == "arg" || a.path == "clap")
    {
        if a.has("long") {
            out.push(format!("--{}", kebab(&f.name)));
        }
        for v in a.values("long") {
            out.push(format!("--{v}"));
        }
        for key in ["alias", "aliases", "visible_alias", "visible_aliases"] {
            out.extend(a.values(key).into_iter().map(|v| format!("--{v}")));
        }
        if a.has("short") {
            out.push(format!("-{}", f.name.chars().next().unwrap()));
        }
        for key in [
            "short",
            "short_alias",
            "short_aliases",
            "visible_short_alias",
        ] {
            out.extend(a.values(key).into_iter().map(|v| format!("-{v}")));
        }
    }
    out
}

fn is_flatten(f: &Field) -> bool {
    f.attrs
        .iter()
        .any(|a| (a.path == "command" || a.path == "clap") && a.has("flatten"))
}

fn fields_flags(
    items: &Items,
    module: &str,
    fields: &[Field],
    depth: usize,
    out: &mut BTreeSet<String>,
) {
    for f in fields {
        out.extend(field_flags(f));
        if is_flatten(f) && depth < 8 {
            if let Some(inner) = resolve(&items.structs, module, &f.ty) {
                fields_flags(items, &inner.module, &inner.body, depth + 1, out);
            }
        }
    }
}

/// The CLI as its sources define it: each subcommand's flags (`None` for a subcommand
/// that has subcommands of its own, whose flags are not checked).
#[derive(Debug)]
struct CliFlags {
    commands: BTreeMap<String, Option<BTreeSet<String>>>,
}

impl CliFlags {
    fn from_items(items: &Items) -> Result<CliFlags, String> {
        let derives = |attrs: &[Attr], what: &str| attrs.iter().any(|a| a.derives(what));
        let top = items
            .structs
            .iter()
            .find(|d| derives(&d.attrs, "Parser"))
            .ok_or("no struct derives clap::Parser")?;
        let subcommand_ty = top
            .body
            .iter()
            .find(|f| {
                f.attrs
                    .iter()
                    .any(|a| a.path == "command" && a.has("subcommand"))
            })
            .map(|f| f.ty.clone())
            .ok_or("the Parser struct has no #[command(subcommand)] field")?;
        let commands_enum = resolve(&items.enums, &top.module, &subcommand_ty)
            .ok_or(format!("no enum {}", subcommand_ty.join("::")))?;
        let mut global: BTreeSet<String> =
            ["--help", "-h", "--version", "-V"].map(String::from).into();
        let global_arg = |a: &Attr| a.items.iter().any(|it| ident(it.first()) == Some("global"));
        for f in &top.body {
            if f.attrs.iter().any(global_arg) {
                global.extend(field_flags(f));
            }
        }
        let module = commands_enum.module.as_str();
        let mut commands = BTreeMap::new();
        for v in &commands_enum.body {
            let mut names = vec![kebab(&v.name)];
            for a in v
                .attrs
                .iter()
                .filter(|a| a.path == "command" || a.path == "clap")
            {
                if let Some(n) = a.values("name").pop() {
                    names[0] = n;
                }
                for key in ["alias", "aliases", "visible_alias", "visible_aliases"] {
                    names.extend(a.values(key));
                }
            }
            let mut set = global.clone();
            let flags = match &v.ty {
                Some(ty) => {
                    if let Some(inner) = resolve(&items.structs, module, ty) {
                        fields_flags(items, &inner.module, &inner.body, 0, &mut set);
                        Some(set)
                    } else if resolve(&items.enums, module, ty).is_some() {
                        None
                    } else {
                        return Err(format!(
                            "subcommand {} takes {}, which is not defined",
                            v.name,
                            ty.join("::")
                        ));
                    }
                }
                None => {
                    fields_flags(items, module, &v.fields, 0, &mut set);
                    Some(set)
                }
            };
            for n in names {
                commands.insert(n, flags.clone());
            }
        }
        Ok(CliFlags { commands })
    }

    fn read() -> CliFlags {
        fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
            for e in std::fs::read_dir(dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk(&p, out);
                } else if p.extension().is_some_and(|e| e == "rs") {
                    out.push(p);
                }
            }
        }
        let src_dir = repo().join("cli/src");
        let mut files = Vec::new();
        walk(&src_dir, &mut files);
        files.sort();
        let mut items = Items::default();
        for f in files {
            // `figures/merge.rs` is module `figures::merge`; `main.rs`, `lib.rs` and a
            // folder's `mod.rs` are their folder's module.
            let rel = f.strip_prefix(&src_dir).unwrap().with_extension("");
            let mut module: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if matches!(
                module.last().map(String::as_str),
                Some("mod" | "main" | "lib")
            ) {
                module.pop();
            }
            // A file being rewritten by an editor at this moment may be unreadable for an
            // instant; the next run reads it.
            if let Ok(src) = std::fs::read_to_string(&f) {
                parse_items(&src, &module.join("::"), &mut items);
            }
        }
        let cli = CliFlags::from_items(&items)
            .unwrap_or_else(|e| panic!("cannot read the CLI's definitions in cli/src: {e}"));
        let render = cli
            .commands
            .get("render")
            .cloned()
            .flatten()
            .unwrap_or_default();
        assert!(
            render.len() > 15 && render.contains("--paths"),
            "the scan of cli/src found too few flags of `cohort render` ({render:?}): is it broken?"
        );
        cli
    }

    fn all_flags(&self) -> BTreeSet<&str> {
        self.commands
            .values()
            .flatten()
            .flatten()
            .map(String::as_str)
            .collect()
    }
}

/// The flag a shell word starts with (`--out-dir=x` -> `--out-dir`, `-D` of `-DNAME=1`,
/// `[--out-dir` -> `--out-dir`); `None` for other words and negative numbers.
fn flag_of(word: &str) -> Option<String> {
    let w = word.trim_start_matches(['[', '(']);
    if let Some(long) = w.strip_prefix("--") {
        let name: String = long
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
            .collect();
        return (!name.is_empty()).then(|| format!("--{name}"));
    }
    let mut it = w.chars();
    match (it.next(), it.next()) {
        (Some('-'), Some(c)) if c.is_ascii_alphabetic() => Some(format!("-{c}")),
        _ => None,
    }
}

/// The `cohort` commands in a piece of code: (subcommand, flags), a command ending at a
/// shell separator or comment. `cargo run ... -p cohort-cli -- SUB` counts as `cohort SUB`.
fn commands_in(code: &str) -> Vec<(String, Vec<String>)> {
    let words: Vec<&str> = code.split_whitespace().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < words.len() {
        let w = words[i].trim_start_matches(['(', '"', '\'']);
        let sub_at = if w == "cohort" || w.ends_with("/cohort") {
            Some(i + 1)
        } else if w == "cohort-cli" && words.get(i + 1) == Some(&"--") {
            Some(i + 2)
        } else {
            None
        };
        let Some(s) = sub_at else {
            i += 1;
            continue;
        };
        let Some(sub) = words
            .get(s)
            .filter(|x| !x.is_empty() && x.chars().all(|c| c.is_ascii_lowercase() || c == '-'))
        else {
            i += 1;
            continue;
        };
        let mut flags = Vec::new();
        let mut k = s + 1;
        while k < words.len() {
            let x = words[k];
            if ["|", "||", "&&", ";", ">", "2>&1"].contains(&x) || x.starts_with('#') {
                break;
            }
            // `--width/--height`: two flags.
            for part in x.split('/') {
                if let Some(f) = flag_of(part) {
                    if part.trim_start_matches(['[', '(']).starts_with('-') {
                        flags.push(f);
                    }
                }
            }
            k += 1;
        }
        out.push((sub.to_string(), flags));
        i = k;
    }
    out
}

/// The flags in `doc`'s commands that the CLI lacks, as messages.
fn unknown_flags(cli: &CliFlags, doc: &Doc) -> Vec<String> {
    let all = cli.all_flags();
    let mut bad = Vec::new();
    for code in code_pieces(&doc.text) {
        let commands = commands_in(&code.text);
        for (sub, flags) in &commands {
            match cli.commands.get(sub) {
                Some(Some(known)) => {
                    for f in flags.iter().filter(|f| !known.contains(*f)) {
                        bad.push(format!(
                            "{}:{}: `cohort {sub}` has no flag {f} (in `{}`)",
                            doc.name, code.line, code.text
                        ));
                    }
                }
                Some(None) => {}
                None if !flags.is_empty() => bad.push(format!(
                    "{}:{}: `cohort {sub}` is not a subcommand (in `{}`)",
                    doc.name, code.line, code.text
                )),
                None => {}
            }
        }
        // A span that starts with a long flag (`--paths P`) names an option of some
        // subcommand (or of cargo and the test harness). Short ones are left alone: `-a`
        // is also Rust.
        if commands.is_empty() && !code.block {
            let first = code
                .text
                .split_whitespace()
                .next()
                .filter(|w| w.starts_with("--"));
            if let Some(f) = first.and_then(flag_of) {
                let other = f
                    .strip_prefix("--")
                    .is_some_and(|n| OTHER_PROGRAMS_FLAGS.contains(&n));
                if !all.contains(f.as_str()) && !other {
                    bad.push(format!(
                        "{}:{}: no subcommand of `cohort` has the flag {f} (in `{}`)",
                        doc.name, code.line, code.text
                    ));
                }
            }
        }
    }
    bad
}

#[test]
fn documented_flags_exist() {
    let cli = CliFlags::read();
    let mut checked = 0;
    let mut bad = Vec::new();
    for doc in docs().iter().filter(|d| d.user) {
        checked += code_pieces(&doc.text)
            .iter()
            .map(|c| commands_in(&c.text).len())
            .sum::<usize>();
        bad.extend(unknown_flags(&cli, doc));
    }
    assert!(
        checked > 10,
        "only {checked} commands found: is the scan broken?"
    );
    assert!(
        bad.is_empty(),
        "documentation shows flags the CLI does not have (cli/src):\n{}",
        bad.join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// The scanners themselves.

#[test]
fn the_scan_finds_paths_and_skips_placeholders() {
    let text = "see `render/src/lights.rs:12-40`, `../shared/x.md`, `DIR/figures.csv`, \
                `cohort render`, `a/b.txt` and `docs/results/x.csv.gz`";
    assert_eq!(
        named_paths(text),
        ["render/src/lights.rs", "docs/results/x.csv.gz"]
    );
}

#[test]
fn the_scan_finds_spans_blocks_and_their_lines() {
    let text =
        "One `a b`\nand `c\nd` here.\n\n```sh\ncohort render \\\n  --paths 4\nx\n```\n``k`l``\n";
    let pieces = code_pieces(text);
    let got: Vec<(usize, &str, bool)> = pieces
        .iter()
        .map(|c| (c.line, c.text.as_str(), c.block))
        .collect();
    assert_eq!(
        got,
        [
            (1, "a b", false),
            (2, "c d", false),
            (6, "cohort render    --paths 4", true),
            (8, "x", true),
            (10, "k`l", false),
        ]
    );
    assert_eq!(
        link_targets("[a](docs/A.md#x) and ![b](img.png \"t\")"),
        [(1, "docs/A.md#x".to_string()), (1, "img.png".to_string())]
    );
}

#[test]
fn the_scan_reads_clap_definitions() {
    let src = r#"
        #[derive(Parser)]
        struct Cli {
            #[arg(long, global = true)]
            verbose: bool,
            #[command(subcommand)]
            command: Command,
        }
        #[derive(Subcommand)]
        enum Command {
            /// Render a scene (a comment with `#[arg(long)] fake: u32`).
            Render(RenderArgs),
            FiguresMerge(figures::merge::MergeArgs),
            Merge(merge::MergeArgs),
            Scenes,
            #[command(name = "cmp", alias = "compare")]
            Diff { #[arg(long = "tol")] tolerance: f32, a: String },
        }
        #[derive(clap::Args)]
        pub struct RenderArgs {
            #[arg(long, value_enum, default_value_t = Rr::Path)]
            end_continue: f32,
            #[arg(short = 'D', value_parser = parse_define)]
            define: Vec<(String, String)>,
            #[command(flatten)]
            common: crate::Common,
            #[arg(long, aliases = ["old-name"], default_value = "a, b")]
            new_name: Option<Vec<u32>>,
        }
        #[derive(Args)]
        pub(crate) struct Common { #[arg(long)] seed: u32 }
        #[derive(Debug)]
        enum Command { Camera(Camera) }
    "#;
    let mut items = Items::default();
    // Two `MergeArgs`, told apart by their modules.
    parse_items(
        "#[derive(clap::Args)] pub struct MergeArgs { #[arg(long)] require_all: bool }",
        "merge",
        &mut items,
    );
    parse_items(src, "", &mut items);
    parse_items(
        "#[derive(clap::Args)] pub struct MergeArgs { shards: Vec<PathBuf>, #[arg(long)] out_dir: PathBuf }",
        "figures::merge",
        &mut items,
    );
    let cli = CliFlags::from_items(&items).unwrap();
    let flags = |sub: &str| -> Vec<String> {
        let mut v: Vec<String> = cli.commands[sub].clone().unwrap().into_iter().collect();
        v.retain(|f| !["--help", "-h", "--version", "-V", "--verbose"].contains(&f.as_str()));
        v
    };
    assert_eq!(
        flags("render"),
        ["--end-continue", "--new-name", "--old-name", "--seed", "-D"]
    );
    assert_eq!(flags("figures-merge"), ["--out-dir"]);
    assert_eq!(flags("merge"), ["--require-all"]);
    assert_eq!(flags("scenes"), Vec::<String>::new());
    assert_eq!(flags("cmp"), ["--tol"]);
    assert_eq!(flags("compare"), ["--tol"]);
    assert!(cli.commands["render"]
        .as_ref()
        .unwrap()
        .contains("--verbose"));

    assert_eq!(
        commands_in(
            "cargo run --release -p cohort-cli -- view --compare a=b,c=d --width/--height 4 # --no"
        ),
        [(
            "view".to_string(),
            vec!["--compare".into(), "--width".into(), "--height".into()]
        )]
    );
    assert_eq!(
        commands_in(
            "cohort figures-merge X.csv [--out-dir DIR] && cohort render -D a=1 --exposure -1"
        ),
        [
            ("figures-merge".to_string(), vec!["--out-dir".to_string()]),
            (
                "render".to_string(),
                vec!["-D".to_string(), "--exposure".to_string()]
            ),
        ]
    );
}
