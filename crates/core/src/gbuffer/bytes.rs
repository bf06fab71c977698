//! Byte counts as people read them, for the budget's warnings and the
//! errors that quote it (a leaf, so that `crate::Error` can use it).

/// `bytes` for people: `512.0 MiB`, `1.25 GiB`, `900 B`.
pub fn fmt_bytes(bytes: u64) -> String {
    const KIB: f64 = 1024.0;
    let b = bytes as f64;
    if b >= KIB * KIB * KIB {
        format!("{:.2} GiB", b / (KIB * KIB * KIB))
    } else if b >= KIB * KIB {
        format!("{:.1} MiB", b / (KIB * KIB))
    } else if b >= KIB {
        format!("{:.1} KiB", b / KIB)
    } else {
        format!("{bytes} B")
    }
}
