//! The layout's rules, read from the sources (docs/layout.md): no import
//! cycle among the files of any crate of the workspace, nor among the
//! modules (a folder with its files, or one file) beside each other in one
//! parent module, no source file over
//! 900 lines but a data table, and nothing in the renderer's shared passes
//! naming a technique.
//!
//! The import graph has an arrow from file A to file B where A names an
//! item that B defines, through a `use` or a `crate::`/`super::`/`self::`
//! path in its code. A name that a module only re-exports (`pub use`) is
//! followed to the file that defines it, and the re-export itself is no
//! arrow, so that a folder's `mod.rs` that hands its children's items on is
//! neither taken for their author nor for their user. `mod` declarations
//! are no arrows, and code under `#[cfg(test)]` (a unit test may reach
//! anywhere) or `#[cfg(doc)]` (imports for rustdoc's links) is left out.
//!
//! A cycle can run through folders with no two files importing each other
//! (`hooks/wrappers.rs` → `state/handlers.rs` → `hooks/loader.rs`): the
//! module graph has an arrow from module A to module B, two children of one
//! parent, where any file in A (or below it) has an arrow to any file in B
//! (or below it), and a cycle there is one too.

mod modules;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// The source folders of the workspace's crates (a crate's root is its
/// `lib.rs`; `src/main.rs` only calls the lab's library).
const CRATE_ROOTS: &[&str] = &[
    "src",
    "crates/core/src",
    "crates/headless/src",
    "crates/capi/src",
    "crates/testkit/src",
    "crates/inject/src",
];

/// Where the size rule looks.
const SIZE_ROOTS: &[&str] = &["src", "crates", "tests", "examples", "benches", "fuzz"];

const MAX_LINES: usize = 900;

/// Files over [`MAX_LINES`] that are data, not code: a table is read as a
/// whole, and cutting it in two only hides its shape.
const DATA_TABLES: &[&str] = &["src/renderer/technique/smaa/tables.rs"];

/// Files over [`MAX_LINES`] not split yet, each named so that no other
/// file can pass the limit unnoticed. None is left.
const NOT_YET_SPLIT: &[&str] = &[];

