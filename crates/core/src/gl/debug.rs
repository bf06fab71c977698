//! KHR_debug: driver messages into `log`, debug labels on objects.

use glow::HasContext;

fn has_khr_debug(gl: &glow::Context) -> bool {
    let v = gl.version();
    (v.major, v.minor) >= (4, 3) || gl.supported_extensions().contains("GL_KHR_debug")
}

/// Route the driver's debug messages to `log`: high-severity notes as `warn!`,
/// GL errors (which also come back as typed errors) and the rest as `debug!`. Returns `false` when the context lacks
/// KHR_debug; then nothing is installed.
pub fn install_debug_log(gl: &mut glow::Context) -> bool {
    if !has_khr_debug(gl) {
        return false;
    }
    unsafe {
        gl.enable(glow::DEBUG_OUTPUT);
        gl.debug_message_callback(|source, kind, id, severity, message| {
            let _ = source;
            match (kind, severity) {
                // GL errors also reach the caller as typed errors (check_error):
                // logging them loudly would say the same thing twice.
                (glow::DEBUG_TYPE_ERROR, _) => log::debug!(target: "gl", "[{id}] {message}"),
                (_, glow::DEBUG_SEVERITY_HIGH) => log::warn!(target: "gl", "[{id}] {message}"),
                (_, glow::DEBUG_SEVERITY_MEDIUM) => log::warn!(target: "gl", "[{id}] {message}"),
                (_, glow::DEBUG_SEVERITY_NOTIFICATION) => {
                    log::trace!(target: "gl", "[{id}] {message}")
                }
                _ => log::debug!(target: "gl", "[{id}] {message}"),
            }
        });
    }
    true
}

/// Give an object a debug label where KHR_debug exists (a no-op elsewhere).
/// `identifier` is the namespace, e.g. `glow::TEXTURE`; `name` the raw GL name.
pub fn label_object(gl: &glow::Context, identifier: u32, name: u32, label: &str) {
    if has_khr_debug(gl) {
        unsafe { gl.object_label(identifier, name, Some(label)) };
    }
}
