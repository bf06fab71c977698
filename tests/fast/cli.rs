//! The command line as a user meets it: real processes, real files, exit codes
//! and one-line refusals.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

fn cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deferred-msaa"))
        .args(args)
        .output()
        .expect("running deferred-msaa")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "exit {:?}: {}", o.status, stderr(o));
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

fn check_info(info: &serde_json::Value, backend: &str) {
    assert_eq!(info["backend"], backend);
    for key in ["gl_version", "glsl_version", "renderer"] {
        assert!(
            !info[key].as_str().unwrap_or("").is_empty(),
            "{key} missing: {info}"
        );
    }
    assert!(info["max_samples"].as_u64().unwrap_or(0) >= 1);
    let counts = info["sample_counts"]["RGBA16F"]
        .as_array()
        .expect("RGBA16F counts");
    assert!(!counts.is_empty());
    for n in counts {
        let key = n.as_u64().unwrap().to_string();
        let positions = info["sample_positions"][&key]
            .as_array()
            .expect("positions per count");
        assert_eq!(positions.len() as u64, n.as_u64().unwrap(), "{info}");
    }
}

#[test]
fn info_reports_the_real_context_on_both_backends() {
    if common::egl_context().is_some() {
        check_info(&json(&cli(&["info", "--json"])), "egl");
    }
    if common::context(deferred_msaa_lab::context::Backend::OsMesa).is_some() {
        check_info(
            &json(&cli(&["info", "--json", "--backend", "osmesa"])),
            "osmesa",
        );
    }
}

#[test]
fn info_on_the_gl_3_2_floor() {
    if common::egl_context().is_none() {
        return;
    }
    for backend in ["egl", "osmesa"] {
        let out = common::floor_command()
            .args(["info", "--json", "--backend", backend])
            .output()
            .unwrap();
        let info = json(&out);
        assert!(
            info["gl_version"].as_str().unwrap().starts_with("3.2"),
            "{info}"
        );
        assert!(
            info["glsl_version"].as_str().unwrap().starts_with("1.50"),
            "{info}"
        );
    }
}

