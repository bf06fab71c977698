//! What holds for the whole run, every context: the settings read from the
//! environment, the messages said once, what was seen of the program, the
//! one line at exit for a run that said nothing else, and `--check`'s
//! summary at exit.

use crate::check;
use crate::profile::Profile;
use std::collections::{BTreeSet, HashSet};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
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

/// Whether a line saying what the run did (or why it did nothing) was said.
static OUTCOME_SAID: AtomicBool = AtomicBool::new(false);

/// Say `message` on stderr, once per run for each `key`. Every key but
/// `"pending"` and `"warning-…"` says what the run did or why it did
/// nothing, so that the exit line is not said too.
pub(crate) fn say_once(key: &str, message: &str) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said
        .get_or_insert_with(HashSet::new)
        .insert(key.to_string())
    {
        if key != "pending" && !key.starts_with("warning") {
            OUTCOME_SAID.store(true, Ordering::Relaxed);
        }
        eprintln!("deferred-msaa inject: {message}");
    }
}

/// What the library saw of the program over the run, every context: what
/// the exit line says where nothing else was said.
#[derive(Default)]
pub(crate) struct Seen {
    /// Draw calls that reached the library.
    pub(crate) draws: u64,
    /// Framebuffers drawn into with a G-buffer's shape.
    pub(crate) candidates: BTreeSet<u32>,
    /// The G-buffer found last, and whether it was retrofitted.
    pub(crate) found: Option<u32>,
    pub(crate) retrofitted: bool,
    /// A G-buffer found, then deleted before it was bound for drawing
    /// again: its name, and how many times (twice or more: one made and
    /// deleted for each image; once: a program that ends after one).
    pub(crate) made_and_deleted: Option<(u32, u64)>,
    /// A get-proc-address the library does not stand in for, that the
    /// program looked up (`OSMesaGetProcAddress`).
    pub(crate) other_loader: Option<&'static str>,
}

/// What was seen, every context.
pub(crate) static SEEN: Mutex<Seen> = Mutex::new(Seen {
    draws: 0,
    candidates: BTreeSet::new(),
    found: None,
    retrofitted: false,
    made_and_deleted: None,
    other_loader: None,
});

/// Frames ended (swaps), every context.
pub(crate) static FRAMES: AtomicU64 = AtomicU64::new(0);

/// `f` on what was seen.
pub(crate) fn seen<R>(f: impl FnOnce(&mut Seen) -> R) -> R {
    f(&mut SEEN.lock().unwrap_or_else(|e| e.into_inner()))
}

/// What the library looks for without a profile, for the lines that say
/// none was found.
pub(crate) const LOOKED_FOR: &str = "looked for a complete single-sample framebuffer with two or more colour \
     textures and depth, drawn into, two of whose colour textures a later draw reads together";

/// The one line saying why the program is left alone, from what was seen
/// over `frames` frames: at its exit (`ended`) for a run that said nothing
/// else, or after its second frame.
pub(crate) fn left_alone(seen: &Seen, frames: u64, ended: bool) -> String {
    let frames_said = match (frames, ended) {
        (0, _) => {
            "no frame boundary was seen: no glXSwapBuffers or eglSwapBuffers after a draw, as in a \
                   surfaceless program"
                .to_string()
        }
        (1, true) => "the program ended after one frame".to_string(),
        (n, true) => format!("the program ended after {n} frames"),
        (n, false) => format!("{n} frames seen"),
    };
    if seen.draws == 0 {
        return format!(
            "no draw call reached the library ({frames_said}): GL was not reached through glXGetProcAddress, \
             eglGetProcAddress, dlsym or libGL's symbols{}; leaving the program untouched",
            match seen.other_loader {
                Some(name) => format!(
                    " (the program looked up {name}, whose contexts and entry points the library does not follow)"
                ),
                None => String::new(),
            }
        );
    }
    if let Some((g, times)) = seen.made_and_deleted.filter(|&(_, n)| n >= 2) {
        return format!(
            "framebuffer {g}, found as the G-buffer, was deleted before it was bound for drawing again \
             ({times} time(s)): a G-buffer made and deleted within a frame, as a one-call render does, is never \
             retrofitted (the retrofit takes the G-buffer from its next bind); {frames_said}; leaving the program \
             untouched (keep the G-buffer alive across frames, or give a profile its signature: [framebuffer], which \
             --learn writes)"
        );
    }
    if let Some(g) = seen.found.filter(|_| !seen.retrofitted) {
        return format!(
            "found the G-buffer (framebuffer {g}), but it was never bound for drawing again ({frames_said}): \
             the frame it is found in is the program's own (the retrofit starts at the G-buffer's next bind), \
             so a program that renders one frame, as a screenshot harness does, is never retrofitted; leaving \
             the program untouched"
        );
    }
    let what = if !seen.candidates.is_empty() {
        format!(
            "framebuffer(s) {:?} have the shape of a G-buffer, but no later draw read two of their colour \
             textures together (a profile can name it)",
            seen.candidates.iter().collect::<Vec<_>>()
        )
    } else {
        format!("no G-buffer found ({LOOKED_FOR})")
    };
    format!("{what}; {frames_said}; leaving the program untouched")
}

/// Whether a line saying what the run did was said.
pub(crate) fn outcome_said() -> bool {
    OUTCOME_SAID.load(Ordering::Relaxed)
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
pub(super) static RESOLVES: AtomicU64 = AtomicU64::new(0);
