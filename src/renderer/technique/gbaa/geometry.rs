//! The G-buffer pass of [`AaMode::Gbaa`](crate::renderer::AaMode::Gbaa):
//! `geometry.vert` (its outputs renamed by `#define`s), a geometry stage
//! (`gbaa_geometry.geom`) that hands every fragment its
//! triangle's three screen-space edge lines, and the unchanged model shader
//! `geometry.frag` with its `main` renamed and called from a wrapper
//! (`gbaa_geometry.frag`) that also writes the distance to the nearest edge
//! along x or y and to the triangle's far side into two extra
//! attachments. Geometry shaders are core in OpenGL 3.2, so this works on
//! the floor.

use crate::Result;
use crate::gl::{GlObject, Handle, Program, ShaderSource, ShaderStage, check_error};
use crate::renderer::mesh::{AttribLocations, GpuScene};
use crate::renderer::pass::geometry::model_wrapped;
use crate::renderer::pass::geometry::{GEOMETRY_VERT, GeometryTarget, ModelDraw, draw_models};
use crate::renderer::pass::slots::GBufferSlots;
use glam::{DMat4, Mat4};

/// The geometry stage's body.
pub(crate) const GBAA_GEOMETRY_GEOM: &str = include_str!("gbaa_geometry.geom");
/// The fragment wrapper's body (compiled after `geometry.frag` with `main` renamed).
pub(crate) const GBAA_GEOMETRY_FRAG: &str = include_str!("gbaa_geometry.frag");

/// The value of an edge channel that holds no edge: farther than any
/// distance the pass writes ([`REACH`]), so the post pass never blends by it.
pub(crate) const NO_EDGE: f32 = 4.0;
/// Edge distances are capped here (pixels); only those under 1 matter.
pub(crate) const REACH: f32 = 2.0;
/// Triangles smaller than this many square pixels write no edges: their
/// edges do not separate a pixel's colour from its neighbours'. (Chosen
/// from 0, 0.5, 1, 2 and 4 by FLIP against the supersampled reference on
/// `builtin:greebles` and `builtin:thin` at 96x54 to 640x360; with 0,
/// pixel-sized greebles blend into whatever surrounds them.)
pub(crate) const MIN_AREA: f32 = 1.0;

/// The defines the G-buffer pass and the post pass share.
pub(crate) fn edge_defines() -> Vec<(String, String)> {
    vec![
        ("GBAA_NO_EDGE".into(), format!("{NO_EDGE:.1}")),
        ("GBAA_REACH".into(), format!("{REACH:.1}")),
        ("GBAA_MIN_AREA".into(), format!("{MIN_AREA:.3}")),
    ]
}

/// The model program with the edge outputs.
#[derive(Debug)]
pub(crate) struct GbaaGeometryPass {
    program: Program,
    slots: GBufferSlots,
    locations: AttribLocations,
}

impl GbaaGeometryPass {
    /// Build the program: the model outputs at `slots` (with the defines
    /// that drop those the layout lacks), `o_edge` on draw buffer
    /// `edge_slot` and `o_edge_far` on `edge_slot + 1`.
    pub(crate) fn new(gl: &glow::Context, slots: GBufferSlots, edge_slot: u32) -> Result<Self> {
        let mut outputs = slots.outputs();
        outputs.extend([("o_edge", edge_slot), ("o_edge_far", edge_slot + 1)]);
        let mut defines = edge_defines();
        defines.extend(slots.defines());
        let header = ShaderSource::new().defines(&defines);
        // geometry.vert's outputs renamed to the geometry stage's inputs.
        let vertex = header
            .clone()
            .define("v_position", "vert_position")
            .define("v_normal", "vert_normal")
            .define("v_uv", "vert_uv")
            .part("geometry.vert", GEOMETRY_VERT);
        let geometry = header
            .clone()
            .part("gbaa_geometry.geom", GBAA_GEOMETRY_GEOM);
        let fragment = model_wrapped(header, &[("gbaa_geometry.frag", GBAA_GEOMETRY_FRAG)]);
        let program = Program::from_sources(
            gl,
            "geometry + gbaa edges",
            &[
                (ShaderStage::Vertex, &vertex),
                (ShaderStage::Geometry, &geometry),
                (ShaderStage::Fragment, &fragment),
            ],
            &outputs,
        )?;
        let locations = AttribLocations::of(gl, &program);
        Ok(GbaaGeometryPass {
            program,
            slots,
            locations,
        })
    }

    /// The attachment numbers the model outputs are bound to.
    pub(crate) fn slots(&self) -> GBufferSlots {
        self.slots
    }

    /// Draw the scene's opaque and alpha-tested objects into `target` with
    /// the same state as [`GeometryPass::draw`](crate::renderer::pass::geometry::GeometryPass::draw)
    /// (depth test `depth_func`, depth written, back faces culled unless
    /// double-sided); the framebuffer's draw buffers must map the edge outputs.
    pub(crate) fn draw(
        &self,
        gl: &glow::Context,
        target: GeometryTarget,
        scene: &GpuScene,
        view: &DMat4,
        projection: &Mat4,
        depth_func: u32,
    ) -> Result<()> {
        // The geometry stage needs the viewport to measure edges in pixels.
        self.program.bind(gl);
        self.program.set_vec2(
            gl,
            "u_viewport",
            [target.width as f32, target.height as f32],
        );
        draw_models(
            gl,
            &self.program,
            self.locations,
            target,
            ModelDraw {
                scene,
                view,
                projection,
                depth_func,
            },
        );
        Ok(check_error(gl, "the G-buffer pass of gbaa")?)
    }

    /// Free the program.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.program.destroy(gl);
    }
}

impl GlObject for GbaaGeometryPass {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.program.handles(out);
    }
}
