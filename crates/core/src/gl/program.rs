//! Shader programs: compiled from a file body with a generated preamble.

use super::counters::{self, Kind};
use super::{check_error, label_object};
use crate::{Error, Result};
use glow::HasContext;
use std::cell::RefCell;
use std::collections::HashMap;

/// A shader stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShaderStage {
    /// Vertex shader.
    Vertex,
    /// Geometry shader.
    Geometry,
    /// Fragment shader.
    Fragment,
}

impl ShaderStage {
    fn gl_enum(self) -> u32 {
        match self {
            ShaderStage::Vertex => glow::VERTEX_SHADER,
            ShaderStage::Geometry => glow::GEOMETRY_SHADER,
            ShaderStage::Fragment => glow::FRAGMENT_SHADER,
        }
    }

    /// `vertex`, `geometry` or `fragment`.
    pub fn name(self) -> &'static str {
        match self {
            ShaderStage::Vertex => "vertex",
            ShaderStage::Geometry => "geometry",
            ShaderStage::Fragment => "fragment",
        }
    }
}

/// The text prepended to every shader body: `#version 150 core` (the floor),
/// the requested extensions, then one `#define` per entry, then a `#line` so
/// the driver's line numbers refer to the body file. (GLSL before 3.30 numbers
/// the line after `#line N` as N + 1, hence `#line 0`.)
pub fn preamble(extensions: &[&str], defines: &[(String, String)]) -> String {
    let mut text = String::from("#version 150 core\n");
    for ext in extensions {
        text.push_str(&format!("#extension {ext} : enable\n"));
    }
    for (name, value) in defines {
        text.push_str(&format!("#define {name} {value}\n"));
    }
    text.push_str("#line 0\n");
    text
}

/// Pull the line numbers a driver log points at: Mesa writes `0:12(5): error`,
/// NVIDIA `0(12) : error`, AMD `ERROR: 0:12:`.
fn log_line_numbers(log: &str) -> Vec<usize> {
    let mut lines = Vec::new();
    for entry in log.lines() {
        let rest = entry
            .trim_start_matches("ERROR: ")
            .trim_start_matches("WARNING: ");
        let Some(after_file) = rest.strip_prefix("0:").or_else(|| rest.strip_prefix("0(")) else {
            continue;
        };
        let digits: String = after_file
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        if let Ok(n) = digits.parse::<usize>() {
            if !lines.contains(&n) {
                lines.push(n);
            }
        }
    }
    lines
}

/// The body's lines that a log points at, one line of context either side, numbered.
fn excerpt(name: &str, body: &str, log: &str) -> String {
    let source: Vec<&str> = body.lines().collect();
    let mut out = String::new();
    for n in log_line_numbers(log) {
        let first = n.saturating_sub(1).max(1);
        let last = (n + 1).min(source.len());
        for k in first..=last {
            let marker = if k == n { ">" } else { " " };
            if let Some(text) = source.get(k - 1) {
                out.push_str(&format!("{marker} {name}:{k:>4} | {text}\n"));
            }
        }
    }
    out
}

/// A linked program with a uniform-location cache.
#[derive(Debug)]
pub struct Program {
    /// The GL name.
    pub(crate) raw: glow::Program,
    /// Debug label.
    pub label: String,
    uniforms: RefCell<HashMap<String, Option<glow::UniformLocation>>>,
}

/// One stage's source: the file name (for messages) and its body.
pub type StageSource<'a> = (ShaderStage, &'a str, &'a str);

impl Program {
    /// The GL handle, for the host's own calls (binding, attaching);
    /// [`Program::destroy`] frees it.
    pub fn raw(&self) -> glow::Program {
        self.raw
    }

