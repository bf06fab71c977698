//! What holds for the whole run, every context: the settings read from the
//! environment, the messages said once, and `--check`'s summary at exit.

use crate::check;
use crate::profile::Profile;
use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

/// How the run is set up: from the environment `deferred-msaa inject` sets.
pub(crate) struct Settings {
    /// `DMSAA_INJECT_CHECK=1`: the state and error checks around every call.
    pub(crate) check: bool,
    /// `DMSAA_INJECT_PROFILE`: the profile, read.
    pub(crate) profile: Option<Profile>,
    /// `DMSAA_INJECT_LEARN`: where to write a first profile (and retrofit
    /// nothing).
    pub(crate) learn: Option<std::path::PathBuf>,
    /// Why the retrofit is off from the start (a profile that did not
    /// load).
    pub(crate) off: Option<String>,
}

/// The run's settings, read once.
pub(crate) fn settings() -> &'static Settings {
    static SETTINGS: OnceLock<Settings> = OnceLock::new();
    SETTINGS.get_or_init(|| {
        let check = std::env::var("DMSAA_INJECT_CHECK").is_ok_and(|v| v == "1");
        let learn = std::env::var_os("DMSAA_INJECT_LEARN").map(Into::into);
        let (profile, off) = match std::env::var_os("DMSAA_INJECT_PROFILE") {
            None => (None, None),
            Some(path) => match Profile::load(std::path::Path::new(&path)) {
                Ok(p) => (Some(p), None),
                Err(e) => (None, Some(e.to_string())),
            },
        };
        if check {
            // SAFETY: a plain extern "C" function with no arguments.
            unsafe { libc::atexit(print_check_totals) };
        }
        Settings {
            check,
            profile,
            learn,
            off,
        }
    })
}

/// Say `message` on stderr, once per run for each `key`.
pub(crate) fn say_once(key: &str, message: &str) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said
        .get_or_insert_with(HashSet::new)
        .insert(key.to_string())
    {
        eprintln!("deferred-msaa inject: {message}");
    }
}

extern "C" fn print_check_totals() {
    let t = check::TOTALS.lock().unwrap_or_else(|e| e.into_inner());
    let resolves = RESOLVES.load(std::sync::atomic::Ordering::Relaxed);
    let calls: Vec<String> = t
        .by_call
        .iter()
        .map(|(call, n)| format!("{call} {n}"))
        .collect();
    eprintln!(
        "deferred-msaa inject: check: {} calls into the library, {} GL state values compared around each, \
         {} changed, {} GL errors left by the library, {} left pending by the program; {} frames resolved \
         (calls: {})",
        t.calls,
        t.values,
        t.changed,
        t.errors,
        t.program_errors,
        resolves,
        calls.join(", ")
    );
}

/// Frames resolved over the run, every context.
pub(super) static RESOLVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
