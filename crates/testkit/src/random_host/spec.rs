//! A host as plain data ([`HostSpec`]): its attachments, draw buffers,
//! depth, size and retrofit options, and how a seed draws one.

use super::formats::*;
use crate::Rng;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::retrofit::PositionSpace;
use deferred_msaa::{
    ColorAttachment, FirstLayerRestore, LayerMix, NormalAttachment, RetrofitOptions,
};
use glow::HasContext;

/// What image an attachment is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Level 0 of a `GL_TEXTURE_2D`.
    Texture,
    /// A single-sample renderbuffer.
    Renderbuffer,
    /// Layer `layer` of a `GL_TEXTURE_2D_ARRAY` of `layers` layers,
    /// attached with `glFramebufferTextureLayer`.
    Layer {
        /// Layers of the array.
        layers: u32,
        /// The attached one.
        layer: u32,
    },
    /// Level 1 of a texture twice the size (what the retrofit refuses).
    MipLevel1,
    /// The `+X` face of a cube map (square sizes only; refused).
    CubeFace,
    /// A `GL_TEXTURE_RECTANGLE` (refused).
    Rectangle,
    /// A layer of a `GL_TEXTURE_3D` (refused).
    Texture3dLayer,
    /// A whole array texture of one layer, attached layered with
    /// `glFramebufferTexture` (refused; complete only when every
    /// attachment is).
    Layered,
    /// A 4x multisampled renderbuffer (refused; complete only when every
    /// attachment is).
    MultisampledRenderbuffer,
    /// A 4x `GL_TEXTURE_2D_MULTISAMPLE` (refused likewise).
    MultisampledTexture,
}

/// One colour attachment of a random host.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorSpec {
    /// Its attachment point number (`GL_COLOR_ATTACHMENTn`).
    pub point: u32,
    /// The internal format the host asks for.
    pub format: HostFormat,
    /// The image kind.
    pub storage: Storage,
    /// A size other than the host's (what the retrofit refuses), or `None`.
    pub size: Option<(u32, u32)>,
}

/// Where the host's depth-stencil image is attached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthPoint {
    /// `GL_DEPTH_ATTACHMENT` (a depth-stencil format there has its stencil
    /// outside the framebuffer).
    Depth,
    /// `GL_DEPTH_STENCIL_ATTACHMENT`.
    DepthStencil,
    /// The same image at `GL_DEPTH_ATTACHMENT` and `GL_STENCIL_ATTACHMENT`,
    /// in two calls (the GL 3.0 habit).
    Both,
    /// `GL_STENCIL_ATTACHMENT` alone (a stencil-only host).
    Stencil,
}

/// The depth (or stencil) attachment of a random host.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthSpec {
    /// The internal format.
    pub format: HostFormat,
    /// The image kind.
    pub storage: Storage,
    /// Where it is attached.
    pub point: DepthPoint,
}

/// A random host G-buffer and the options its integrator passes.
#[derive(Clone, Debug, PartialEq)]
pub struct HostSpec {
    /// The seed it was drawn from (0 for a case written out by hand).
    pub seed: u64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The size the host resizes to before `refresh`.
    pub resized: (u32, u32),
    /// Colour attachments.
    pub colors: Vec<ColorSpec>,
    /// `glDrawBuffers`' list: attachment numbers, `None` for `GL_NONE`.
    pub draw_buffers: Vec<Option<u32>>,
    /// The depth attachment, or none.
    pub depth: Option<DepthSpec>,
    /// The options `MsaaRetrofit::new` is given.
    pub options: RetrofitOptions,
    /// The options `set_options` is given afterwards.
    pub other_options: RetrofitOptions,
}

/// The driver's limits the generator draws within.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// `GL_MAX_COLOR_ATTACHMENTS`.
    pub color_attachments: u32,
    /// `GL_MAX_DRAW_BUFFERS`.
    pub draw_buffers: u32,
}

impl Limits {
    /// Read them from the context.
    pub fn of(gl: &glow::Context) -> Limits {
        unsafe {
            Limits {
                color_attachments: gl
                    .get_parameter_i32(glow::MAX_COLOR_ATTACHMENTS)
                    .clamp(1, 32) as u32,
                draw_buffers: gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(1, 32) as u32,
            }
        }
    }
}

pub(super) fn chance(rng: &mut Rng, percent: u32) -> bool {
    rng.below(100) < percent
}

