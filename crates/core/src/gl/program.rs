//! Shader programs: compiled from a file body with a generated preamble.

use super::counters::{self, Kind};
use super::{ShaderSource, check_error, label_object};
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

/// The header [`ShaderSource`] writes: `#version 150 core` (the floor), the
/// requested extensions, one `#define` per entry, then `#line 0`, so that a
/// body appended by hand is numbered from its own line 1 (GLSL before 3.30
/// numbers the line after `#line N` as N + 1). [`Program::build`] takes it
/// as the verbatim header of a [`ShaderSource`].
pub fn preamble(extensions: &[&str], defines: &[(String, String)]) -> String {
    let header = ShaderSource::new()
        .extensions(extensions)
        .defines(defines)
        .header_text();
    format!("{header}#line 0\n")
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

    /// Compile every stage as `preamble + body` (the preamble as the
    /// verbatim header of a one-part [`ShaderSource`]), bind fragment outputs
    /// to their colour numbers before linking, and link. Errors carry the
    /// stage, the driver log and the offending body lines.
    pub fn build(
        gl: &glow::Context,
        label: &str,
        preamble: &str,
        stages: &[StageSource<'_>],
        frag_outputs: &[(&str, u32)],
    ) -> Result<Self> {
        let sources: Vec<(ShaderStage, ShaderSource)> = stages
            .iter()
            .map(|&(stage, name, body)| {
                (stage, ShaderSource::with_header(preamble).part(name, body))
            })
            .collect();
        let refs: Vec<(ShaderStage, &ShaderSource)> =
            sources.iter().map(|(stage, s)| (*stage, s)).collect();
        Self::from_sources(gl, label, &refs, frag_outputs)
    }

    /// Compile every stage from its [`ShaderSource`], bind fragment outputs
    /// to their colour numbers before linking, and link. A compile error
    /// names the stage, carries the driver log, and maps each location the
    /// log names to its part's file and line ([`ShaderSource::explain`]).
    pub fn from_sources(
        gl: &glow::Context,
        label: &str,
        stages: &[(ShaderStage, &ShaderSource)],
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
        for &(stage, source) in stages {
            match compile(gl, stage, source) {
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

    /// Set uniforms that never change (sampler units, constants) once, at
    /// set-up: `set` runs with the program bound, then whatever program was
    /// current before (the host's) is current again.
    pub fn set_at_setup(&self, gl: &glow::Context, set: impl FnOnce(&Program)) {
        let previous = unsafe { gl.get_parameter_i32(glow::CURRENT_PROGRAM) };
        self.bind(gl);
        set(self);
        let previous = u32::try_from(previous)
            .ok()
            .and_then(std::num::NonZeroU32::new)
            .map(glow::NativeProgram);
        unsafe { gl.use_program(previous) };
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

fn compile(gl: &glow::Context, stage: ShaderStage, source: &ShaderSource) -> Result<glow::Shader> {
    let name = source.name();
    let shader = unsafe { gl.create_shader(stage.gl_enum()) }.map_err(|reason| Error::Create {
        what: format!("{} shader `{name}`", stage.name()),
        reason,
    })?;
    counters::created(Kind::Shader);
    unsafe {
        gl.shader_source(shader, &source.text());
        gl.compile_shader(shader);
        if !gl.get_shader_compile_status(shader) {
            let log = gl.get_shader_info_log(shader);
            gl.delete_shader(shader);
            counters::destroyed(Kind::Shader);
            return Err(Error::ShaderCompile {
                stage: stage.name(),
                excerpt: source.explain(&log),
                name,
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
    fn preamble_is_the_builders_header_then_line_zero() {
        assert_eq!(
            preamble(&["GL_ARB_x"], &[("A".into(), "1".into())]),
            "#version 150 core\n#extension GL_ARB_x : enable\n#define A 1\n#line 0\n"
        );
    }
}
