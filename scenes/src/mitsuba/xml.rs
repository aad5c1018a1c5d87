//! First stage of the Mitsuba loader: scene files → one owned element tree, read the way Mitsuba
//! 3.9's parser (`src/core/parser.cpp`) reads them (checked against mitsuba 3.9.1):
//!
//! - `$name` is replaced in every attribute, in document order, longest parameter name first, as
//!   plain text (`$resx` with only `res` defined becomes `<value of res>x`); `\$` is a literal `$`;
//!   a `$` left over is an error ("undefined parameter").
//! - `<default name value>` defines `$name` from that element on (anywhere, also in included
//!   files), unless it is already defined: the caller's parameters (`-D name=value`) and the first
//!   `<default>` win. A caller's parameter the scene never uses is reported, as Mitsuba does.
//! - `<include filename>` is resolved like any file (below) from the including file; the included
//!   file's root is replaced by its children when it is a `<scene>`, and inserted as one child
//!   otherwise. An include that leads back to a file being read is an error showing the chain.
//! - `<path value>` (only at the top level of a file) adds a search folder in front of the
//!   file's search list. File names are searched in: that file's `<path>` folders, the last one
//!   first, then the file's own folder, then the search list of the file that included it, and
//!   finally the working directory. Mesh file names are resolved with the MAIN file's list, even
//!   for shapes written in an included file (Mitsuba instantiates every object with the main
//!   file's resolver), so a `<path>` inside an included file only affects that file's includes.
//! - Every file's root needs a `version` ("major.minor.patch"); files older than 2.0.0 have their
//!   camelCase parameter names renamed (Mitsuba's upgrade), e.g. `diffuseReflectance`.

use std::path::{Path, PathBuf};

use roxmltree::Node;

use crate::error::{ErrorKind, Location, SceneError};

use super::diag::{err, syntax, Diag};

/// One element after parameter substitution and include splicing.
#[derive(Clone, Debug)]
pub(crate) struct Elem {
    pub tag: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Elem>,
    pub loc: Location,
}

impl Elem {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn set_attr(&mut self, name: &str, value: &str) {
        match self.attrs.iter_mut().find(|(k, _)| k == name) {
            Some(a) => a.1 = value.to_string(),
            None => self.attrs.push((name.to_string(), value.to_string())),
        }
    }
}

pub(crate) struct Document {
    /// The main file's `<scene>`.
    pub root: Elem,
    /// Folders searched for mesh files, in order (see the module documentation).
    pub search: Vec<PathBuf>,
    /// Each included file and the `<include>` that (first) read it.
    pub included_from: Vec<(PathBuf, Location)>,
}

impl Document {
    /// Adds to an error in an included file the `<include>` elements that led there.
    pub fn with_includes(&self, mut e: SceneError) -> SceneError {
        let mut file = e.location.file.clone();
        for _ in 0..MAX_INCLUDE_DEPTH {
            let Some((_, site)) = self.included_from.iter().find(|(f, _)| *f == file) else {
                break;
            };
            file = site.file.clone();
            e = e.referenced_from(site.clone());
        }
        e
    }
}

pub(crate) enum Source<'a> {
    File(&'a Path),
    Text { text: &'a str, base_dir: &'a Path },
}

struct Param {
    /// `$name`.
    key: String,
    value: String,
    used: bool,
    from_caller: bool,
}

/// Deeper nesting than this is refused even without a cycle (Mitsuba has a limit too).
const MAX_INCLUDE_DEPTH: usize = 64;

/// Elements nested deeper than this (across includes) are refused: no scene needs it, and the
/// readers recurse.
pub(crate) const MAX_NESTING: usize = 100;

/// Checks an element's attributes: a missing required one (`"!name"`) is an error, an unexpected
/// one is rejected as Mitsuba does (a warning under `lenient`).
pub(crate) fn check_attrs(
    diag: &mut Diag,
    loc: &Location,
    tag: &str,
    attrs: &[(String, String)],
    allowed: &[&str],
) -> Result<(), SceneError> {
    for (name, _) in attrs {
        if !allowed.iter().any(|a| a.trim_start_matches('!') == name) {
            diag.unsupported(
                loc,
                format!("unexpected attribute '{name}' in <{tag}>"),
                "ignored",
            )?;
        }
    }
    for a in allowed.iter().filter_map(|a| a.strip_prefix('!')) {
        if !attrs.iter().any(|(k, _)| k == a) {
            return Err(syntax(loc, format!("<{tag}> needs a '{a}' attribute")));
        }
    }
    Ok(())
}