#[test]
fn render_and_dump_write_what_they_say() {
    if common::egl_context().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("dmsaa-cli-{}", std::process::id()));
    let png = dir.join("out.png");
    let o = cli(&["render", "--size", "96x54", "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (96, 54));
    for view in ["normal", "position", "depth", "emissive"] {
        let o = cli(&[
            "render",
            "--size",
            "32x18",
            "--view",
            view,
            "--out",
            png.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{view}: {}", stderr(&o));
    }

    let dump = dir.join("dump");
    let o = cli(&[
        "dump",
        "--size",
        "40x24",
        "--method",
        "front",
        "--window",
        "hard",
        "--out",
        dump.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dump.join("meta.json")).unwrap()).unwrap();
    for key in [
        "width",
        "height",
        "samples",
        "fov_y",
        "near",
        "far",
        "projection",
        "clear_depth",
        "method",
        "window",
        "c",
        "c_in",
        "fast_path",
        "key_source",
        "attachments",
    ] {
        assert!(meta.get(key).is_some(), "meta.json lacks {key}: {meta}");
    }
    assert_eq!(
        (meta["width"].as_u64(), meta["height"].as_u64()),
        (Some(40), Some(24))
    );
    assert_eq!(
        (meta["method"].as_str(), meta["window"].as_str()),
        (Some("front"), Some("hard"))
    );
    let n = meta["samples"].as_u64().unwrap() as usize;
    let header = |name: &str| -> String {
        let bytes = std::fs::read(dump.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(&bytes[..6], b"\x93NUMPY");
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        String::from_utf8_lossy(&bytes[10..10 + len]).into_owned()
    };
    for a in meta["attachments"].as_array().unwrap() {
        let name = a["name"].as_str().unwrap();
        let c = if a["format"] == "R32F" { 1 } else { 4 };
        assert!(header(&format!("{name}_samples.npy")).contains(&format!("({n}, 24, 40, {c})")));
        assert!(header(&format!("{name}_resolved.npy")).contains(&format!("(24, 40, {c})")));
    }
    assert!(header("depth_samples.npy").contains(&format!("({n}, 24, 40)")));
    assert!(header("depth_resolved.npy").contains("(24, 40)"));
    assert!(Path::new(&dump.join("final.png")).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The values of a float32 `.npy` file `dump` wrote, and its header.
fn read_npy(path: &Path) -> (String, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = String::from_utf8_lossy(&bytes[10..10 + len]).into_owned();
    let data = bytes[10 + len..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    (header, data)
}

#[test]
fn dump_with_two_layers_writes_the_second_layer() {
    if common::egl_context().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("dmsaa-cli-layers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let dump = |layers: &str| {
        let out = dir.join(format!("layers{layers}"));
        let o = cli(&[
            "dump",
            "--scene",
            "builtin:bars",
            "--size",
            "48x27",
            "--layers",
            layers,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("meta.json")).unwrap()).unwrap();
        (out, meta)
    };

    let (one, meta) = dump("1");
    assert_eq!(meta["layers"].as_u64(), Some(1));
    assert!(meta["second_layer"].is_null(), "{meta}");
    assert!(!one.join("layer2_coverage.npy").exists());

    let (two, meta) = dump("2");
    assert_eq!(meta["layers"].as_u64(), Some(2));
    let second = &meta["second_layer"];
    let names: Vec<&str> = meta["attachments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    let files = second["attachments"]
        .as_array()
        .expect("second_layer.attachments");
    assert_eq!(
        files
            .iter()
            .map(|f| f["name"].as_str().unwrap())
            .collect::<Vec<_>>(),
        names,
        "one second-layer file per attachment, in order"
    );
    for (f, a) in files.iter().zip(meta["attachments"].as_array().unwrap()) {
        let c = if a["format"] == "R32F" { 1 } else { 4 };
        let (header, _) = read_npy(&two.join(f["file"].as_str().unwrap()));
        assert!(header.contains(&format!("(27, 48, {c})")), "{header}");
    }
    let (header, coverage) = read_npy(&two.join(second["coverage"].as_str().unwrap()));
    assert!(header.contains("(27, 48)"), "{header}");
    let (_, depth) = read_npy(&two.join(second["depth"].as_str().unwrap()));
    assert!(
        coverage.iter().all(|a| (0.0..1.0).contains(a)),
        "coverage in [0, 1)"
    );
    let covered = coverage.iter().filter(|&&a| a > 0.0).count();
    assert!(
        covered > 0 && covered < coverage.len() / 2,
        "the bars' silhouettes have a second layer: {covered} of {} pixels",
        coverage.len()
    );
    // Where nothing is covered the second layer holds the clear depth (a
    // covered pixel may too: a bar's second layer can be the background).
    let clear = meta["clear_depth"].as_f64().unwrap() as f32;
    for (a, d) in coverage.iter().zip(&depth) {
        if *a == 0.0 {
            assert_eq!(*d, clear);
        }
    }
    assert!(
        coverage
            .iter()
            .zip(&depth)
            .any(|(a, d)| *a > 0.0 && *d != clear),
        "some second layer is a surface"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn refusals_are_one_line_with_a_non_zero_exit() {
    let cases: &[(&[&str], &str)] = &[
        (&["info", "--backend", "glx"], "glx"),
        (
            &["render", "--scene", "/no/such/file.glb"],
            "/no/such/file.glb",
        ),
        (&["render", "--scene", "builtin:nothing"], "nothing"),
        (&["render", "--size", "0x0"], "0x0"),
        (&["render", "--size", "big"], "big"),
        (&["render", "--method", "sideways"], "sideways"),
        (&["render", "--window", "round"], "round"),
        (&["render", "--c", "2", "--c-in", "3"], "--c-in"),
        (&["render", "--samples", "64", "--size", "16x16"], "64x"),
        (&["render", "--view", "nope", "--size", "16x16"], "nope"),
        (&["render", "--aa-region", "circle:1,2,3,4"], "circle"),
        (&["render", "--aa-region", "ellipse:8,8,0,4"], "radii"),
        (&["render", "--aa-region", "rect:1,2,3"], "four numbers"),
        (
            &["render", "--method", "none", "--aa-max-depth", "5"],
            "none",
        ),
        (&["render", "--aa-max-depth", "-1", "--size", "16x16"], "-1"),
        (&["render", "--layers", "3", "--size", "16x16"], "layers"),
        (&["render", "--method", "gbaa", "--layers", "2"], "gbaa"),
        (
            &["render", "--method", "average", "--layers", "2"],
            "average",
        ),
        (
            &["render", "--view", "layers", "--size", "16x16"],
            "--layers 2",
        ),
        (&["frobnicate"], "frobnicate"),
    ];
    for (args, needle) in cases {
        let o = cli(args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{args:?}: not one line:\n{err}"
        );
        assert!(
            err.contains(needle),
            "{args:?}: `{err}` does not mention {needle}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}