pub(super) fn pick<T: Clone>(rng: &mut Rng, items: &[T]) -> T {
    items[rng.below(items.len() as u32) as usize].clone()
}

pub(super) fn storage(rng: &mut Rng) -> Storage {
    match rng.below(100) {
        0..=44 => Storage::Texture,
        45..=74 => Storage::Renderbuffer,
        75..=95 => {
            let layers = 1 + rng.below(4);
            Storage::Layer {
                layers,
                layer: rng.below(layers),
            }
        }
        96 => Storage::MipLevel1,
        97 => Storage::CubeFace,
        98 => Storage::Rectangle,
        _ => Storage::Texture3dLayer,
    }
}

/// Random options for a host with colour points `points` (of `limits`).
pub fn random_options(rng: &mut Rng, points: &[u32], limits: Limits) -> RetrofitOptions {
    let mut o = RetrofitOptions {
        samples: pick(rng, &[4, 4, 4, 4, 4, 2, 1, 8]),
        ..RetrofitOptions::default()
    };
    // A point the host has, or now and then any point (which may be empty).
    let point = |rng: &mut Rng| {
        if points.is_empty() || chance(rng, 4) {
            rng.below(limits.color_attachments)
        } else {
            pick(rng, points)
        }
    };
    for _ in 0..rng.below(3) {
        let p = point(rng);
        let rule = pick(
            rng,
            &[
                ResolveRule::Blend,
                ResolveRule::BlendNormal,
                ResolveRule::BlendHdr,
                ResolveRule::Select,
            ],
        );
        if !o.rules.iter().any(|(n, _)| n.0 == p) {
            o.rules.push((ColorAttachment(p), rule));
        }
    }
    if chance(rng, 30) {
        o.position_attachment = Some(ColorAttachment(point(rng)));
        o.position_space = if chance(rng, 50) {
            PositionSpace::View
        } else {
            PositionSpace::World
        };
    }
    if chance(rng, 30) {
        o.normal_attachment = Some(NormalAttachment {
            attachment: ColorAttachment(point(rng)),
            encoding: pick(
                rng,
                &[
                    NormalEncoding::Xyz,
                    NormalEncoding::Unorm,
                    NormalEncoding::Octahedral,
                    NormalEncoding::OctahedralUnorm,
                ],
            ),
        });
    }
    o.resolve.method = pick(rng, ResolveMethod::all());
    o.resolve.window = pick(rng, Window::all());
    o.resolve.fast_path = chance(rng, 70);
    o.resolve.layers = if chance(rng, 30) { 2 } else { 1 };
    o.stencil = pick(
        rng,
        &[
            StencilCopy::Auto,
            StencilCopy::Auto,
            StencilCopy::Export,
            StencilCopy::BitPasses,
            StencilCopy::Blit,
        ],
    );
    o.layer_mix = pick(
        rng,
        &[LayerMix::Auto, LayerMix::Linear, LayerMix::Tonemapped],
    );
    // One draw, as the flag this was took: the same seeds make the same hosts.
    o.restore_first_layer = match rng.below(100) {
        0..=79 => FirstLayerRestore::Everything,
        80..=89 => FirstLayerRestore::DepthAndStencil,
        _ => FirstLayerRestore::Nothing,
    };
    match rng.below(100) {
        0..=3 => o.memory_budget = Some(deferred_msaa::gbuffer::MemoryBudget::limit(64).strict()),
        4..=7 => o.memory_budget = Some(deferred_msaa::gbuffer::MemoryBudget::limit(4096)),
        _ => {}
    }
    o
}

pub(super) fn size(rng: &mut Rng) -> (u32, u32) {
    match rng.below(100) {
        0..=9 => (1 + rng.below(3), 1 + rng.below(3)),
        10..=89 => (4 + rng.below(45), 4 + rng.below(37)),
        _ => (64 + rng.below(254), 16 + rng.below(76)),
    }
}

