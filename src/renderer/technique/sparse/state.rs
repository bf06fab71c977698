//! Method `sparse` ([`AaMode::Sparse`]): the multisampled G-buffer without
//! its redundancy, as per-pixel linked lists of G-buffer blocks in shader
//! storage buffers. The design, the frame, selective anti-aliasing and the
//! requirements are documented on [`SparseOptions`] (public); the layout of
//! heads and blocks in `sparse.frag`.

pub(crate) use super::geometry::BuildParams;
use super::geometry::SparseBuildPasses;
pub(crate) use super::lighting::LightParams;
use super::lighting::SparseLightingPass;
use super::options::SparseStats;
use super::shader::EXTENSIONS;
use super::targets::SparseMemory;
use super::targets::{SparseTargets, TargetKey, prepass_format};
use crate::gl::{Capabilities, VertexArray};
use crate::renderer::mesh::GpuScene;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::pass::lighting::LightBatch;
use crate::renderer::pass::shared::LightTarget;
use crate::{Error, Result};
use glow::HasContext;
use std::cell::Cell;
use std::collections::HashSet;

/// The value [`Sparse::read_mask`](super::Sparse::read_mask) gives a pixel that fell back
/// to one sample because the pool ran out.
pub const MASK_OVERFLOW: u8 = 255;
/// The value [`Sparse::read_mask`](super::Sparse::read_mask) gives a pixel that shows one
/// sample because a visible fragment is not to be anti-aliased (its
/// object's flag, or beyond the depth limit).
pub const MASK_SINGLE: u8 = 128;

/// Flag bits of a pixel's head (`sparse.frag`).
const FLAG_OVERFLOW: u32 = 2;
const FLAG_SINGLE: u32 = 4;

/// The extensions of [`EXTENSIONS`] that `available` lacks.
pub(crate) fn missing_extensions(available: &HashSet<String>) -> Vec<&'static str> {
    EXTENSIONS
        .iter()
        .copied()
        .filter(|e| !available.contains(*e))
        .collect()
}

/// [`Error::Unsupported`](deferred_msaa::Error::Unsupported) when `aa` is [`AaMode::Sparse`] and the context
/// lacks what it needs; `Ok` otherwise.
pub(crate) fn check_support(gl: &glow::Context, aa: &AaMode) -> Result<()> {
    if !matches!(aa, AaMode::Sparse(_)) {
        return Ok(());
    }
    let missing = missing_extensions(gl.supported_extensions());
    if missing.is_empty() {
        return Ok(());
    }
    let caps = Capabilities::query(gl);
    Err(deferred_msaa::Error::Unsupported {
        feature: "method `sparse` (per-pixel linked lists of G-buffer blocks)".into(),
        requires: format!(
            "{} (the shader storage buffers and atomic counters of OpenGL 4.3, and post-depth \
             coverage, reached from GLSL 1.50 through extensions)",
            missing.join(" and ")
        ),
        found: format!(
            "OpenGL {}.{}, {}{}",
            caps.version.0,
            caps.version.1,
            caps.renderer,
            if caps.storage_buffers {
                ""
            } else {
                ", no shader storage buffers"
            }
        ),
    }
    .into())
}

/// The programs and targets of [`AaMode::Sparse`]; the programs are built
/// when the method is first used and kept, the targets follow the options
/// and are freed when another method is chosen.
#[derive(Debug, Default)]
pub(crate) struct SparseState {
    build: Option<SparseBuildPasses>,
    lighting: Option<SparseLightingPass>,
    targets: Option<SparseTargets>,
    /// A frame has built the lists in the current targets.
    rendered: Cell<bool>,
}

impl SparseState {
    /// Bring programs and targets in line with `options`: for
    /// [`AaMode::Sparse`], build what is missing and (re)allocate the
    /// targets unless they match (new ones before the old are freed);
    /// otherwise free the targets.
    pub(crate) fn prepare(&mut self, gl: &glow::Context, options: &RenderOptions) -> Result<()> {
        let AaMode::Sparse(sparse) = options.aa else {
            self.release(gl);
            return Ok(());
        };
        check_support(gl, &options.aa)?;
        sparse.validate(options.samples)?;
        if self.build.is_none() {
            self.build = Some(SparseBuildPasses::new(gl)?);
        }
        if self.lighting.is_none() {
            self.lighting = Some(SparseLightingPass::new(gl)?);
        }
        let key = TargetKey {
            width: options.width,
            height: options.height,
            samples: options.samples,
            format: prepass_format(options.layout.depth),
            pool_capacity: sparse.pool_capacity(options.width, options.height),
        };
        if self.targets.as_ref().map(SparseTargets::key) != Some(key) {
            let targets = SparseTargets::new(gl, key)?;
            if let Some(old) = self.targets.replace(targets) {
                old.destroy(gl);
            }
            self.rendered.set(false);
        }
        Ok(())
    }

