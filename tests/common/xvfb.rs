//! An Xvfb server on a free display, for the tests that open real windows
//! (the viewer in the slow tier, the GLFW C++ host in the fast tier's C API
//! test), and the X client libraries they load.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An Xvfb server on a free display, stopped when dropped.
pub struct Xvfb {
    child: Child,
    number: u32,
}

impl Xvfb {
    /// The display, as `DISPLAY` names it.
    pub fn display(&self) -> String {
        format!(":{}", self.number)
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM lets the server remove its socket and lock file; SIGKILL
        // (what `Child::kill` sends) would leave them behind.
        let pid = self.child.id();
        let _ = Command::new("kill")
            .args(["-TERM", &pid.to_string()])
            .stderr(Stdio::null())
            .status();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(5) {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        // Whatever our server left behind, and only that.
        let lock = PathBuf::from(format!("/tmp/.X{}-lock", self.number));
        let ours = std::fs::read_to_string(&lock).is_ok_and(|text| text.trim() == pid.to_string());
        if ours {
            let _ = std::fs::remove_file(format!("/tmp/.X11-unix/X{}", self.number));
            let _ = std::fs::remove_file(lock);
        }
    }
}

/// Whether `program` is on `PATH`.
pub fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .map(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
        .unwrap_or(false)
}

/// The X client libraries winit loads at run time, and their Debian packages.
const X_CLIENT_LIBRARIES: [(&str, &str); 6] = [
    ("libX11.so.6", "libx11-6"),
    ("libX11-xcb.so.1", "libx11-xcb1"),
    ("libXcursor.so.1", "libxcursor1"),
    ("libXrandr.so.2", "libxrandr2"),
    ("libXi.so.6", "libxi6"),
    ("libxkbcommon-x11.so.0", "libxkbcommon-x11-0"),
];

/// A new Xvfb server, or `None` (with a skip line) where Xvfb or the X
/// client libraries are missing.
pub fn start_xvfb() -> Option<Xvfb> {
    if !on_path("Xvfb") {
        super::skip("Xvfb is not installed (Debian package xvfb)");
        return None;
    }
    let missing: Vec<&str> = X_CLIENT_LIBRARIES
        .iter()
        // SAFETY: these are plain C libraries whose initialisers only set up globals.
        .filter(|(library, _)| unsafe { libloading::Library::new(library) }.is_err())
        .map(|(_, package)| *package)
        .collect();
    if !missing.is_empty() {
        super::skip(&format!(
            "the viewer's X client libraries are missing (Debian packages {})",
            missing.join(" ")
        ));
        return None;
    }
    let first = 100 + std::process::id() % 300;
    for n in (first..first + 40).map(|n| n % 400 + 100) {
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{n}"));
        if socket.exists() || Path::new(&format!("/tmp/.X{n}-lock")).exists() {
            continue;
        }
        let child = Command::new("Xvfb")
            .arg(format!(":{n}"))
            .args(["-screen", "0", "320x240x24", "-nolisten", "tcp"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("starting Xvfb");
        let mut server = Xvfb { child, number: n };
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(15) {
            if let Ok(Some(_)) = server.child.try_wait() {
                break; // lost a race for this display: try the next
            }
            if socket.exists() {
                // The socket appears just before the server accepts clients.
                std::thread::sleep(Duration::from_millis(200));
                // Tests of one binary start from the same display number:
                // the socket may be another test's server, started a moment
                // before, while this one is still losing the race for the
                // display. The lock file names the winner.
                let lock = format!("/tmp/.X{n}-lock");
                let winner = std::fs::read_to_string(&lock).unwrap_or_default();
                if winner.trim() == server.child.id().to_string() {
                    return Some(server);
                }
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        drop(server);
    }
    panic!("no free X display for Xvfb between :100 and :499");
}