/// Import cycles among files that other work has open now, each the exact
/// set of its files: to be broken when that work lands. None is left; a
/// cycle named here that gains or loses a file, or any other cycle, fails.
const KNOWN_CYCLES: &[&[&str]] = &[];

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` whose name ends with one of `extensions`.
fn files_under(dir: &Path, extensions: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            // Build outputs and fuzzing's corpora are no sources.
            if !name.starts_with('.') && !["target", "corpus", "artifacts"].contains(&name.as_str())
            {
                files_under(&path, extensions, out);
            }
        } else if extensions.iter().any(|e| name.ends_with(e)) {
            out.push(path);
        }
    }
}

/// The source with comments, string and character literals blanked and
/// `#[cfg(test)]` items cut out, so that what is left is paths and braces.
fn code_of(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && !ident_char_before(&chars, i)
        {
            // A raw string: r"…", r#"…"#, …
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= chars.len() {
                    break;
                }
                if chars[j] == '"' && (0..hashes).all(|k| chars.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
            let close = if next == Some('\\') {
                (i + 2..chars.len().min(i + 12)).find(|&k| chars[k] == '\'')
            } else if chars.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match close {
                Some(k) => {
                    out.push_str("' '");
                    i = k + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    cut_test_items(&out)
}

fn ident_char_before(chars: &[char], i: usize) -> bool {
    i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_')
}

/// `code` without the items that follow `#[cfg(test)]` or `#[cfg(doc)]` (to
/// the end of their braces, or their `;`): a unit test, or a `use` that only
/// rustdoc's links need, is no dependency of the code.
fn cut_test_items(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = ["#[cfg(test)]", "#[cfg(doc)]"]
        .iter()
        .filter_map(|attribute| rest.find(attribute))
        .min()
    {
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        let (mut depth, mut end) = (0usize, after.len());
        for (k, ch) in after.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// One leaf of a `use` tree: the path as written and the name it binds.
#[derive(Clone, Debug)]
struct UseLeaf {
    path: Vec<String>,
    name: String,
    /// A `pub use` (of any visibility): the module hands the item on. That
    /// is no arrow of its own; whoever names the item through it gets the
    /// arrow to the file that defines it.
    reexport: bool,
}

fn split_top_level(s: &str) -> Vec<&str> {
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (k, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&s[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[start..]);
    parts
        .into_iter()
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect()
}

/// The leaves of a `use` tree (globs are left out: nothing here uses one
/// outside tests).
fn use_leaves(prefix: &[String], tree: &str, reexport: bool, out: &mut Vec<UseLeaf>) {
    let tree = tree.trim();
    if let Some(open) = tree.find('{') {
        let head = tree[..open].trim().trim_end_matches("::");
        let mut path = prefix.to_vec();
        path.extend(
            head.split("::")
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from),
        );
        let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
        for part in split_top_level(inner) {
            use_leaves(&path, part, reexport, out);
        }
        return;
    }
    let (path_text, alias) = match tree.split_once(" as ") {
        Some((p, a)) => (p.trim(), Some(a.trim())),
        None => (tree, None),
    };
    let mut path = prefix.to_vec();
    path.extend(path_text.split("::").map(|s| s.trim().to_string()));
    let Some(last) = path.last().cloned() else {
        return;
    };
    if last == "*" {
        return;
    }
    if last == "self" {
        path.pop();
    }
    let name = match alias {
        Some(a) => a.to_string(),
        None => path.last().cloned().unwrap_or_default(),
    };
    out.push(UseLeaf {
        path,
        name,
        reexport,
    });
}

/// What a file holds, as far as the graph needs it.
struct ModuleFile {
    /// The file, from the workspace's root.
    file: String,
    /// `use` leaves, each with the inline module it stands in (a path
    /// inside the file, usually empty).
    uses: Vec<(Vec<String>, UseLeaf)>,
    /// Other paths in its code that start with `crate`, `super`, `self` or a
    /// name bound here, with the inline module they stand in.
    paths: Vec<(Vec<String>, Vec<String>)>,
    /// The names its own items have (fn, struct, enum, trait, const, static,
    /// type, union, macro_rules, mod).
    defines: BTreeSet<String>,
}

/// The crate's module tree: module path to its file.
struct CrateModules {
    files: BTreeMap<Vec<String>, ModuleFile>,
}

fn module_path(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).unwrap_or(file);
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

fn is_ident(s: &str) -> bool {
    !s.is_empty()
        && s.chars().all(|c| c.is_alphanumeric() || c == '_')
        && !s.starts_with(|c: char| c.is_ascii_digit())
}

fn read_module(file: String, source: &str) -> ModuleFile {
    let code = code_of(source);
    let mut uses = Vec::new();
    let mut paths = Vec::new();
    let mut defines = BTreeSet::new();
    // Walk the code token by token, keeping the inline `mod name {` nesting.
    let tokens = tokenize(&code);
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut pending_mod: Option<String> = None;
    let mut k = 0;
    while k < tokens.len() {
        let t = tokens[k].as_str();
        let here: Vec<String> = inline.iter().map(|(n, _)| n.clone()).collect();
        match t {
            "{" => {
                depth += 1;
                if let Some(name) = pending_mod.take() {
                    inline.push((name, depth));
                }
            }
            "}" => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            ";" => pending_mod = None,
            "use" => {
                // `pub use`, `pub(crate) use`, `pub(super) use`, `pub(in …) use`.
                let reexport = k > 0
                    && (tokens[k - 1] == "pub"
                        || (tokens[k - 1] == ")"
                            && tokens[..k].iter().rev().take(8).any(|t| t == "pub")));
                let mut text = String::new();
                k += 1;
                while k < tokens.len() && tokens[k] != ";" {
                    text.push_str(&tokens[k]);
                    text.push(' ');
                    k += 1;
                }
                let text = text
                    .replace(" :: ", "::")
                    .replace(":: ", "::")
                    .replace(" ::", "::");
                let mut leaves = Vec::new();
                use_leaves(&[], &text, reexport, &mut leaves);
                uses.extend(leaves.into_iter().map(|l| (here.clone(), l)));
            }
            "fn" | "struct" | "enum" | "trait" | "const" | "static" | "type" | "union" | "mod"
            | "macro_rules" => {
                if let Some(name) = tokens.get(k + 1).filter(|n| is_ident(n)) {
                    if inline.is_empty() {
                        defines.insert(name.clone());
                    }
                    if t == "mod" {
                        pending_mod = Some(name.clone());
                    }
                } else if t == "macro_rules" {
                    if let Some(name) = tokens.get(k + 2) {
                        defines.insert(name.clone());
                    }
                }
            }
            _ if is_ident(t) && tokens.get(k + 1).is_some_and(|n| n == "::") => {
                // A path in code: `a::b::c`.
                let mut path = vec![t.to_string()];
                let mut j = k + 1;
                while tokens.get(j).is_some_and(|n| n == "::")
                    && tokens.get(j + 1).is_some_and(|n| is_ident(n))
                {
                    path.push(tokens[j + 1].clone());
                    j += 2;
                }
                if path.len() > 1 {
                    paths.push((here.clone(), path));
                }
                k = j - 1;
            }
            _ => {}
        }
        k += 1;
    }
    ModuleFile {
        file,
        uses,
        paths,
        defines,
    }
}

/// Identifiers, `::`, and single punctuation characters.
fn tokenize(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            // `r#ident` is an identifier too.
            tokens.push(chars[start..i].iter().collect());
            continue;
        }
        if c == ':' && chars.get(i + 1) == Some(&':') {
            tokens.push("::".into());
            i += 2;
            continue;
        }
        if !c.is_whitespace() {
            tokens.push(c.to_string());
        }
        i += 1;
    }
    tokens
}

impl CrateModules {
    fn read(workspace: &Path, root: &str) -> Self {
        let root_dir = workspace.join(root);
        let mut list = Vec::new();
        files_under(&root_dir, &[".rs"], &mut list);
        let files = list
            .iter()
            .filter(|f| !f.ends_with("main.rs") || root != "src")
            .map(|f| {
                let name = f
                    .strip_prefix(workspace)
                    .unwrap_or(f)
                    .to_string_lossy()
                    .replace('\\', "/");
                let source = std::fs::read_to_string(f).unwrap_or_default();
                (module_path(&root_dir, f), read_module(name, &source))
            })
            .collect();
        CrateModules { files }
    }

    /// The file module that holds `module` (an inline module is in its
    /// file's), and the inline part.
    fn file_of(&self, module: &[String]) -> Option<(Vec<String>, Vec<String>)> {
        (0..=module.len()).rev().find_map(|n| {
            self.files
                .contains_key(&module[..n])
                .then(|| (module[..n].to_vec(), module[n..].to_vec()))
        })
    }

    /// `path`, as written in module `at`, from the crate's root; `None` for
    /// another crate's path.
    fn absolute(&self, at: &[String], path: &[String]) -> Option<Vec<String>> {
        self.absolute_within(at, path, 8)
    }

    /// [`CrateModules::absolute`], following at most `hops` bindings (`pub
    /// use glow;` binds `glow` to itself).
    fn absolute_within(&self, at: &[String], path: &[String], hops: usize) -> Option<Vec<String>> {
        let (first, rest) = path.split_first()?;
        match first.as_str() {
            "crate" => Some(rest.to_vec()),
            "self" => Some([at, rest].concat()),
            "super" => {
                let mut base = at.to_vec();
                base.pop();
                let mut rest = rest;
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
                Some([base.as_slice(), rest].concat())
            }
            name => {
                // A child module, or a name this module's `use` binds.
                let (file, inline) = self.file_of(at)?;
                let module = &self.files[&file];
                let child: Vec<String> = [at, &[name.to_string()]].concat();
                if self.files.contains_key(&child) {
                    return Some([child.as_slice(), rest].concat());
                }
                let bound = module
                    .uses
                    .iter()
                    .find(|(scope, leaf)| *scope == inline && leaf.name == name)?;
                if hops == 0 || bound.1.path.first().is_some_and(|f| f == name) {
                    return None;
                }
                let target = self.absolute_within(at, &bound.1.path, hops - 1)?;
                Some([target.as_slice(), rest].concat())
            }
        }
    }

    /// The file that defines what `path` (from the root) names, following
    /// re-exports; `None` outside the crate.
    fn defining_file(&self, path: &[String], hops: usize) -> Option<Vec<String>> {
        let (file, rest) = self.file_of(path)?;
        let Some(name) = rest.first() else {
            return Some(file);
        };
        let module = &self.files[&file];
        if hops == 0 || module.defines.contains(name) {
            return Some(file);
        }
        match module
            .uses
            .iter()
            .find(|(scope, leaf)| scope.is_empty() && &leaf.name == name)
        {
            // Re-exported from another crate (the lab's `crate::gl` is the
            // core's): no file of this one.
            Some((_, leaf)) => {
                let target = self.absolute(&file, &leaf.path)?;
                let target = [target.as_slice(), &rest[1..]].concat();
                self.defining_file(&target, hops - 1)
            }
            None => Some(file),
        }
    }

    /// Every arrow: file → the files whose items it names.
    fn arrows(&self) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
        let mut arrows: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
        for (module, f) in &self.files {
            let from_uses = f
                .uses
                .iter()
                .filter(|(_, leaf)| !leaf.reexport)
                .map(|(scope, leaf)| (scope, &leaf.path));
            let from_code = f.paths.iter().map(|(scope, path)| (scope, path));
            for (scope, path) in from_uses.chain(from_code) {
                let at = [module.as_slice(), scope.as_slice()].concat();
                let Some(abs) = self.absolute(&at, path) else {
                    continue;
                };
                if let Some(target) = self.defining_file(&abs, 8) {
                    if &target != module {
                        arrows.entry(module.clone()).or_default().insert(target);
                    }
                }
            }
        }
        arrows
    }
}

/// The strongly connected components of more than one file (Tarjan).
fn cycles(arrows: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct State<'a> {
        arrows: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: HashMap<&'a Vec<String>, usize>,
        low: HashMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        on_stack: BTreeSet<&'a Vec<String>>,
        next: usize,
        found: Vec<Vec<Vec<String>>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a Vec<String>) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on_stack.insert(v);
        if let Some(targets) = s.arrows.get(v) {
            for w in targets {
                if !s.index.contains_key(w) {
                    visit(s, w);
                    let low = s.low[w].min(s.low[v]);
                    s.low.insert(v, low);
                } else if s.on_stack.contains(w) {
                    let low = s.index[w].min(s.low[v]);
                    s.low.insert(v, low);
                }
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.clone());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                s.found.push(component);
            }
        }
    }
    let mut state = State {
        arrows,
        index: HashMap::new(),
        low: HashMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        next: 0,
        found: Vec::new(),
    };
    for v in arrows.keys() {
        if !state.index.contains_key(v) {
            visit(&mut state, v);
        }
    }
    state.found
}

