//! Random host G-buffers: the layouts engines we have not seen could build,
//! drawn from a seed ([`HostSpec::generate`]) and built with raw GL calls
//! the way a host writes them ([`RandomHost::build`]).
//!
//! A [`HostSpec`] is plain data: the colour attachments (point, internal
//! format as the host asks for it, sized or unsized, and the image kind:
//! a 2D texture, a renderbuffer, a layer of an array texture, and rarely
//! what the retrofit must refuse), the draw-buffer list with `GL_NONE`
//! gaps, the depth (every depth and depth-stencil format, as a texture,
//! a renderbuffer or a layer, or missing), the size, and the retrofit
//! options the host's integrator would pass (position and normal
//! attachments, rules, layers, stencil copy, budget). The property test
//! shrinks it by editing it and building again, so everything a case is
//! made of is written out in it.

use crate::Rng;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::retrofit::PositionSpace;
use deferred_msaa::{
    ColorAttachment, FirstLayerRestore, LayerMix, NormalAttachment, RetrofitOptions,
};
use glow::HasContext;

/// An internal format a host may ask for: its enum, its name, and the
/// pixel format and type it allocates texture storage with.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct HostFormat {
    /// The internal format enum as passed to `glTexImage2D` /
    /// `glRenderbufferStorage`.
    pub internal: u32,
    /// Its GL name, e.g. `GL_RGBA` or `GL_R11F_G11F_B10F`.
    pub name: &'static str,
    /// The pixel format of the (empty) upload.
    pub pixel: u32,
    /// The pixel type of the (empty) upload.
    pub ty: u32,
}

const fn f(internal: u32, name: &'static str, pixel: u32, ty: u32) -> HostFormat {
    HostFormat {
        internal,
        name,
        pixel,
        ty,
    }
}