pub(crate) fn read(
    diag: &mut Diag,
    source: Source,
    params: &[(String, String)],
) -> Result<Document, SceneError> {
    let mut r = Reader {
        diag,
        params: params
            .iter()
            .map(|(k, v)| Param {
                key: format!("${k}"),
                value: v.clone(),
                used: false,
                from_caller: true,
            })
            .collect(),
        chain: Vec::new(),
        included_from: Vec::new(),
        depth: 0,
    };
    sort_params(&mut r.params);
    let cwd: Vec<PathBuf> = std::env::current_dir().into_iter().collect();
    let (text, file, dir) = match source {
        Source::File(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| {
                err(
                    &Location::file(path),
                    ErrorKind::Io,
                    format!("cannot read scene file: {e}"),
                )
            })?;
            r.chain.push((canonical(path), path.to_path_buf()));
            (text, path.to_path_buf(), parent_dir(path))
        }
        Source::Text { text, base_dir } => (
            text.to_string(),
            PathBuf::from("<string>"),
            base_dir.to_path_buf(),
        ),
    };
    let (root, search) = r.read_doc(&text, &file, &dir, cwd, true)?;
    let unused: Vec<String> = r
        .params
        .iter()
        .filter(|p| p.from_caller && !p.used)
        .map(|p| format!("{}={}", &p.key[1..], p.value))
        .collect();
    if !unused.is_empty() {
        r.diag.unsupported(
            &Location::file(&file),
            format!(
                "parameter {} is never used by the scene (Mitsuba rejects unused parameters)",
                unused.join(", ")
            ),
            "ignored",
        )?;
    }
    Ok(Document {
        root,
        search,
        included_from: r.included_from,
    })
}

struct Reader<'d> {
    diag: &'d mut Diag,
    /// Longest key first, so that `$resx` is replaced before `$res`.
    params: Vec<Param>,
    /// The files being read, outermost first: (canonical path, path as written).
    chain: Vec<(PathBuf, PathBuf)>,
    included_from: Vec<(PathBuf, Location)>,
    /// Nesting of the element being read.
    depth: usize,
}

struct FileState<'d, 'i> {
    doc: &'d roxmltree::Document<'i>,
    file: PathBuf,
    /// This file's search folders, first searched first.
    search: Vec<PathBuf>,
    /// Version < 2.0.0: upgrade camelCase names.
    v1: bool,
}