    /// The pre-pass's real sample count, once allocated.
    pub(crate) fn samples(&self) -> Option<u32> {
        self.targets.as_ref().map(SparseTargets::samples)
    }

    /// What the targets take, once allocated.
    pub(crate) fn memory(&self) -> Option<SparseMemory> {
        self.targets.as_ref().map(SparseTargets::memory)
    }

    fn parts(&self) -> Result<(&SparseBuildPasses, &SparseLightingPass, &SparseTargets)> {
        match (&self.build, &self.lighting, &self.targets) {
            (Some(b), Some(l), Some(t)) => Ok((b, l, t)),
            _ => Err(Error::invalid(
                "method `sparse` has no programs or targets (not prepared)",
            )),
        }
    }

    /// Steps 1–3 of the frame: the depth pre-pass, the set-up pass into
    /// the G-buffer's framebuffer `gbuffer_fbo`, and the G-buffer pass.
    pub(crate) fn build_lists(
        &self,
        gl: &glow::Context,
        scene: &GpuScene,
        gbuffer_fbo: glow::Framebuffer,
        vao: &VertexArray,
        params: &BuildParams<'_>,
    ) -> Result<()> {
        let (build, _, targets) = self.parts()?;
        build.draw_depth(gl, targets, scene, params)?;
        build.draw_setup(gl, targets, gbuffer_fbo, vao)?;
        let result = build.draw_blocks(gl, targets, scene, params);
        SparseTargets::unbind_buffers(gl);
        self.rendered.set(result.is_ok());
        result
    }

    /// Step 4: light the lists into `target`.
    pub(crate) fn light(
        &self,
        gl: &glow::Context,
        target: LightTarget,
        vao: &VertexArray,
        batches: &[LightBatch],
        params: &LightParams<'_>,
    ) -> Result<()> {
        let (_, lighting, targets) = self.parts()?;
        lighting.draw(gl, target, vao, targets, batches, params)
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        if let Some(p) = self.build {
            p.destroy(gl);
        }
        if let Some(p) = self.lighting {
            p.destroy(gl);
        }
        if let Some(t) = self.targets {
            t.destroy(gl);
        }
    }
}

impl SparseState {
    /// Free the targets (another method was chosen); the programs stay.
    pub(crate) fn release(&mut self, gl: &glow::Context) {
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
        self.rendered.set(false);
    }

    /// What the last frame's G-buffer pass counted, read back from the
    /// atomic counters (this waits for the frame); `None` before the first
    /// frame.
    pub(crate) fn stats(&self, gl: &glow::Context) -> Result<Option<SparseStats>> {
        if !self.rendered.get() {
            return Ok(None);
        }
        let Some(targets) = self.targets.as_ref() else {
            return Ok(None);
        };
        let (pool_requested, overflow_pixels) = targets.read_counters(gl)?;
        Ok(Some(SparseStats {
            pool_capacity: targets.pool_capacity,
            pool_requested,
            overflow_pixels,
        }))
    }

    /// The last frame's one-sample pixels, read back from the heads (see
    /// [`super::technique::Sparse::read_mask`]); `None` before the first frame.
    pub(crate) fn read_mask(&self, gl: &glow::Context) -> Result<Option<image::GrayImage>> {
        if !self.rendered.get() {
            return Ok(None);
        }
        let Some(targets) = self.targets.as_ref() else {
            return Ok(None);
        };
        let flags = targets.read_flags(gl)?;
        let (w, h) = (targets.width as usize, targets.height as usize);
        if flags.len() != w * h {
            return Err(Error::invalid(format!(
                "the sparse heads hold {} pixels, not {w}x{h}",
                flags.len()
            )));
        }
        // The heads run bottom-up, as gl_FragCoord counts rows.
        let pixels: Vec<u8> = flags
            .chunks_exact(w.max(1))
            .rev()
            .flatten()
            .map(|&f| {
                if f & FLAG_OVERFLOW != 0 {
                    MASK_OVERFLOW
                } else if f & FLAG_SINGLE != 0 {
                    MASK_SINGLE
                } else {
                    0
                }
            })
            .collect();
        image::GrayImage::from_raw(w as u32, h as u32, pixels)
            .map(Some)
            .ok_or_else(|| Error::invalid("the sparse mask does not hold the image"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_extensions_are_named() {
        let all: HashSet<String> = EXTENSIONS.iter().map(|e| e.to_string()).collect();
        assert!(missing_extensions(&all).is_empty());
        let mut some = all.clone();
        some.remove("GL_ARB_post_depth_coverage");
        some.remove("GL_ARB_shader_storage_buffer_object");
        assert_eq!(
            missing_extensions(&some),
            [
                "GL_ARB_shader_storage_buffer_object",
                "GL_ARB_post_depth_coverage"
            ]
        );
    }
}
