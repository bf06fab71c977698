//! Method `gbaa` ([`AaMode::Gbaa`]): no multisampling; the G-buffer pass
//! also writes two edge buffers (`gbaa_geometry.geom`, wrapping
//! `geometry.frag` in `gbaa_geometry.frag`), the tonemap writes an sRGB
//! texture, and a post pass (`gbaa.frag`) blends across the edges into the
//! LDR image before FXAA.

mod edge_blend;
mod geometry;

use super::contract::{FrameParts, GBufferTarget, GeometryStep, Setup, Technique, TechniqueState};
use crate::Result;
use crate::gl::{GpuTimer, TextureRef, VertexArray};
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::targets::{ColorTarget, Targets};
use crate::renderer::timing::timed;
use edge_blend::{GbaaPasses, GbaaTargets, edge_bytes};
use std::any::Any;

/// Geometry-buffer anti-aliasing ([`AaMode::Gbaa`]), as
/// [`Renderer::technique`](crate::renderer::Renderer::technique) lends it:
/// its edge buffers and what they add.
#[derive(Debug, Default)]
pub struct Gbaa {
    /// The programs, built when the method is first used and kept.
    passes: Option<GbaaPasses>,
    /// The edge buffers and the sRGB image, allocated by the first frame
    /// after a change of options (they refer to the G-buffer's textures).
    targets: Option<GbaaTargets>,
    /// The full-screen triangle of the edges view, made with the targets.
    fullscreen: Option<VertexArray>,
    /// The image size of the options last prepared for.
    size: (u32, u32),
}

impl TechniqueState for Gbaa {}
impl super::contract::sealed::Sealed for Gbaa {}

impl Gbaa {
    /// The programs and targets, once a frame has prepared them.
    fn parts(&self) -> Option<(&GbaaPasses, &GbaaTargets)> {
        Some((self.passes.as_ref()?, self.targets.as_ref()?))
    }

    /// The edge buffers as the last frame wrote them: `RG16F`, the signed
    /// distance in pixels from each pixel centre to its triangle's nearest
    /// edge along x (`.r`) or y (`.g`), the other channel (and both where
    /// nothing was drawn) 4.0, meaning no edge; and `R16F`, the distance to
    /// the triangle's boundary the opposite way along the same axis.
    /// Distances are capped at 2 pixels. `None` before the first frame
    /// after [`Renderer::set_options`](crate::renderer::Renderer::set_options).
    pub fn edge_textures(&self) -> Option<(TextureRef, TextureRef)> {
        self.targets
            .as_ref()
            .map(|g| (TextureRef::from(&g.edge), TextureRef::from(&g.far)))
    }

    /// The last frame's edges as the post pass sees them (`render --view
    /// edges`), row 0 at the top: red is the share of the pixel taken from
    /// its left or right neighbour, green from the one above or below, blue
    /// from the second neighbour of a pixel that a triangle thinner than a
    /// pixel crosses (each doubled: a full half pixel shows as 255); black
    /// pixels are left as they are. `None` before the first frame after
    /// [`Renderer::set_options`](crate::renderer::Renderer::set_options).
    pub fn read_edges(&self, gl: &glow::Context) -> Result<Option<image::RgbaImage>> {
        match (self.parts(), &self.fullscreen) {
            (Some((p, g)), Some(vao)) => g.read_edges_view(gl, p, vao).map(Some),
            _ => Ok(None),
        }
    }

    /// The bytes the edge buffers add to the G-buffer at the current size.
    pub fn edge_bytes(&self) -> u64 {
        edge_bytes(self.size.0, self.size.1)
    }
}

impl Technique for Gbaa {
    /// Programs and targets both wait for a frame: the targets refer to the
    /// G-buffer's textures.
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        self.size = (setup.options.width, setup.options.height);
        let Some(frame) = frame else {
            return Ok(());
        };
        GbaaPasses::prepare(&mut self.passes, gl, setup.slots, setup.colors)?;
        if self.fullscreen.is_none() {
            self.fullscreen = Some(VertexArray::new(gl, "gbaa edges view triangle")?);
        }
        if self.targets.is_none() {
            self.targets = Some(GbaaTargets::new(gl, frame.gbuffer)?);
        }
        Ok(())
    }

    fn options_changed(&mut self, gl: &glow::Context, _active: bool) {
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
    }

    /// The G-buffer plus its edge buffers.
    fn geometry_target(&self, frame: &FrameParts<'_>) -> GBufferTarget {
        match self.parts() {
            Some((_, g)) => GBufferTarget {
                fbo: g.fbo.raw(),
                draw_buffers: g.draw_buffers.clone(),
            },
            None => GBufferTarget::of_frame(frame),
        }
    }

    fn clear_outputs(&self, gl: &glow::Context) {
        if let Some((_, g)) = self.parts() {
            g.clear_edges(gl);
        }
    }

    /// The model shaders through the edge-measuring geometry stage.
    fn draw_gbuffer(&self, gl: &glow::Context, step: &GeometryStep<'_>) -> Result<()> {
        step.copy_background(gl)?;
        let Some((p, _)) = self.parts() else {
            return step.draw_models(gl, step.model);
        };
        p.geometry().draw(
            gl,
            step.target,
            step.scene,
            step.view,
            step.projection,
            step.nearer_func,
        )
    }

    /// Its sRGB texture, which the post pass reads.
    fn tonemap_target<'a>(&'a self, targets: &'a Targets) -> &'a ColorTarget {
        self.parts().map_or(&targets.ldr, |(_, g)| &g.tonemapped)
    }

    /// Blend across the edges into the LDR image (where FXAA, if on, finds it).
    fn post(
        &mut self,
        gl: &glow::Context,
        targets: &Targets,
        fullscreen: &VertexArray,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        match self.parts() {
            Some((p, g)) => timed(gl, timer, || {
                p.draw_post(gl, &targets.ldr, fullscreen, g, false)
            }),
            None => Ok(0.0),
        }
    }

    /// The edge buffers.
    fn memory(&self, options: &RenderOptions) -> u64 {
        edge_bytes(options.width, options.height)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, gl: &glow::Context) {
        if let Some(t) = self.targets {
            t.destroy(gl);
        }
        if let Some(p) = self.passes {
            p.destroy(gl);
        }
        if let Some(v) = self.fullscreen {
            v.destroy(gl);
        }
    }
}

/// What is known of `gbaa` before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn methods(&self) -> &'static [&'static str] {
        &["gbaa"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        *aa == AaMode::Gbaa
    }

    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        super::kind::no_options(method, options, spec)?;
        Ok(AaMode::Gbaa)
    }

    fn adds_geometry(&self) -> bool {
        true
    }

    fn post_passes(&self) -> Vec<Pass> {
        vec![Pass::GbaaPost]
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(Gbaa::default())
    }
}