impl Reader<'_> {
    /// Reads one file's text; returns its root element and its final search list.
    fn read_doc(
        &mut self,
        text: &str,
        file: &Path,
        dir: &Path,
        parent_search: Vec<PathBuf>,
        is_main: bool,
    ) -> Result<(Elem, Vec<PathBuf>), SceneError> {
        // roxmltree recurses per nesting level: refuse absurd nesting before it overflows.
        check_nesting(text, file)?;
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            err(
                &Location::line(file, e.pos().row),
                ErrorKind::Xml,
                format!("malformed XML: {e}"),
            )
        })?;
        let root = doc.root_element();
        let loc = Location::line(file, doc.text_pos_at(root.range().start).row);
        if is_main && root.tag_name().name() != "scene" {
            return Err(syntax(&loc, "the root element must be <scene>"));
        }
        let v1 = self.version(&loc, root)?;
        let mut search = parent_search;
        search.insert(0, dir.to_path_buf());
        let mut f = FileState {
            doc: &doc,
            file: file.to_path_buf(),
            search,
            v1,
        };
        let elem = self.element(&mut f, root, loc, true)?;
        Ok((elem, f.search))
    }

    /// Mitsuba requires `version="major.minor.patch"` on every file's root; returns whether the
    /// file predates 2.0.0.
    fn version(&mut self, loc: &Location, root: Node) -> Result<bool, SceneError> {
        let tag = root.tag_name().name();
        match root.attribute("version") {
            None => {
                self.diag.unsupported(
                    loc,
                    format!("<{tag}> has no 'version' attribute (Mitsuba requires one, e.g. version=\"3.0.0\")"),
                    "read as version 3.0.0",
                )?;
                Ok(false)
            }
            Some(v) => match parse_version(v) {
                Some(v) => Ok(v < (2, 0, 0)),
                None => {
                    self.diag.unsupported(
                        loc,
                        format!("invalid version number \"{v}\" (Mitsuba expects major.minor.patch, e.g. 3.0.0)"),
                        "read as version 3.0.0",
                    )?;
                    Ok(false)
                }
            },
        }
    }

    /// One element and, recursively, its children; `<default>`, `<path>` and `<include>` children
    /// are consumed here.
    fn element(
        &mut self,
        f: &mut FileState,
        node: Node,
        loc: Location,
        is_root: bool,
    ) -> Result<Elem, SceneError> {
        if self.depth >= MAX_NESTING {
            return Err(syntax(
                &loc,
                format!("elements nested deeper than {MAX_NESTING} levels"),
            ));
        }
        self.depth += 1;
        let e = self.element_inner(f, node, loc, is_root);
        self.depth -= 1;
        e
    }

    fn element_inner(
        &mut self,
        f: &mut FileState,
        node: Node,
        loc: Location,
        is_root: bool,
    ) -> Result<Elem, SceneError> {
        let mut attrs = self.attrs(node, &loc)?;
        if is_root {
            attrs.retain(|(k, _)| k != "version");
        }
        let mut e = Elem {
            tag: node.tag_name().name().to_string(),
            attrs,
            children: Vec::new(),
            loc,
        };
        if f.v1 {
            if let Some(name) = e.attr("name") {
                let renamed = camel_to_underscore(name);
                e.set_attr("name", &renamed);
            }
        }
        for child in node.children().filter(Node::is_element) {
            let loc = Location::line(&f.file, f.doc.text_pos_at(child.range().start).row);
            match child.tag_name().name() {
                tag @ ("default" | "path" | "include") => {
                    if child.children().any(|c| c.is_element()) {
                        self.diag.unsupported(
                            &loc,
                            format!("<{tag}> cannot have child elements"),
                            "they are ignored",
                        )?;
                    }
                    match tag {
                        "default" => self.default(child, &loc)?,
                        "path" => self.path(f, is_root, child, &loc)?,
                        _ => self.include(f, child, &loc, &mut e)?,
                    }
                }
                _ => {
                    let c = self.element(f, child, loc, false)?;
                    e.children.push(c);
                }
            }
        }
        // Mitsuba's upgrade of pre-2.0 files also renames diffuse's old parameter name.
        if f.v1 && e.tag == "bsdf" && e.attr("type") == Some("diffuse") {
            for c in &mut e.children {
                if c.attr("name") == Some("diffuse_reflectance") {
                    c.set_attr("name", "reflectance");
                }
            }
        }
        Ok(e)
    }

    fn attrs(&mut self, node: Node, loc: &Location) -> Result<Vec<(String, String)>, SceneError> {
        node.attributes()
            .map(|a| {
                let v = if a.value().contains('$') {
                    self.substitute(a.value(), loc)?
                } else {
                    a.value().to_string()
                };
                Ok((a.name().to_string(), v))
            })
            .collect()
    }

    fn substitute(&mut self, value: &str, loc: &Location) -> Result<String, SceneError> {
        let mut v = value.to_string();
        for p in &mut self.params {
            let mut pos = 0;
            while let Some(off) = v[pos..].find(&p.key) {
                let i = pos + off;
                if i > 0 && v.as_bytes()[i - 1] == b'\\' {
                    pos = i + p.key.len();
                } else {
                    v.replace_range(i..i + p.key.len(), &p.value);
                    p.used = true;
                    pos = i + p.value.len();
                }
            }
        }
        let mut pos = 0;
        while let Some(off) = v[pos..].find('$') {
            let i = pos + off;
            if i > 0 && v.as_bytes()[i - 1] == b'\\' {
                pos = i + 1;
                continue;
            }
            let name: String = v[i + 1..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            return Err(syntax(
                loc,
                format!(
                    "undefined parameter '${name}' (define it with <default name=\"{name}\" value=\"...\"/> before its first use, or pass -D {name}=...)"
                ),
            ));
        }
        Ok(v.replace("\\$", "$"))
    }

    fn default(&mut self, node: Node, loc: &Location) -> Result<(), SceneError> {
        let attrs = self.attrs(node, loc)?;
        check_attrs(self.diag, loc, "default", &attrs, &["!name", "!value"])?;
        let get = |k: &str| {
            attrs
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| v.clone())
                .unwrap_or_default()
        };
        let (name, value) = (get("name"), get("value"));
        if name.is_empty() {
            return Err(syntax(loc, "<default>: name must not be empty"));
        }
        let key = format!("${name}");
        if !self.params.iter().any(|p| p.key == key) {
            self.params.push(Param {
                key,
                value,
                used: true,
                from_caller: false,
            });
            sort_params(&mut self.params);
        }
        Ok(())
    }

    fn path(
        &mut self,
        f: &mut FileState,
        parent_is_root: bool,
        node: Node,
        loc: &Location,
    ) -> Result<(), SceneError> {
        let attrs = self.attrs(node, loc)?;
        check_attrs(self.diag, loc, "path", &attrs, &["!value"])?;
        if !parent_is_root {
            return Err(syntax(
                loc,
                "<path> can only be a child of the root element",
            ));
        }
        let value = attrs
            .iter()
            .find(|(k, _)| k == "value")
            .map(|(_, v)| v.clone())
            .unwrap_or_default();
        let folder = resolve(&f.search, Path::new(&value)).ok_or_else(|| {
            err(
                loc,
                ErrorKind::Io,
                format!(
                    "<path>: folder '{value}' not found (searched in {})",
                    show_list(&f.search)
                ),
            )
        })?;
        f.search.insert(0, folder);
        Ok(())
    }

    fn include(
        &mut self,
        f: &mut FileState,
        node: Node,
        loc: &Location,
        parent: &mut Elem,
    ) -> Result<(), SceneError> {
        let attrs = self.attrs(node, loc)?;
        check_attrs(self.diag, loc, "include", &attrs, &["!filename", "name"])?;
        let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        let filename = get("filename").unwrap_or_default();
        let path = resolve(&f.search, Path::new(&filename)).ok_or_else(|| {
            err(
                loc,
                ErrorKind::Io,
                format!(
                    "included file '{filename}' not found (searched in {})",
                    show_list(&f.search)
                ),
            )
        })?;
        let canon = canonical(&path);
        if let Some(i) = self.chain.iter().position(|(c, _)| *c == canon) {
            let files: Vec<String> = self.chain[i..]
                .iter()
                .map(|(_, shown)| shown.display().to_string())
                .chain([path.display().to_string()])
                .collect();
            return Err(err(
                loc,
                ErrorKind::Cycle,
                format!("include cycle: {}", files.join(" -> ")),
            ));
        }
        if self.chain.len() >= MAX_INCLUDE_DEPTH {
            return Err(syntax(
                loc,
                format!("includes nested deeper than {MAX_INCLUDE_DEPTH} files"),
            ));
        }
        let text = std::fs::read_to_string(&path).map_err(|e| {
            err(
                loc,
                ErrorKind::Io,
                format!("cannot read included file '{}': {e}", path.display()),
            )
        })?;
        self.chain.push((canon, path.clone()));
        if !self.included_from.iter().any(|(f, _)| *f == path) {
            self.included_from.push((path.clone(), loc.clone()));
        }
        let result = self.read_doc(&text, &path, &parent_dir(&path), f.search.clone(), false);
        self.chain.pop();
        let (mut root, _) = result.map_err(|e| e.referenced_from(loc.clone()))?;
        if root.tag == "scene" {
            parent.children.append(&mut root.children);
        } else {
            if let Some(name) = get("name") {
                root.set_attr("name", &name);
            }
            parent.children.push(root);
        }
        Ok(())
    }
}