/// Every colour internal format GL 3.2–4.5 defines that an engine could
/// attach: the unsized base formats with the types tutorials pass, the
/// sized normalised, snorm, unorm16, float, packed, sRGB and integer
/// ones. Some are not required to be colour-renderable (the snorm and
/// three-channel ones, `GL_RGB9_E5`, the `RGB*I` family): a driver may
/// refuse them, and such a host is counted as incomplete, not retrofitted.
pub const COLOR_FORMATS: &[HostFormat] = &[
    f(glow::RGBA, "GL_RGBA", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGBA, "GL_RGBA", glow::RGBA, glow::FLOAT),
    f(glow::RGB, "GL_RGB", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB, "GL_RGB", glow::RGB, glow::FLOAT),
    f(glow::RG, "GL_RG", glow::RG, glow::UNSIGNED_BYTE),
    f(glow::RED, "GL_RED", glow::RED, glow::UNSIGNED_BYTE),
    f(glow::R8, "GL_R8", glow::RED, glow::UNSIGNED_BYTE),
    f(glow::RG8, "GL_RG8", glow::RG, glow::UNSIGNED_BYTE),
    f(glow::RGB8, "GL_RGB8", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGBA8, "GL_RGBA8", glow::RGBA, glow::UNSIGNED_BYTE),
    f(
        glow::R3_G3_B2,
        "GL_R3_G3_B2",
        glow::RGB,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGB4, "GL_RGB4", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB5, "GL_RGB5", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB565, "GL_RGB565", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB10, "GL_RGB10", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGB12, "GL_RGB12", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGBA2, "GL_RGBA2", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGBA4, "GL_RGBA4", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGB5_A1, "GL_RGB5_A1", glow::RGBA, glow::UNSIGNED_BYTE),
    f(
        glow::RGB10_A2,
        "GL_RGB10_A2",
        glow::RGBA,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGBA12, "GL_RGBA12", glow::RGBA, glow::UNSIGNED_SHORT),
    f(glow::SRGB8, "GL_SRGB8", glow::RGB, glow::UNSIGNED_BYTE),
    f(
        glow::SRGB8_ALPHA8,
        "GL_SRGB8_ALPHA8",
        glow::RGBA,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::R16, "GL_R16", glow::RED, glow::UNSIGNED_SHORT),
    f(glow::RG16, "GL_RG16", glow::RG, glow::UNSIGNED_SHORT),
    f(glow::RGB16, "GL_RGB16", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGBA16, "GL_RGBA16", glow::RGBA, glow::UNSIGNED_SHORT),
    f(glow::R8_SNORM, "GL_R8_SNORM", glow::RED, glow::BYTE),
    f(glow::RG8_SNORM, "GL_RG8_SNORM", glow::RG, glow::BYTE),
    f(glow::RGB8_SNORM, "GL_RGB8_SNORM", glow::RGB, glow::BYTE),
    f(glow::RGBA8_SNORM, "GL_RGBA8_SNORM", glow::RGBA, glow::BYTE),
    f(glow::R16_SNORM, "GL_R16_SNORM", glow::RED, glow::SHORT),
    f(glow::RG16_SNORM, "GL_RG16_SNORM", glow::RG, glow::SHORT),
    f(glow::RGB16_SNORM, "GL_RGB16_SNORM", glow::RGB, glow::SHORT),
    f(
        glow::RGBA16_SNORM,
        "GL_RGBA16_SNORM",
        glow::RGBA,
        glow::SHORT,
    ),
    f(glow::R16F, "GL_R16F", glow::RED, glow::HALF_FLOAT),
    f(glow::RG16F, "GL_RG16F", glow::RG, glow::HALF_FLOAT),
    f(glow::RGB16F, "GL_RGB16F", glow::RGB, glow::HALF_FLOAT),
    f(glow::RGBA16F, "GL_RGBA16F", glow::RGBA, glow::FLOAT),
    f(glow::R32F, "GL_R32F", glow::RED, glow::FLOAT),
    f(glow::RG32F, "GL_RG32F", glow::RG, glow::FLOAT),
    f(glow::RGB32F, "GL_RGB32F", glow::RGB, glow::FLOAT),
    f(glow::RGBA32F, "GL_RGBA32F", glow::RGBA, glow::FLOAT),
    f(
        glow::R11F_G11F_B10F,
        "GL_R11F_G11F_B10F",
        glow::RGB,
        glow::FLOAT,
    ),
    f(glow::RGB9_E5, "GL_RGB9_E5", glow::RGB, glow::FLOAT),
    f(glow::R8I, "GL_R8I", glow::RED_INTEGER, glow::BYTE),
    f(
        glow::R8UI,
        "GL_R8UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::R16I, "GL_R16I", glow::RED_INTEGER, glow::SHORT),
    f(
        glow::R16UI,
        "GL_R16UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::R32I, "GL_R32I", glow::RED_INTEGER, glow::INT),
    f(
        glow::R32UI,
        "GL_R32UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RG8I, "GL_RG8I", glow::RG_INTEGER, glow::BYTE),
    f(
        glow::RG8UI,
        "GL_RG8UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RG16I, "GL_RG16I", glow::RG_INTEGER, glow::SHORT),
    f(
        glow::RG16UI,
        "GL_RG16UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::RG32I, "GL_RG32I", glow::RG_INTEGER, glow::INT),
    f(
        glow::RG32UI,
        "GL_RG32UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RGB8I, "GL_RGB8I", glow::RGB_INTEGER, glow::BYTE),
    f(
        glow::RGB8UI,
        "GL_RGB8UI",
        glow::RGB_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(
        glow::RGB32UI,
        "GL_RGB32UI",
        glow::RGB_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RGBA8I, "GL_RGBA8I", glow::RGBA_INTEGER, glow::BYTE),
    f(
        glow::RGBA8UI,
        "GL_RGBA8UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGBA16I, "GL_RGBA16I", glow::RGBA_INTEGER, glow::SHORT),
    f(
        glow::RGBA16UI,
        "GL_RGBA16UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::RGBA32I, "GL_RGBA32I", glow::RGBA_INTEGER, glow::INT),
    f(
        glow::RGBA32UI,
        "GL_RGBA32UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::RGB10_A2UI,
        "GL_RGB10_A2UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
];

/// Every depth and depth-stencil internal format, sized and unsized.
pub const DEPTH_FORMATS: &[HostFormat] = &[
    f(
        glow::DEPTH_COMPONENT16,
        "GL_DEPTH_COMPONENT16",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_SHORT,
    ),
    f(
        glow::DEPTH_COMPONENT24,
        "GL_DEPTH_COMPONENT24",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::DEPTH_COMPONENT32,
        "GL_DEPTH_COMPONENT32",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::DEPTH_COMPONENT32F,
        "GL_DEPTH_COMPONENT32F",
        glow::DEPTH_COMPONENT,
        glow::FLOAT,
    ),
    f(
        glow::DEPTH_COMPONENT,
        "GL_DEPTH_COMPONENT",
        glow::DEPTH_COMPONENT,
        glow::FLOAT,
    ),
    f(
        glow::DEPTH24_STENCIL8,
        "GL_DEPTH24_STENCIL8",
        glow::DEPTH_STENCIL,
        glow::UNSIGNED_INT_24_8,
    ),
    f(
        glow::DEPTH32F_STENCIL8,
        "GL_DEPTH32F_STENCIL8",
        glow::DEPTH_STENCIL,
        glow::FLOAT_32_UNSIGNED_INT_24_8_REV,
    ),
    f(
        glow::DEPTH_STENCIL,
        "GL_DEPTH_STENCIL",
        glow::DEPTH_STENCIL,
        glow::UNSIGNED_INT_24_8,
    ),
];

/// The stencil-only format a host with no depth may attach.
pub const STENCIL_ONLY: HostFormat = f(
    glow::STENCIL_INDEX8,
    "GL_STENCIL_INDEX8",
    glow::STENCIL_INDEX,
    glow::UNSIGNED_BYTE,
);

impl std::fmt::Debug for HostFormat {
    // A case written out names its formats as the host's code does.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ty = match self.ty {
            glow::UNSIGNED_BYTE => "GL_UNSIGNED_BYTE",
            glow::BYTE => "GL_BYTE",
            glow::UNSIGNED_SHORT => "GL_UNSIGNED_SHORT",
            glow::SHORT => "GL_SHORT",
            glow::UNSIGNED_INT => "GL_UNSIGNED_INT",
            glow::INT => "GL_INT",
            glow::HALF_FLOAT => "GL_HALF_FLOAT",
            glow::FLOAT => "GL_FLOAT",
            glow::UNSIGNED_INT_24_8 => "GL_UNSIGNED_INT_24_8",
            _ => "GL_FLOAT_32_UNSIGNED_INT_24_8_REV",
        };
        write!(f, "HostFormat::of(\"{}\", \"{ty}\")", self.name)
    }
}

impl HostFormat {
    /// The format named `name` uploaded with pixel type `ty` (both by their
    /// GL names), as a case written out states it.
    pub fn of(name: &str, ty: &str) -> HostFormat {
        COLOR_FORMATS
            .iter()
            .chain(DEPTH_FORMATS)
            .chain([&STENCIL_ONLY])
            .copied()
            .find(|f| f.name == name && format!("{f:?}").contains(&format!("\"{ty}\"")))
            .unwrap_or_else(|| panic!("no host format {name} with type {ty}"))
    }

    /// The format whose GL name is `name` (for regression cases written out
    /// by name); the first entry where a name appears twice (with two types).
    pub fn named(name: &str) -> Option<HostFormat> {
        COLOR_FORMATS
            .iter()
            .chain(DEPTH_FORMATS)
            .chain([&STENCIL_ONLY])
            .copied()
            .find(|f| f.name == name)
    }

    /// A depth-stencil format.
    pub fn has_stencil(&self) -> bool {
        self.pixel == glow::DEPTH_STENCIL || self.pixel == glow::STENCIL_INDEX
    }
}

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

fn chance(rng: &mut Rng, percent: u32) -> bool {
    rng.below(100) < percent
}

fn pick<T: Clone>(rng: &mut Rng, items: &[T]) -> T {
    items[rng.below(items.len() as u32) as usize].clone()
}

fn storage(rng: &mut Rng) -> Storage {
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

fn size(rng: &mut Rng) -> (u32, u32) {
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

/// How a shader writes and reads an attachment, as the driver made it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueKind {
    /// Unsigned normalised (and sRGB): `vec4` in [0, 1].
    Unorm,
    /// Signed normalised: `vec4` in [-1, 1].
    Snorm,
    /// Floating point (`unsigned` for `GL_R11F_G11F_B10F`).
    Float {
        /// Whether the format stores no sign.
        unsigned: bool,
    },
    /// Signed integer: `ivec4`.
    Int,
    /// Unsigned integer: `uvec4`.
    Uint,
}

impl ValueKind {
    /// Integer formats, which the resolve selects one sample of.
    pub fn is_integer(self) -> bool {
        matches!(self, ValueKind::Int | ValueKind::Uint)
    }
}

/// The GL objects of one image.
#[derive(Clone, Copy, Debug)]
enum Image {
    Texture(glow::Texture),
    Renderbuffer(glow::Renderbuffer),
}

/// A random host's objects, built from its [`HostSpec`] with raw GL.
#[derive(Debug)]
pub struct RandomHost {
    /// What it was built from.
    pub spec: HostSpec,
    /// Its framebuffer.
    pub fbo: glow::Framebuffer,
    /// Width now.
    pub width: u32,
    /// Height now.
    pub height: u32,
    /// How each colour attachment (in spec order) is written.
    pub kinds: Vec<ValueKind>,
    images: Vec<Image>,
    depth_image: Option<Image>,
}

/// Why a random host could not be built: a host bug, not a case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HostIncomplete(pub String);

fn status_name(status: u32) -> String {
    deferred_msaa::gl::framebuffer_status_name(status).to_string()
}

impl RandomHost {
    /// Build it; a framebuffer the driver calls incomplete, or a GL error
    /// while building it, is the host's own bug ([`HostIncomplete`],
    /// nothing left allocated). The host's bindings go back to 0.
    pub fn build(gl: &glow::Context, spec: &HostSpec) -> Result<RandomHost, HostIncomplete> {
        unsafe {
            let _ = gl.get_error();
            let fbo = gl.create_framebuffer().map_err(HostIncomplete)?;
            let mut host = RandomHost {
                spec: spec.clone(),
                fbo,
                width: spec.width,
                height: spec.height,
                kinds: Vec::new(),
                images: Vec::new(),
                depth_image: None,
            };
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            for c in &spec.colors {
                let (w, h) = c.size.unwrap_or((spec.width, spec.height));
                let image = allocate(gl, c.format, c.storage, w, h);
                attach(gl, glow::COLOR_ATTACHMENT0 + c.point, &image, c.storage);
                host.images.push(image);
            }
            if let Some(d) = &spec.depth {
                let image = allocate(gl, d.format, d.storage, spec.width, spec.height);
                let points: &[u32] = match d.point {
                    DepthPoint::Depth => &[glow::DEPTH_ATTACHMENT],
                    DepthPoint::DepthStencil => &[glow::DEPTH_STENCIL_ATTACHMENT],
                    DepthPoint::Both => &[glow::DEPTH_ATTACHMENT, glow::STENCIL_ATTACHMENT],
                    DepthPoint::Stencil => &[glow::STENCIL_ATTACHMENT],
                };
                for &p in points {
                    attach(gl, p, &image, d.storage);
                }
                host.depth_image = Some(image);
            }
            let buffers: Vec<u32> = spec
                .draw_buffers
                .iter()
                .map(|b| b.map_or(glow::NONE, |n| glow::COLOR_ATTACHMENT0 + n))
                .collect();
            gl.draw_buffers(&buffers);
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            let error = gl.get_error();
            let problem = if error != glow::NO_ERROR {
                Some(format!("GL error 0x{error:04X} while building"))
            } else if status != glow::FRAMEBUFFER_COMPLETE {
                Some(status_name(status))
            } else {
                None
            };
            if let Some(p) = problem {
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                host.destroy(gl);
                let _ = gl.get_error();
                return Err(HostIncomplete(p));
            }
            host.kinds = spec
                .colors
                .iter()
                .map(|c| value_kind(gl, glow::COLOR_ATTACHMENT0 + c.point, c.format))
                .collect();
            host.fill_undrawn(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            let error = gl.get_error();
            if error != glow::NO_ERROR {
                host.destroy(gl);
                return Err(HostIncomplete(format!(
                    "GL error 0x{error:04X} while clearing"
                )));
            }
            Ok(host)
        }
    }

    /// Give attachments no draw buffer maps a value of their own, so that
    /// a resolve that wrote them would show: each in turn becomes draw
    /// buffer 0 for one clear, then the host's list is put back.
    unsafe fn fill_undrawn(&self, gl: &glow::Context) {
        unsafe {
            for (c, kind) in self.spec.colors.iter().zip(&self.kinds) {
                if self.spec.draw_buffers.contains(&Some(c.point)) {
                    continue;
                }
                gl.draw_buffers(&[glow::COLOR_ATTACHMENT0 + c.point]);
                let v = 3 + c.point;
                match kind {
                    ValueKind::Int => gl.clear_buffer_i32_slice(glow::COLOR, 0, &[v as i32; 4]),
                    ValueKind::Uint => gl.clear_buffer_u32_slice(glow::COLOR, 0, &[v; 4]),
                    _ => gl.clear_buffer_f32_slice(glow::COLOR, 0, &[v as f32 / 16.0; 4]),
                }
            }
            let buffers: Vec<u32> = self
                .spec
                .draw_buffers
                .iter()
                .map(|b| b.map_or(glow::NONE, |n| glow::COLOR_ATTACHMENT0 + n))
                .collect();
            gl.draw_buffers(&buffers);
        }
    }

    /// Re-specify every image at `width` x `height`, in place (the same
    /// texture and renderbuffer names), as an engine does on a window
    /// resize; the framebuffer is left as it is.
    pub fn resize(&mut self, gl: &glow::Context, width: u32, height: u32) {
        unsafe {
            for (c, image) in self.spec.colors.iter().zip(&self.images) {
                respecify(gl, c.format, c.storage, image, width, height);
            }
            if let (Some(d), Some(image)) = (&self.spec.depth, &self.depth_image) {
                respecify(gl, d.format, d.storage, image, width, height);
            }
            self.width = width;
            self.height = height;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            self.fill_undrawn(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    /// Delete everything the host made.
    pub fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            for image in self.images.iter().chain(&self.depth_image) {
                match *image {
                    Image::Texture(t) => gl.delete_texture(t),
                    Image::Renderbuffer(r) => gl.delete_renderbuffer(r),
                }
            }
        }
    }
}

fn value_kind(gl: &glow::Context, point: u32, format: HostFormat) -> ValueKind {
    let ty = unsafe {
        gl.get_framebuffer_attachment_parameter_i32(
            glow::FRAMEBUFFER,
            point,
            glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE,
        )
    } as u32;
    match ty {
        glow::INT => ValueKind::Int,
        glow::UNSIGNED_INT => ValueKind::Uint,
        glow::SIGNED_NORMALIZED => ValueKind::Snorm,
        glow::FLOAT => ValueKind::Float {
            unsigned: matches!(format.internal, glow::R11F_G11F_B10F | glow::RGB9_E5),
        },
        _ => ValueKind::Unorm,
    }
}

unsafe fn tex_image(gl: &glow::Context, target: u32, format: HostFormat, w: u32, h: u32) {
    unsafe {
        gl.tex_image_2d(
            target,
            0,
            format.internal as i32,
            w as i32,
            h as i32,
            0,
            format.pixel,
            format.ty,
            glow::PixelUnpackData::Slice(None),
        );
    }
}

unsafe fn array_image(gl: &glow::Context, target: u32, format: HostFormat, w: u32, h: u32, d: u32) {
    unsafe {
        gl.tex_image_3d(
            target,
            0,
            format.internal as i32,
            w as i32,
            h as i32,
            d as i32,
            0,
            format.pixel,
            format.ty,
            glow::PixelUnpackData::Slice(None),
        );
    }
}

fn layers_of(storage: Storage) -> u32 {
    match storage {
        Storage::Layer { layers, .. } => layers,
        Storage::Texture3dLayer => 2,
        _ => 1,
    }
}

unsafe fn respecify(
    gl: &glow::Context,
    format: HostFormat,
    storage: Storage,
    image: &Image,
    w: u32,
    h: u32,
) {
    unsafe {
        match (*image, storage) {
            (Image::Renderbuffer(rb), Storage::MultisampledRenderbuffer) => {
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage_multisample(
                    glow::RENDERBUFFER,
                    4,
                    format.internal,
                    w as i32,
                    h as i32,
                );
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
            }
            (Image::Renderbuffer(rb), _) => {
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage(glow::RENDERBUFFER, format.internal, w as i32, h as i32);
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
            }
            (Image::Texture(t), s) => {
                let target = texture_target(s);
                gl.bind_texture(target, Some(t));
                match s {
                    Storage::Layer { .. } | Storage::Texture3dLayer | Storage::Layered => {
                        array_image(gl, target, format, w, h, layers_of(s))
                    }
                    Storage::MipLevel1 => {
                        tex_image(gl, target, format, 2 * w, 2 * h);
                        gl.tex_image_2d(
                            target,
                            1,
                            format.internal as i32,
                            w as i32,
                            h as i32,
                            0,
                            format.pixel,
                            format.ty,
                            glow::PixelUnpackData::Slice(None),
                        );
                        // Levels 0 and 1 make the whole chain: a level
                        // other than the base one is attachable only from
                        // a mipmap-complete texture.
                        gl.tex_parameter_i32(target, glow::TEXTURE_MAX_LEVEL, 1);
                    }
                    Storage::CubeFace => {
                        for face in 0..6 {
                            tex_image(gl, glow::TEXTURE_CUBE_MAP_POSITIVE_X + face, format, w, h);
                        }
                    }
                    Storage::MultisampledTexture => gl.tex_image_2d_multisample(
                        target,
                        4,
                        format.internal as i32,
                        w as i32,
                        h as i32,
                        true,
                    ),
                    _ => tex_image(gl, target, format, w, h),
                }
                if s != Storage::MultisampledTexture {
                    // Tutorials set nearest filtering; mipmaps are not made.
                    gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
                    gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
                }
                gl.bind_texture(target, None);
            }
        }
    }
}

fn texture_target(storage: Storage) -> u32 {
    match storage {
        Storage::Layer { .. } | Storage::Layered => glow::TEXTURE_2D_ARRAY,
        Storage::CubeFace => glow::TEXTURE_CUBE_MAP,
        Storage::Rectangle => glow::TEXTURE_RECTANGLE,
        Storage::Texture3dLayer => glow::TEXTURE_3D,
        Storage::MultisampledTexture => glow::TEXTURE_2D_MULTISAMPLE,
        _ => glow::TEXTURE_2D,
    }
}

unsafe fn allocate(
    gl: &glow::Context,
    format: HostFormat,
    storage: Storage,
    w: u32,
    h: u32,
) -> Image {
    unsafe {
        let image = match storage {
            Storage::Renderbuffer | Storage::MultisampledRenderbuffer => {
                Image::Renderbuffer(gl.create_renderbuffer().expect("a renderbuffer name"))
            }
            _ => Image::Texture(gl.create_texture().expect("a texture name")),
        };
        respecify(gl, format, storage, &image, w, h);
        image
    }
}

unsafe fn attach(gl: &glow::Context, point: u32, image: &Image, storage: Storage) {
    unsafe {
        match (*image, storage) {
            (Image::Renderbuffer(rb), _) => {
                gl.framebuffer_renderbuffer(glow::FRAMEBUFFER, point, glow::RENDERBUFFER, Some(rb))
            }
            (Image::Texture(t), Storage::Layer { layer, .. }) => {
                gl.framebuffer_texture_layer(glow::FRAMEBUFFER, point, Some(t), 0, layer as i32)
            }
            (Image::Texture(t), Storage::Texture3dLayer) => {
                gl.framebuffer_texture_layer(glow::FRAMEBUFFER, point, Some(t), 0, 1)
            }
            (Image::Texture(t), Storage::Layered) => {
                gl.framebuffer_texture(glow::FRAMEBUFFER, point, Some(t), 0)
            }
            (Image::Texture(t), Storage::MipLevel1) => {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(t), 1)
            }
            (Image::Texture(t), Storage::CubeFace) => gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                point,
                glow::TEXTURE_CUBE_MAP_POSITIVE_X,
                Some(t),
                0,
            ),
            (Image::Texture(t), s) => {
                gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, texture_target(s), Some(t), 0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_is_one_host() {
        let limits = Limits {
            color_attachments: 8,
            draw_buffers: 8,
        };
        for seed in 0..200 {
            let a = HostSpec::generate(seed, limits);
            assert_eq!(a, HostSpec::generate(seed, limits));
            let points: Vec<u32> = a.colors.iter().map(|c| c.point).collect();
            let mut sorted = points.clone();
            sorted.dedup();
            assert_eq!(points, sorted, "distinct points in order");
            assert!(a.draw_buffers.len() as u32 <= limits.draw_buffers);
            for b in a.draw_buffers.iter().flatten() {
                assert!(
                    points.contains(b),
                    "seed {seed}: draws only what is attached"
                );
            }
        }
        assert_ne!(HostSpec::generate(1, limits), HostSpec::generate(2, limits));
    }
}