#[test]
fn no_file_imports_itself_through_others() {
    let root = workspace();
    let mut report = Vec::new();
    let mut files_read = 0;
    for crate_root in CRATE_ROOTS {
        let modules = CrateModules::read(&root, crate_root);
        files_read += modules.files.len();
        let arrows = modules.arrows();
        for component in cycles(&arrows) {
            let name = |m: &Vec<String>| modules.files[m].file.clone();
            let mut files: Vec<String> = component.iter().map(name).collect();
            files.sort();
            if KNOWN_CYCLES.iter().any(|known| *known == files.as_slice()) {
                continue;
            }
            let members: BTreeSet<&Vec<String>> = component.iter().collect();
            let mut lines: Vec<String> = Vec::new();
            for m in &component {
                for t in arrows[m].iter().filter(|t| members.contains(t)) {
                    lines.push(format!("  {} -> {}", name(m), name(t)));
                }
            }
            lines.sort();
            report.push(format!(
                "a cycle of {} files:\n{}",
                component.len(),
                lines.join("\n")
            ));
        }
    }
    // The reader must have found the workspace, not an empty folder.
    assert!(files_read > 100, "only {files_read} source files read");
    assert!(report.is_empty(), "{}", report.join("\n"));
}

#[test]
fn the_cycle_check_sees_a_cycle() {
    // Two files that import each other, as the reader sees them; what a
    // comment or a unit test names is no arrow.
    let a = "use super::b::Thing;\npub struct Other;\n#[cfg(test)]\nmod tests { use crate::m::c::Third; }\n";
    let b = "use crate::m::a::Other; // see crate::m::c::Third\npub struct Thing;\n";
    let c = "pub struct Third;\nfn f() { let _ = crate::m::b::Thing; }\n";
    let mut modules = CrateModules {
        files: BTreeMap::new(),
    };
    for (name, source) in [("a", a), ("b", b), ("c", c)] {
        modules.files.insert(
            vec!["m".to_string(), name.to_string()],
            read_module(format!("m/{name}.rs"), source),
        );
    }
    modules.files.insert(
        vec!["m".to_string()],
        ModuleFile {
            file: "m/mod.rs".into(),
            uses: Vec::new(),
            paths: Vec::new(),
            defines: ["a", "b", "c"].map(String::from).into_iter().collect(),
        },
    );
    let arrows = modules.arrows();
    let m = |n: &str| vec!["m".to_string(), n.to_string()];
    assert_eq!(arrows[&m("a")], [m("b")].into_iter().collect());
    assert_eq!(arrows[&m("b")], [m("a")].into_iter().collect());
    assert_eq!(arrows[&m("c")], [m("b")].into_iter().collect());
    let found = cycles(&arrows);
    assert_eq!(found.len(), 1, "{found:?}");
    let mut members = found[0].clone();
    members.sort();
    assert_eq!(members, [m("a"), m("b")]);
}