/// Refuses text whose elements nest deeper than [`MAX_NESTING`], by a scan of its tags (start
/// tags, end tags, empty-element tags; comments, CDATA, processing instructions and declarations
/// skipped; quoted attribute values may hold '>').
fn check_nesting(text: &str, file: &Path) -> Result<(), SceneError> {
    let b = text.as_bytes();
    let (mut i, mut depth, mut line) = (0, 0usize, 1u32);
    let skip_to = |from: usize, end: &str| {
        text[from..]
            .find(end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    while i < b.len() {
        match b[i] {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'<' => {
                let rest = &text[i..];
                let next = if rest.starts_with("<!--") {
                    skip_to(i, "-->")
                } else if rest.starts_with("<![CDATA[") {
                    skip_to(i, "]]>")
                } else if rest.starts_with("<?") {
                    skip_to(i, "?>")
                } else if rest.starts_with("<!") {
                    skip_to(i, ">")
                } else if rest.starts_with("</") {
                    depth = depth.saturating_sub(1);
                    skip_to(i, ">")
                } else {
                    // A start tag: find its '>' outside quotes.
                    let mut j = i + 1;
                    let mut quote = None;
                    while j < b.len() {
                        match (quote, b[j]) {
                            (None, b'"' | b'\'') => quote = Some(b[j]),
                            (Some(q), c) if c == q => quote = None,
                            (None, b'>') => break,
                            _ => {}
                        }
                        j += 1;
                    }
                    if j < b.len() && b[j - 1] != b'/' {
                        depth += 1;
                        if depth > MAX_NESTING {
                            return Err(syntax(
                                &Location::line(file, line),
                                format!("elements nested deeper than {MAX_NESTING} levels"),
                            ));
                        }
                    }
                    j + 1
                };
                line += text[i..next.min(b.len())].matches('\n').count() as u32;
                i = next;
            }
            _ => i += 1,
        }
    }
    Ok(())
}

fn sort_params(params: &mut [Param]) {
    params.sort_by_key(|p| std::cmp::Reverse(p.key.len()));
}

/// The folder a file's relative names start from ("." for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Mitsuba's file resolver: an absolute name as is, a relative one in the first folder of
/// `search` that has it.
pub(crate) fn resolve(search: &[PathBuf], name: &Path) -> Option<PathBuf> {
    if name.is_absolute() {
        return name.exists().then(|| name.to_path_buf());
    }
    search.iter().map(|b| b.join(name)).find(|p| p.exists())
}

pub(crate) fn show_list(folders: &[PathBuf]) -> String {
    folders
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// "major.minor.patch" with an optional "-prerelease" and "+build", as Mitsuba's semantic
/// version parser accepts it (blanks around the numbers are tolerated).
fn parse_version(v: &str) -> Option<(i64, i64, i64)> {
    let v = v.trim().split('+').next()?;
    let mut parts = v.splitn(3, '.');
    let major = parts.next()?.trim().parse().ok()?;
    let minor = parts.next()?.trim().parse().ok()?;
    let patch = parts.next()?.split('-').next()?.trim().parse().ok()?;
    Some((major, minor, patch))
}

/// Mitsuba's renaming of pre-2.0 parameter names: `diffuseReflectance` → `diffuse_reflectance`.
fn camel_to_underscore(input: &str) -> String {
    let chars: Vec<char> = input.chars().collect();
    let mut out = String::with_capacity(input.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_as_mitsuba_parses_them() {
        for ok in [
            "3.0.0",
            " 3.0.0",
            "3.0.0 ",
            "3.0.0-rc1",
            "3.0.0+x",
            "03.0.0",
            "-1.0.0",
            "3. 0.0",
            "3.0.0-",
        ] {
            assert!(parse_version(ok).is_some(), "{ok}");
        }
        for bad in ["3", "3.0", "abc", "", "3.0.0.1", "v3.0.0"] {
            assert!(parse_version(bad).is_none(), "{bad}");
        }
        assert!(parse_version("0.6.0").unwrap() < (2, 0, 0));
    }

    #[test]
    fn nesting_scan() {
        let f = Path::new("x.xml");
        let nest = |n: usize| format!("{}{}", "<a x='>'>".repeat(n), "</a>".repeat(n));
        assert!(check_nesting(&nest(MAX_NESTING), f).is_ok());
        assert!(check_nesting(&nest(MAX_NESTING + 1), f).is_err());
        assert!(check_nesting(&nest(100_000), f).is_err());
        let flat = "<s>\n<!-- <a><a> -->\n<b/><![CDATA[<c>]]><?pi <d>?>\n</s>".repeat(500);
        assert!(check_nesting(&flat, f).is_ok());
        let e = check_nesting(&format!("<s>\n\n{}", nest(200)), f).unwrap_err();
        assert_eq!(e.location.line_number(), Some(3));
    }

    #[test]
    fn camel_case_upgrade() {
        assert_eq!(
            camel_to_underscore("diffuseReflectance"),
            "diffuse_reflectance"
        );
        assert_eq!(camel_to_underscore("intIOR"), "int_ior");
        assert_eq!(camel_to_underscore("toWorld"), "to_world");
        assert_eq!(camel_to_underscore("Foo"), "Foo");
        assert_eq!(camel_to_underscore("max_depth"), "max_depth");
    }
}
