//! The committed header is what cbindgen makes of the declarations now:
//! a change to the C API that is not in `include/deferred_msaa.h` fails
//! here (and so in CI). `DEFERRED_MSAA_BLESS=1` rewrites the header.

use std::path::Path;

#[test]
fn the_committed_header_is_up_to_date() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("reading cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/lib.rs"))
        .generate()
        .expect("generating the header from src/lib.rs")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("the header is UTF-8");
    let path = crate_dir.join("include/deferred_msaa.h");
    if std::env::var_os("DEFERRED_MSAA_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("writing the header");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let line = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || committed.lines().count().min(generated.lines().count()) + 1,
                |n| n + 1,
            );
        panic!(
            "{} is stale (first difference at line {line}): the C API changed; \
             run `DEFERRED_MSAA_BLESS=1 cargo test -p deferred-msaa-capi --test header` \
             and commit the header",
            path.display()
        );
    }
}