#[test]
fn no_source_file_passes_900_lines_but_a_data_table() {
    let root = workspace();
    let mut files = Vec::new();
    for dir in SIZE_ROOTS {
        files_under(
            &root.join(dir),
            &[".rs", ".frag", ".vert", ".geom", ".glsl", ".c", ".h"],
            &mut files,
        );
    }
    assert!(files.len() > 100, "only {} files found", files.len());
    let mut over = Vec::new();
    for f in &files {
        let rel = f
            .strip_prefix(&root)
            .unwrap_or(f)
            .to_string_lossy()
            .replace('\\', "/");
        if rel.starts_with("crates/capi/include/") {
            // Generated by cbindgen from crates/capi/src/lib.rs.
            continue;
        }
        let lines = std::fs::read_to_string(f)
            .map(|s| s.lines().count())
            .unwrap_or(0);
        if lines > MAX_LINES
            && !DATA_TABLES.contains(&rel.as_str())
            && !NOT_YET_SPLIT.contains(&rel.as_str())
        {
            over.push(format!("{rel}: {lines} lines"));
        }
    }
    over.sort();
    assert!(
        over.is_empty(),
        "over {MAX_LINES} lines (split it along a seam; docs/layout.md):\n{}",
        over.join("\n")
    );
}

#[test]
fn the_shared_passes_name_no_technique() {
    let root = workspace();
    let modules = CrateModules::read(&root, "src");
    let arrows = modules.arrows();
    let shared = ["renderer".to_string(), "pass".to_string()];
    let technique = ["renderer".to_string(), "technique".to_string()];
    let mut wrong = Vec::new();
    for (from, targets) in &arrows {
        if !from.starts_with(&shared) {
            continue;
        }
        for t in targets.iter().filter(|t| t.starts_with(&technique)) {
            wrong.push(format!(
                "{} -> {}",
                modules.files[from].file, modules.files[t].file
            ));
        }
    }
    assert!(
        modules.files.keys().any(|m| m.starts_with(&shared)),
        "no renderer/pass/ found"
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
