//! What both back ends' run-time loading shares: opening a system library
//! under one of its names and copying symbols out of it, with one-line
//! messages that say which.

/// The loader's message on one line.
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The first of `names` that loads, or every failure on one line, ending
/// with `hint` (which package to install).
pub(crate) fn open(names: &[&str], hint: &str) -> Result<libloading::Library, String> {
    let mut failures = Vec::new();
    for name in names {
        // SAFETY: loading a GL system library (libEGL, libOSMesa) runs its
        // initialisers, which are sound.
        match unsafe { libloading::Library::new(name) } {
            Ok(lib) => return Ok(lib),
            Err(e) => failures.push(one_line(&e.to_string())),
        }
    }
    Err(format!(
        "cannot load {} ({}); {hint}",
        names.first().copied().unwrap_or("the library"),
        failures.join("; ")
    ))
}

/// Copies a symbol out of `lib`.
///
/// # Safety
/// `T` must be the symbol's true function pointer type.
pub(crate) unsafe fn symbol<T: Copy>(lib: &libloading::Library, name: &str) -> Result<T, String> {
    let mut bytes = name.as_bytes().to_vec();
    bytes.push(0);
    // SAFETY: forwarded to the caller.
    unsafe { lib.get::<T>(&bytes) }
        .map(|s| *s)
        .map_err(|e| format!("{name} is missing ({})", one_line(&e.to_string())))
}
