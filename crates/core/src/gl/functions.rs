//! The GL entry points the crate calls, by name, so that a host's loader
//! can be checked before glow builds its function table from it: glow
//! stores a null pointer without complaint and panics only when the
//! function is called, in the middle of a pass.

use glow::HasContext;
use std::ffi::c_void;

/// Every entry point a retrofit may call on an OpenGL 3.2 core context
/// (glow's own calls while it is made included: `glGetString`,
/// `glGetIntegerv`, `glGetStringi`), and the two [`load_state_functions`]
/// loads.
///
/// [`load_state_functions`]: super::load_state_functions
pub const REQUIRED_FUNCTIONS: &[&str] = &[
    "glGetString",
    "glGetStringi",
    "glGetIntegerv",
    "glGetIntegeri_v",
    "glGetError",
    "glIsEnabled",
    "glIsEnabledi",
    "glGetBooleani_v",
    "glEnable",
    "glDisable",
    "glEnablei",
    "glDisablei",
    "glActiveTexture",
    "glBindTexture",
    "glGenTextures",
    "glDeleteTextures",
    "glIsTexture",
    "glTexImage2D",
    "glTexImage3D",
    "glTexImage2DMultisample",
    "glTexParameteri",
    "glGetTexLevelParameteriv",
    "glPixelStorei",
    "glGenFramebuffers",
    "glDeleteFramebuffers",
    "glIsFramebuffer",
    "glBindFramebuffer",
    "glFramebufferTexture",
    "glFramebufferTexture2D",
    "glFramebufferTextureLayer",
    "glFramebufferRenderbuffer",
    "glCheckFramebufferStatus",
    "glGetFramebufferAttachmentParameteriv",
    "glDrawBuffers",
    "glReadBuffer",
    "glBlitFramebuffer",
    "glReadPixels",
    "glBindRenderbuffer",
    "glGenRenderbuffers",
    "glDeleteRenderbuffers",
    "glRenderbufferStorage",
    "glIsRenderbuffer",
    "glGetRenderbufferParameteriv",
    "glGenBuffers",
    "glDeleteBuffers",
    "glIsBuffer",
    "glBindBuffer",
    "glBufferData",
    "glGenVertexArrays",
    "glDeleteVertexArrays",
    "glBindVertexArray",
    "glCreateShader",
    "glDeleteShader",
    "glShaderSource",
    "glCompileShader",
    "glGetShaderiv",
    "glGetShaderInfoLog",
    "glCreateProgram",
    "glDeleteProgram",
    "glIsProgram",
    "glAttachShader",
    "glDetachShader",
    "glBindFragDataLocation",
    "glLinkProgram",
    "glGetProgramiv",
    "glGetProgramInfoLog",
    "glUseProgram",
    "glGetUniformLocation",
    "glUniform1i",
    "glUniform1ui",
    "glUniform1f",
    "glUniform2f",
    "glUniform3f",
    "glUniform4f",
    "glUniform4fv",
    "glUniformMatrix4fv",
    "glGenQueries",
    "glDeleteQueries",
    "glBeginQuery",
    "glEndQuery",
    "glGetQueryObjectuiv",
    "glViewport",
    "glScissor",
    "glPolygonMode",
    "glDepthFunc",
    "glDepthMask",
    "glColorMask",
    "glColorMaski",
    "glStencilFunc",
    "glStencilFuncSeparate",
    "glStencilOp",
    "glStencilOpSeparate",
    "glStencilMask",
    "glStencilMaskSeparate",
    "glClear",
    "glClearColor",
    "glClearDepth",
    "glClearStencil",
    "glClearBufferfv",
    "glClearBufferiv",
    "glClearBufferuiv",
    "glClearBufferfi",
    "glGetFloatv",
    "glDrawArrays",
    "glFinish",
];

/// Entry points the crate calls only where the context offers what they
/// belong to: the GL version that made them core, or the extension.
pub const CONDITIONAL_FUNCTIONS: &[(&str, (u32, u32), &str)] = &[
    ("glCopyImageSubData", (4, 3), "GL_ARB_copy_image"),
    (
        "glGetInternalformativ",
        (4, 2),
        "GL_ARB_internalformat_query",
    ),
    ("glGetQueryObjectui64v", (3, 3), "GL_ARB_timer_query"),
    ("glObjectLabel", (4, 3), "GL_KHR_debug"),
    ("glDebugMessageCallback", (4, 3), "GL_KHR_debug"),
    ("glGetFloati_v", (4, 1), "GL_ARB_viewport_array"),
    ("glViewportArrayv", (4, 1), "GL_ARB_viewport_array"),
    ("glScissorArrayv", (4, 1), "GL_ARB_viewport_array"),
];

/// The first of [`REQUIRED_FUNCTIONS`] that `loader` returns null for.
/// Call it before building a glow context from the loader.
pub fn first_missing_function(
    mut loader: impl FnMut(&str) -> *const c_void,
) -> Option<&'static str> {
    REQUIRED_FUNCTIONS
        .iter()
        .copied()
        .find(|name| loader(name).is_null())
}

