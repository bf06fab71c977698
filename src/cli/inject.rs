//! `deferred-msaa inject`: run an unmodified deferred GL program with the
//! retrofit applied from outside, through the preloaded library of
//! `crates/inject` (docs/inject.md).

use crate::{Error, Result};
use std::ffi::{CString, OsString, c_char};
use std::path::{Path, PathBuf};

/// The preloaded library's file name.
const LIBRARY: &str = "libdeferred_msaa_inject.so";

/// Run a program with the retrofit injected.
#[derive(Debug, Clone, clap::Args)]
pub struct InjectArgs {
    /// A profile (TOML) saying which framebuffer is the G-buffer, what its
    /// attachments hold and the retrofit's options; without one the
    /// library finds the G-buffer itself and uses the default options.
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Retrofit nothing; write a first profile from one observed frame to
    /// this file.
    #[arg(long)]
    pub learn: Option<PathBuf>,
    /// Read the GL state and errors around every call into the library and
    /// sum them up on stderr at exit.
    #[arg(long)]
    pub check: bool,
    /// The preloaded library (default: `$DMSAA_INJECT_LIBRARY`, else
    /// `libdeferred_msaa_inject.so` beside this binary, in its `deps/`, or
    /// in `../lib`).
    #[arg(long)]
    pub library: Option<PathBuf>,
    /// The program and its arguments, after `--`.
    #[arg(required = true, last = true)]
    pub program: Vec<OsString>,
}

/// The library to preload: the flag, the environment, then the places a
/// build or an install puts it.
fn find_library(flag: Option<&Path>) -> Result<PathBuf> {
    if let Some(p) = flag {
        return Ok(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("DMSAA_INJECT_LIBRARY") {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe()
        .map_err(|e| Error::InvalidArgument(format!("cannot find this binary's path: {e}")))?;
    let dir = exe.parent().unwrap_or(Path::new("."));
    let candidates = [
        dir.join(LIBRARY),
        dir.join("deps").join(LIBRARY),
        dir.join("../lib").join(LIBRARY),
    ];
    candidates.iter().find(|p| p.is_file()).cloned().ok_or_else(|| {
        Error::InvalidArgument(format!(
            "no {LIBRARY} beside {} (build it with `cargo build -p deferred-msaa-inject`, or give --library or DMSAA_INJECT_LIBRARY)",
            dir.display()
        ))
    })
}

/// Ask the library itself whether the profile is valid, so that a bad one
/// is refused before the program starts (the library's parser is the one
/// that will read it).
fn check_profile(library: &Path, profile: &Path) -> Result<()> {
    type Check = unsafe extern "C" fn(*const c_char, *mut c_char, usize) -> i32;
    let refuse = |why: String| Error::InvalidArgument(why);
    // SAFETY: the library's initialisers only set up statics; its `dlsym`
    // is not in the global scope of this process (RTLD_LOCAL).
    let lib = unsafe { libloading::Library::new(library) }
        .map_err(|e| refuse(format!("cannot load {}: {e}", library.display())))?;
    // SAFETY: the function's C signature, as crates/inject declares it.
    let check: libloading::Symbol<Check> = unsafe { lib.get(b"dmsaa_inject_check_profile\0") }
        .map_err(|e| {
            refuse(format!(
                "{} is not the inject library: {e}",
                library.display()
            ))
        })?;
    let path = CString::new(profile.as_os_str().as_encoded_bytes()).map_err(|_| {
        refuse(format!(
            "the profile path {} holds a NUL byte",
            profile.display()
        ))
    })?;
    let mut message = vec![0u8; 1024];
    // SAFETY: a C string and a writable buffer of the length given.
    let status = unsafe { check(path.as_ptr(), message.as_mut_ptr().cast(), message.len()) };
    if status == 0 {
        return Ok(());
    }
    let end = message
        .iter()
        .position(|&b| b == 0)
        .unwrap_or(message.len());
    Err(refuse(
        String::from_utf8_lossy(&message[..end]).into_owned(),
    ))
}

/// Run the program under the library; its exit status is the return value.
pub fn run(args: &InjectArgs) -> Result<i32> {
    let library = find_library(args.library.as_deref())?;
    let library = library.canonicalize().map_err(|e| {
        Error::InvalidArgument(format!("the inject library {}: {e}", library.display()))
    })?;
    if let Some(profile) = &args.profile {
        check_profile(&library, profile)?;
    }
    let (program, rest) = args
        .program
        .split_first()
        .ok_or_else(|| Error::InvalidArgument("no program given after --".into()))?;
    let mut preload = OsString::from(&library);
    if let Some(old) = std::env::var_os("LD_PRELOAD").filter(|v| !v.is_empty()) {
        preload.push(":");
        preload.push(old);
    }
    let mut command = std::process::Command::new(program);
    command.args(rest).env("LD_PRELOAD", preload);
    for (var, value) in [
        (
            "DMSAA_INJECT_PROFILE",
            args.profile.as_ref().map(|p| p.as_os_str().to_owned()),
        ),
        (
            "DMSAA_INJECT_LEARN",
            args.learn.as_ref().map(|p| p.as_os_str().to_owned()),
        ),
        ("DMSAA_INJECT_CHECK", args.check.then(|| "1".into())),
    ] {
        match value {
            Some(v) => command.env(var, v),
            None => command.env_remove(var),
        };
    }
    let status = command.status().map_err(|e| {
        Error::InvalidArgument(format!("cannot run {}: {e}", Path::new(program).display()))
    })?;
    // A program killed by a signal: the shell's convention, 128 + signal.
    Ok(status.code().unwrap_or_else(|| {
        use std::os::unix::process::ExitStatusExt;
        128 + status.signal().unwrap_or(0)
    }))
}