    /// Compile every stage as `preamble + body`, bind fragment outputs to their
    /// colour numbers before linking, and link. Errors carry the stage, the
    /// driver log and the offending body lines.
    pub fn build(
        gl: &glow::Context,
        label: &str,
        preamble: &str,
        stages: &[StageSource<'_>],
        frag_outputs: &[(&str, u32)],
    ) -> Result<Self> {
        let raw = unsafe { gl.create_program() }.map_err(|reason| Error::Create {
            what: format!("program `{label}`"),
            reason,
        })?;
        counters::created(Kind::Program);
        let program = Program {
            raw,
            label: label.to_string(),
            uniforms: RefCell::new(HashMap::new()),
        };
        let mut shaders = Vec::new();
        let mut result = Ok(());
        for &(stage, name, body) in stages {
            match compile(gl, stage, name, preamble, body) {
                Ok(shader) => {
                    unsafe { gl.attach_shader(raw, shader) };
                    shaders.push(shader);
                }
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        if result.is_ok() {
            unsafe {
                for &(output, location) in frag_outputs {
                    gl.bind_frag_data_location(raw, location, output);
                }
                gl.link_program(raw);
                if !gl.get_program_link_status(raw) {
                    result = Err(Error::ProgramLink {
                        name: label.to_string(),
                        log: gl.get_program_info_log(raw),
                    });
                }
            }
        }
        for shader in shaders {
            unsafe {
                gl.detach_shader(raw, shader);
                gl.delete_shader(shader);
            }
            counters::destroyed(Kind::Shader);
        }
        if let Err(e) = result.and_then(|_| check_error(gl, &format!("linking `{label}`"))) {
            program.destroy(gl);
            return Err(e);
        }
        label_object(gl, glow::PROGRAM, raw.0.get(), label);
        Ok(program)
    }

    /// Make it the current program.
    pub fn bind(&self, gl: &glow::Context) {
        unsafe { gl.use_program(Some(self.raw)) };
    }

    /// A uniform's location (cached); `None` if the linker removed or never had it.
    pub fn uniform(&self, gl: &glow::Context, name: &str) -> Option<glow::UniformLocation> {
        if let Some(loc) = self.uniforms.borrow().get(name) {
            return *loc;
        }
        let loc = unsafe { gl.get_uniform_location(self.raw, name) };
        self.uniforms.borrow_mut().insert(name.to_string(), loc);
        loc
    }

    /// Set an `int` or sampler uniform (the program must be bound).
    pub fn set_i32(&self, gl: &glow::Context, name: &str, v: i32) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_1_i32(Some(&loc), v) };
        }
    }
    /// Set a `uint` uniform.
    pub fn set_u32(&self, gl: &glow::Context, name: &str, v: u32) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_1_u32(Some(&loc), v) };
        }
    }
    /// Set a `float` uniform.
    pub fn set_f32(&self, gl: &glow::Context, name: &str, v: f32) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_1_f32(Some(&loc), v) };
        }
    }
    /// Set a `vec2` uniform.
    pub fn set_vec2(&self, gl: &glow::Context, name: &str, v: [f32; 2]) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_2_f32(Some(&loc), v[0], v[1]) };
        }
    }
    /// Set a `vec3` uniform.
    pub fn set_vec3(&self, gl: &glow::Context, name: &str, v: [f32; 3]) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_3_f32(Some(&loc), v[0], v[1], v[2]) };
        }
    }
    /// Set a `vec4` uniform.
    pub fn set_vec4(&self, gl: &glow::Context, name: &str, v: [f32; 4]) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_4_f32(Some(&loc), v[0], v[1], v[2], v[3]) };
        }
    }
    /// Set a `mat4` uniform from a column-major array.
    pub fn set_mat4(&self, gl: &glow::Context, name: &str, m: &[f32; 16]) {
        if let Some(loc) = self.uniform(gl, name) {
            unsafe { gl.uniform_matrix_4_f32_slice(Some(&loc), false, m) };
        }
    }
    /// Set a `vec4[]` uniform array.
    pub fn set_vec4_array(&self, gl: &glow::Context, name: &str, v: &[[f32; 4]]) {
        if let Some(loc) = self.uniform(gl, name) {
            let flat: Vec<f32> = v.iter().flatten().copied().collect();
            unsafe { gl.uniform_4_f32_slice(Some(&loc), &flat) };
        }
    }

    /// Free the program.
    pub fn destroy(self, gl: &glow::Context) {
        unsafe { gl.delete_program(self.raw) };
        counters::destroyed(Kind::Program);
    }
}

fn compile(
    gl: &glow::Context,
    stage: ShaderStage,
    name: &str,
    preamble: &str,
    body: &str,
) -> Result<glow::Shader> {
    let shader = unsafe { gl.create_shader(stage.gl_enum()) }.map_err(|reason| Error::Create {
        what: format!("{} shader `{name}`", stage.name()),
        reason,
    })?;
    counters::created(Kind::Shader);
    let source = format!("{preamble}{body}");
    unsafe {
        gl.shader_source(shader, &source);
        gl.compile_shader(shader);
        if !gl.get_shader_compile_status(shader) {
            let log = gl.get_shader_info_log(shader);
            gl.delete_shader(shader);
            counters::destroyed(Kind::Shader);
            return Err(Error::ShaderCompile {
                stage: stage.name(),
                name: name.to_string(),
                excerpt: excerpt(name, body, &log),
                log: log.trim_end().to_string(),
            });
        }
    }
    Ok(shader)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_driver_line_numbers() {
        assert_eq!(log_line_numbers("0:12(5): error: `x' undeclared"), vec![12]);
        assert_eq!(
            log_line_numbers("0(7) : error C1008: undefined variable"),
            vec![7]
        );
        assert_eq!(log_line_numbers("ERROR: 0:3: 'y' : undeclared"), vec![3]);
        assert!(log_line_numbers("link failed").is_empty());
    }

    #[test]
    fn excerpt_marks_the_line() {
        let body = "void main() {\n  x = 1;\n}\n";
        let text = excerpt("t.frag", body, "0:2(3): error: `x' undeclared");
        assert!(text.contains("> t.frag:   2 |   x = 1;"), "{text}");
        assert!(text.contains("t.frag:   1 | void main() {"));
    }
}