/// The first of [`CONDITIONAL_FUNCTIONS`] that `gl`'s version or
/// extensions offer and `loader` returns null for: the crate would call it.
pub fn first_missing_conditional_function(
    gl: &glow::Context,
    mut loader: impl FnMut(&str) -> *const c_void,
) -> Option<&'static str> {
    let version = gl.version();
    let extensions = gl.supported_extensions();
    CONDITIONAL_FUNCTIONS
        .iter()
        .filter(|(_, core, extension)| {
            (version.major, version.minor) >= *core || extensions.contains(*extension)
        })
        .map(|(name, _, _)| *name)
        .find(|name| loader(name).is_null())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// glow's methods the crate calls, and the GL entry points each calls
    /// (none: the method reads what glow stored when it was made).
    const GLOW_METHODS: &[(&str, &[&str])] = &[
        ("active_texture", &["glActiveTexture"]),
        ("attach_shader", &["glAttachShader"]),
        ("begin_query", &["glBeginQuery"]),
        ("bind_buffer", &["glBindBuffer"]),
        ("bind_frag_data_location", &["glBindFragDataLocation"]),
        ("bind_framebuffer", &["glBindFramebuffer"]),
        ("bind_renderbuffer", &["glBindRenderbuffer"]),
        ("bind_texture", &["glBindTexture"]),
        ("bind_vertex_array", &["glBindVertexArray"]),
        ("blit_framebuffer", &["glBlitFramebuffer"]),
        ("buffer_data_size", &["glBufferData"]),
        ("buffer_data_u8_slice", &["glBufferData"]),
        ("check_framebuffer_status", &["glCheckFramebufferStatus"]),
        ("clear", &["glClear"]),
        ("clear_buffer_f32_slice", &["glClearBufferfv"]),
        ("clear_buffer_i32_slice", &["glClearBufferiv"]),
        ("clear_buffer_u32_slice", &["glClearBufferuiv"]),
        ("clear_color", &["glClearColor"]),
        ("clear_depth_f64", &["glClearDepth"]),
        ("clear_stencil", &["glClearStencil"]),
        ("color_mask", &["glColorMask"]),
        ("color_mask_draw_buffer", &["glColorMaski"]),
        ("compile_shader", &["glCompileShader"]),
        ("copy_image_sub_data", &["glCopyImageSubData"]),
        ("create_buffer", &["glGenBuffers"]),
        ("create_framebuffer", &["glGenFramebuffers"]),
        ("create_program", &["glCreateProgram"]),
        ("create_query", &["glGenQueries"]),
        ("create_renderbuffer", &["glGenRenderbuffers"]),
        ("create_shader", &["glCreateShader"]),
        ("create_texture", &["glGenTextures"]),
        ("create_vertex_array", &["glGenVertexArrays"]),
        ("debug_message_callback", &["glDebugMessageCallback"]),
        ("delete_buffer", &["glDeleteBuffers"]),
        ("delete_framebuffer", &["glDeleteFramebuffers"]),
        ("delete_program", &["glDeleteProgram"]),
        ("delete_query", &["glDeleteQueries"]),
        ("delete_renderbuffer", &["glDeleteRenderbuffers"]),
        ("delete_shader", &["glDeleteShader"]),
        ("delete_texture", &["glDeleteTextures"]),
        ("delete_vertex_array", &["glDeleteVertexArrays"]),
        ("depth_func", &["glDepthFunc"]),
        ("depth_mask", &["glDepthMask"]),
        ("detach_shader", &["glDetachShader"]),
        ("disable", &["glDisable"]),
        ("disable_draw_buffer", &["glDisablei"]),
        ("draw_arrays", &["glDrawArrays"]),
        ("draw_buffers", &["glDrawBuffers"]),
        ("enable", &["glEnable"]),
        ("enable_draw_buffer", &["glEnablei"]),
        ("end_query", &["glEndQuery"]),
        ("finish", &["glFinish"]),
        ("framebuffer_renderbuffer", &["glFramebufferRenderbuffer"]),
        ("framebuffer_texture", &["glFramebufferTexture"]),
        ("framebuffer_texture_2d", &["glFramebufferTexture2D"]),
        ("framebuffer_texture_layer", &["glFramebufferTextureLayer"]),
        ("get_error", &["glGetError"]),
        (
            "get_framebuffer_attachment_parameter_i32",
            &["glGetFramebufferAttachmentParameteriv"],
        ),
        ("get_internal_format_i32_slice", &["glGetInternalformativ"]),
        ("get_parameter_i32", &["glGetIntegerv"]),
        ("get_parameter_i32_slice", &["glGetIntegerv"]),
        ("get_parameter_indexed_i32", &["glGetIntegeri_v"]),
        ("get_parameter_string", &["glGetString"]),
        (
            "get_program_info_log",
            &["glGetProgramiv", "glGetProgramInfoLog"],
        ),
        ("get_program_link_status", &["glGetProgramiv"]),
        ("get_query_parameter_u32", &["glGetQueryObjectuiv"]),
        ("get_parameter_f32", &["glGetFloatv"]),
        ("get_parameter_f32_slice", &["glGetFloatv"]),
        ("clear_buffer_depth_stencil", &["glClearBufferfi"]),
        ("get_query_parameter_u64", &["glGetQueryObjectui64v"]),
        (
            "get_renderbuffer_parameter_i32",
            &["glGetRenderbufferParameteriv"],
        ),
        ("get_shader_compile_status", &["glGetShaderiv"]),
        (
            "get_shader_info_log",
            &["glGetShaderiv", "glGetShaderInfoLog"],
        ),
        ("get_tex_level_parameter_i32", &["glGetTexLevelParameteriv"]),
        ("get_uniform_location", &["glGetUniformLocation"]),
        ("is_buffer", &["glIsBuffer"]),
        ("is_enabled", &["glIsEnabled"]),
        ("is_framebuffer", &["glIsFramebuffer"]),
        ("is_program", &["glIsProgram"]),
        ("is_renderbuffer", &["glIsRenderbuffer"]),
        ("is_texture", &["glIsTexture"]),
        ("link_program", &["glLinkProgram"]),
        ("object_label", &["glObjectLabel"]),
        ("pixel_store_i32", &["glPixelStorei"]),
        ("polygon_mode", &["glPolygonMode"]),
        ("read_buffer", &["glReadBuffer"]),
        ("read_pixels", &["glReadPixels"]),
        ("renderbuffer_storage", &["glRenderbufferStorage"]),
        ("scissor", &["glScissor"]),
        ("scissor_slice", &["glScissorArrayv"]),
        ("shader_source", &["glShaderSource"]),
        ("stencil_func", &["glStencilFunc"]),
        ("stencil_func_separate", &["glStencilFuncSeparate"]),
        ("stencil_mask", &["glStencilMask"]),
        ("stencil_mask_separate", &["glStencilMaskSeparate"]),
        ("stencil_op", &["glStencilOp"]),
        ("stencil_op_separate", &["glStencilOpSeparate"]),
        ("supported_extensions", &[]),
        ("tex_image_2d", &["glTexImage2D"]),
        ("tex_image_2d_multisample", &["glTexImage2DMultisample"]),
        ("tex_image_3d", &["glTexImage3D"]),
        ("tex_parameter_i32", &["glTexParameteri"]),
        ("uniform_1_f32", &["glUniform1f"]),
        ("uniform_1_i32", &["glUniform1i"]),
        ("uniform_1_u32", &["glUniform1ui"]),
        ("uniform_2_f32", &["glUniform2f"]),
        ("uniform_3_f32", &["glUniform3f"]),
        ("uniform_4_f32", &["glUniform4f"]),
        ("uniform_4_f32_slice", &["glUniform4fv"]),
        ("uniform_matrix_4_f32_slice", &["glUniformMatrix4fv"]),
        ("use_program", &["glUseProgram"]),
        ("version", &[]),
        ("viewport", &["glViewport"]),
        ("viewport_f32_slice", &["glViewportArrayv"]),
    ];

    fn sources(dir: &std::path::Path, out: &mut Vec<(String, String)>) {
        for entry in std::fs::read_dir(dir)
            .expect("reading the crate's sources")
            .flatten()
        {
            let path = entry.path();
            if path.is_dir() {
                sources(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).expect("reading a source file");
                out.push((path.display().to_string(), text));
            }
        }
    }

    /// The names `gl.NAME(` calls in `text`.
    fn called_methods(text: &str) -> Vec<String> {
        let mut found = Vec::new();
        for (at, _) in text.match_indices("gl.") {
            let before = text[..at].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let name: String = text[at + 3..]
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
                .collect();
            if !name.is_empty() && text[at + 3 + name.len()..].starts_with('(') {
                found.push(name);
            }
        }
        found
    }

    #[test]
    fn every_gl_call_of_the_crate_is_listed() {
        let mut files = Vec::new();
        sources(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
            &mut files,
        );
        let listed = |gl_name: &str| {
            REQUIRED_FUNCTIONS.contains(&gl_name)
                || CONDITIONAL_FUNCTIONS.iter().any(|(n, _, _)| *n == gl_name)
        };
        let mut methods = 0;
        for (path, text) in &files {
            for method in called_methods(text) {
                methods += 1;
                let Some((_, names)) = GLOW_METHODS.iter().find(|(m, _)| *m == method) else {
                    panic!("{path} calls gl.{method}, which GLOW_METHODS does not map to GL names");
                };
                for name in *names {
                    assert!(
                        listed(name),
                        "{path}: gl.{method} calls {name}, which is not listed"
                    );
                }
            }
        }
        assert!(methods > GLOW_METHODS.len(), "only {methods} calls found");
    }

    #[test]
    fn the_first_missing_function_is_named() {
        let missing = "glGetBooleani_v";
        let loader = |name: &str| {
            if name == missing {
                std::ptr::null()
            } else {
                std::ptr::NonNull::<c_void>::dangling()
                    .as_ptr()
                    .cast_const()
            }
        };
        assert_eq!(first_missing_function(loader), Some(missing));
        let all = |_: &str| {
            std::ptr::NonNull::<c_void>::dangling()
                .as_ptr()
                .cast_const()
        };
        assert_eq!(first_missing_function(all), None);
    }
}