impl HostSpec {
    /// The host of `seed`, within `limits`.
    pub fn generate(seed: u64, limits: Limits) -> HostSpec {
        let mut rng = Rng::new(seed);
        let (width, height) = size(&mut rng);
        let resized = size(&mut rng);
        // Hosts that must be refused whole: every attachment multisampled,
        // or every attachment layered.
        let whole = match rng.below(100) {
            0 => Some(Storage::MultisampledRenderbuffer),
            1 => Some(Storage::MultisampledTexture),
            2 => Some(Storage::Layered),
            _ => None,
        };
        let count = match rng.below(100) {
            0..=1 => 0,
            2..=11 => limits.color_attachments,
            _ => 1 + rng.below(limits.color_attachments.min(6)),
        };
        let mut free: Vec<u32> = (0..limits.color_attachments).collect();
        let mut colors = Vec::new();
        for _ in 0..count {
            // Mostly the low points in order, as hosts number them; now and
            // then any free point.
            let i = if chance(&mut rng, 60) {
                0
            } else {
                rng.below(free.len() as u32) as usize
            };
            let point = free.remove(i);
            let mut s = whole.unwrap_or_else(|| storage(&mut rng));
            if s == Storage::CubeFace && width != height {
                s = Storage::Texture;
            }
            let size = chance(&mut rng, 2).then(|| (width + 1, height));
            // Mostly formats the crate knows (and the unsized ones), so that
            // most hosts get as far as the resolve; now and then any.
            let format = if chance(&mut rng, 85) {
                let known: Vec<HostFormat> = COLOR_FORMATS
                    .iter()
                    .copied()
                    .filter(|f| {
                        f.pixel == f.internal
                            || deferred_msaa::gl::Format::from_internal_format(f.internal).is_some()
                    })
                    .collect();
                pick(&mut rng, &known)
            } else {
                pick(&mut rng, COLOR_FORMATS)
            };
            colors.push(ColorSpec {
                point,
                format,
                storage: s,
                size,
            });
        }
        colors.sort_by_key(|c| c.point);
        // The draw-buffer list: the attachments in some order with GL_NONE
        // gaps; now and then one left out (undrawn).
        let mut listed: Vec<u32> = colors
            .iter()
            .map(|c| c.point)
            .filter(|_| !chance(&mut rng, 10))
            .collect();
        if !chance(&mut rng, 60) {
            for i in (1..listed.len()).rev() {
                let j = rng.below(i as u32 + 1) as usize;
                listed.swap(i, j);
            }
        }
        let mut draw_buffers: Vec<Option<u32>> = Vec::new();
        for p in listed {
            while chance(&mut rng, 20) && (draw_buffers.len() as u32) < limits.draw_buffers - 1 {
                draw_buffers.push(None);
            }
            if (draw_buffers.len() as u32) < limits.draw_buffers {
                draw_buffers.push(Some(p));
            }
        }
        if draw_buffers.is_empty() {
            draw_buffers.push(None);
        }
        let depth = match rng.below(100) {
            0..=3 => None,
            4..=5 => Some(DepthSpec {
                format: STENCIL_ONLY,
                storage: Storage::Renderbuffer,
                point: DepthPoint::Stencil,
            }),
            _ => {
                let format = pick(&mut rng, DEPTH_FORMATS);
                let mut storage = whole.unwrap_or_else(|| storage(&mut rng));
                if storage == Storage::Texture3dLayer
                    || storage == Storage::Rectangle && format.has_stencil()
                    || storage == Storage::CubeFace && width != height
                {
                    storage = Storage::Texture;
                }
                let point = if !format.has_stencil() {
                    DepthPoint::Depth
                } else {
                    match rng.below(10) {
                        0..=5 => DepthPoint::DepthStencil,
                        6..=7 => DepthPoint::Both,
                        _ => DepthPoint::Depth,
                    }
                };
                Some(DepthSpec {
                    format,
                    storage,
                    point,
                })
            }
        };
        let points: Vec<u32> = colors.iter().map(|c| c.point).collect();
        let options = random_options(&mut rng, &points, limits);
        let other_options = random_options(&mut rng, &points, limits);
        HostSpec {
            seed,
            width,
            height,
            resized,
            colors,
            draw_buffers,
            depth,
            options,
            other_options,
        }
    }

    /// The colour attachment at point `n`.
    pub fn color(&self, n: u32) -> Option<&ColorSpec> {
        self.colors.iter().find(|c| c.point == n)
    }

    /// Whether the host's framebuffer holds a stencil plane.
    pub fn has_stencil(&self) -> bool {
        self.depth
            .as_ref()
            .is_some_and(|d| d.format.has_stencil() && d.point != DepthPoint::Depth)
    }

    /// The spec written out as the Rust a regression case states it in.
    pub fn describe(&self) -> String {
        format!("{self:#?}")
    }
}
