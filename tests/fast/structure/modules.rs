//! The module graph: a cycle among the modules beside each other in one
//! parent (a folder with its files, or one file), which no two files need
//! make between them.

use super::{CRATE_ROOTS, CrateModules, ModuleFile, cycles, read_module, workspace};
use std::collections::{BTreeMap, BTreeSet};

/// Cycles among sibling modules that other work has open now, each the
/// exact set of its modules (`crate root::path`, sorted): to be broken by
/// that work. A cycle named here that gains or loses a module, or any
/// other cycle, fails.
const KNOWN_MODULE_CYCLES: &[&[&str]] = &[
    // The core's error type names the error types of its parts, which name
    // it back (the lead's crate).
    &[
        "crates/core/src::error",
        "crates/core/src::gbuffer",
        "crates/core/src::gl",
        "crates/core/src::resolve",
    ],
    // The lab's error type names the bench's, as above.
    &["src::bench", "src::error", "src::renderer", "src::scene"],
    &["src::renderer::options", "src::renderer::technique"],
    &["src::renderer::pass", "src::renderer::targets"],
];

/// The module arrows: for each file arrow, the two children of the
/// deepest module that holds both files, where neither file is that module
/// itself (a parent's file and its child's are no siblings).
fn module_arrows(
    files: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut arrows: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (from, targets) in files {
        for to in targets {
            let common = from.iter().zip(to).take_while(|(a, b)| a == b).count();
            if from.len() > common && to.len() > common {
                arrows
                    .entry(from[..=common].to_vec())
                    .or_default()
                    .insert(to[..=common].to_vec());
            }
        }
    }
    arrows
}

#[test]
fn no_module_imports_itself_through_its_siblings() {
    let root = workspace();
    let mut report = Vec::new();
    let mut modules_seen = 0;
    for crate_root in CRATE_ROOTS {
        let modules = CrateModules::read(&root, crate_root);
        let files = modules.arrows();
        let arrows = module_arrows(&files);
        modules_seen += arrows.len();
        for component in cycles(&arrows) {
            let members: BTreeSet<&Vec<String>> = component.iter().collect();
            let name = |m: &Vec<String>| format!("{crate_root}::{}", m.join("::"));
            let mut named: Vec<String> = component.iter().map(name).collect();
            named.sort();
            if KNOWN_MODULE_CYCLES
                .iter()
                .any(|known| *known == named.as_slice())
            {
                continue;
            }
            let mut lines: Vec<String> = Vec::new();
            for m in &component {
                for t in arrows[m].iter().filter(|t| members.contains(t)) {
                    // One file arrow that makes it, for the reader.
                    let witness = files
                        .iter()
                        .flat_map(|(f, ts)| ts.iter().map(move |t| (f, t)))
                        .find(|(f, to)| f.starts_with(m) && to.starts_with(t))
                        .map(|(f, to)| {
                            format!(" ({} -> {})", modules.files[f].file, modules.files[to].file)
                        })
                        .unwrap_or_default();
                    lines.push(format!("  {} -> {}{witness}", name(m), name(t)));
                }
            }
            lines.sort();
            report.push(format!(
                "a cycle of {} modules:\n{}",
                component.len(),
                lines.join("\n")
            ));
        }
    }
    assert!(
        modules_seen > 50,
        "only {modules_seen} modules import others"
    );
    assert!(report.is_empty(), "{}", report.join("\n"));
}

#[test]
fn the_module_check_sees_a_cycle_no_two_files_make() {
    // Two folders: `a/one.rs` uses `b/two.rs`, `b/three.rs` uses
    // `a/four.rs`; no two files import each other, the folders do. A file
    // of `a` naming its parent's item is no sibling arrow.
    let sources = [
        (
            vec!["m", "a", "one"],
            "use crate::m::b::two::Two;\npub struct One;\n",
        ),
        (
            vec!["m", "a", "four"],
            "pub struct Four;\nfn f() { let _ = super::super::Top; }\n",
        ),
        (vec!["m", "b", "two"], "pub struct Two;\n"),
        (vec!["m", "b", "three"], "use crate::m::a::four::Four;\n"),
        (vec!["m", "c"], "use crate::m::a::one::One;\n"),
    ];
    let mut modules = CrateModules {
        files: BTreeMap::new(),
    };
    for (path, source) in sources {
        modules.files.insert(
            path.iter().map(|s| s.to_string()).collect(),
            read_module(format!("{}.rs", path.join("/")), source),
        );
    }
    for (path, children) in [
        (vec!["m"], vec!["a", "b", "c", "Top"]),
        (vec!["m", "a"], vec!["one", "four"]),
        (vec!["m", "b"], vec!["two", "three"]),
    ] {
        modules.files.insert(
            path.iter().map(|s| s.to_string()).collect(),
            ModuleFile {
                file: format!("{}/mod.rs", path.join("/")),
                uses: Vec::new(),
                paths: Vec::new(),
                defines: children.into_iter().map(String::from).collect(),
            },
        );
    }
    let files = modules.arrows();
    assert!(cycles(&files).is_empty(), "a file cycle: {files:?}");
    let arrows = module_arrows(&files);
    let m = |p: &[&str]| p.iter().map(|s| s.to_string()).collect::<Vec<String>>();
    assert_eq!(
        arrows[&m(&["m", "a"])],
        [m(&["m", "b"])].into_iter().collect()
    );
    assert_eq!(
        arrows[&m(&["m", "b"])],
        [m(&["m", "a"])].into_iter().collect()
    );
    assert_eq!(
        arrows[&m(&["m", "c"])],
        [m(&["m", "a"])].into_iter().collect()
    );
    let found = cycles(&arrows);
    assert_eq!(found.len(), 1, "{found:?}");
    let mut members = found[0].clone();
    members.sort();
    assert_eq!(members, [m(&["m", "a"]), m(&["m", "b"])]);
}
