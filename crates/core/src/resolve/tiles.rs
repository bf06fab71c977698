//! Tile classification for the resolve's one-sample pixels
//! ([`super::Schedule::Tiles`]).
//!
//! A uniform pixel (and one outside a selective-AA selection) takes sample 0
//! of everything. On GPUs a branch in one shader skips the slow path for
//! such pixels (the default schedule), but a SIMD software rasteriser such
//! as llvmpipe runs both sides of a branch whenever any lane takes the slow
//! one, and never skips work after a `discard`. This schedule runs three
//! passes instead, so that the slow program is never given the tiles that
//! do not need it (measured on llvmpipe it gains little where slow tiles
//! are few and loses where they are many: README, "What the resolve
//! costs"):
//!
//! 1. **classify** (`resolve.frag` with `PASS_CLASSIFY_TILES`): one fragment
//!    per [`TILE_SIZE`]² tile reads the depth keys of the tile's pixels and
//!    writes 1.0 into an R8 tile mask when any of them needs the slow path;
//! 2. **sample 0** (`resolve.frag` with `PASS_ONE_SAMPLE`) over a full-screen
//!    triangle: every pixel copies sample 0 and reads nothing else (drawing
//!    only the one-sample tiles would cost more: each tile's two triangles
//!    make a rasteriser shade the blocks on their shared diagonal twice);
//! 3. **slow tiles** (`resolve_tiles.vert`): the vertex shader draws only
//!    tiles marked 1, with the ordinary single-pass program (its per-pixel
//!    branch included) over what pass 2 wrote, so every pixel gets exactly
//!    the value the single pass would give it. The other tiles collapse to a
//!    point outside the viewport, so the rasteriser never visits them.

use crate::Result;
use crate::gl::{Attachment, Format, Framebuffer, Texture2d, TextureRef};

/// The resolve tile grid's vertex shader body.
pub const RESOLVE_TILES_VERT: &str = include_str!("../../shaders/resolve_tiles.vert");

/// Tile edge in pixels: small enough that an edge's slow tiles stay close
/// to its slow pixels, large enough that classification is a small pass.
pub const TILE_SIZE: u32 = 8;

/// The R8 tile mask and its framebuffer, sized for one target.
#[derive(Debug)]
pub(crate) struct TileMask {
    texture: Texture2d,
    framebuffer: Framebuffer,
    /// The target size it serves.
    pub(crate) target: (u32, u32),
    /// Tile size it was made for.
    pub(crate) tile_size: u32,
}

impl TileMask {
    pub(crate) fn new(gl: &glow::Context, width: u32, height: u32, tile_size: u32) -> Result<Self> {
        let (tw, th) = (width.div_ceil(tile_size), height.div_ceil(tile_size));
        let texture = Texture2d::new(gl, "resolve tile mask", Format::R8, tw, th)?;
        let framebuffer = match Framebuffer::new(
            gl,
            "resolve tile mask",
            &[(Attachment::Color(0), TextureRef::from(&texture))],
            &[Some(0)],
        ) {
            Ok(f) => f,
            Err(e) => {
                texture.destroy(gl);
                return Err(e);
            }
        };
        Ok(TileMask {
            texture,
            framebuffer,
            target: (width, height),
            tile_size,
        })
    }

    pub(crate) fn framebuffer(&self) -> &Framebuffer {
        &self.framebuffer
    }

    pub(crate) fn texture(&self) -> TextureRef {
        TextureRef::from(&self.texture)
    }

    /// Tiles in the grid.
    pub(crate) fn tiles(&self) -> u32 {
        self.texture.width * self.texture.height
    }

    pub(crate) fn destroy(self, gl: &glow::Context) {
        self.framebuffer.destroy(gl);
        self.texture.destroy(gl);
    }
}
