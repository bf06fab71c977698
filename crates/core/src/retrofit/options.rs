//! What a host tells the retrofit once ([`RetrofitOptions`]): the sample
//! count, the resolve's settings, its attachments' roles, the twins' clear
//! values and what comes back after a second layer.

use crate::gbuffer::MemoryBudget;
use crate::gl::ColorAttachment;
use crate::layer_mix::LayerMix;
use crate::resolve::{NormalEncoding, ResolveRule, ResolveSettings, StencilCopy};
use crate::second_layer::FirstLayerRestore;

/// How a host G-buffer is multisampled and resolved: everything that does
/// not change from frame to frame, given once. The programs it needs are
/// compiled when the retrofit is made; [`MsaaRetrofit::set_options`](crate::MsaaRetrofit::set_options)
/// changes it and rebuilds what must be rebuilt.
#[derive(Clone, Debug, PartialEq)]
pub struct RetrofitOptions {
    /// Requested samples per pixel (the driver's real count is used:
    /// [`MsaaRetrofit::samples`](crate::MsaaRetrofit::samples)).
    pub samples: u32,
    /// Rules for colour attachments by attachment number; the others take
    /// their format's default ([`ResolveRule::default_for`]: blend, select for
    /// integers).
    pub rules: Vec<(ColorAttachment, ResolveRule)>,
    /// The colour attachment holding view-space position, whose `-z` is
    /// the depth key; `None` (the default) linearises the depth attachment
    /// with each frame's projection instead.
    pub position_attachment: Option<ColorAttachment>,
    /// What space [`RetrofitOptions::position_attachment`] holds
    /// positions in; with [`PositionSpace::World`] each frame passes its
    /// view matrix ([`Frame::with_view`](crate::Frame::with_view)).
    pub position_space: PositionSpace,
    /// Method, window, fast path and selective anti-aliasing.
    pub resolve: ResolveSettings,
    /// How a depth-stencil host's stencil is written back after the
    /// resolve ([`StencilCopy`]: by default the reference sample's value).
    pub stencil: StencilCopy,
    /// A limit on the twins' memory: over it, the sample count steps down
    /// (with a line in [`MsaaRetrofit::warnings`](crate::MsaaRetrofit::warnings)) or, strict, the retrofit
    /// refuses with [`Error::MemoryBudget`](crate::Error::MemoryBudget).
    pub memory_budget: Option<MemoryBudget>,
    /// The colour attachment holding normals, and how: samples whose
    /// normals differ are different surfaces even when close in depth, in
    /// the one-layer resolve as in both of two layers (`None`: by depth
    /// alone), and the reference moves to the face most samples within its
    /// depth window share, a tie by the pixel's parity (a crease's larger
    /// face: docs/resolve.md, "The math"). A host whose normals are packed (`n * 0.5 + 0.5` in an
    /// unsigned normalised format) should name it with
    /// [`NormalEncoding::Unorm`]: without the test a crease pixel blends two
    /// packed normals into one that lights like neither face.
    pub normal_attachment: Option<NormalAttachment>,
    /// What the host's lit values mean, and so how
    /// [`MsaaRetrofit::finish_second_layer`](crate::MsaaRetrofit::finish_second_layer)
    /// mixes the two lit layers and
    /// [`MsaaRetrofit::finish_forward`](crate::MsaaRetrofit::finish_forward)
    /// averages samples. [`LayerMix::Auto`] (the default) infers it for 8-bit
    /// outputs and refuses a floating-point one, whose tonemap it cannot see.
    pub layer_mix: LayerMix,
    /// What [`MsaaRetrofit::finish_second_layer`](crate::MsaaRetrofit::finish_second_layer) puts back of the first
    /// layer in the host's G-buffer ([`FirstLayerRestore`]; by default
    /// everything). The lit image is the same whichever is chosen.
    pub restore_first_layer: FirstLayerRestore,
    /// With two layers: count, with `GL_SAMPLES_PASSED` occlusion queries,
    /// what the host's first and second lighting draw, and return
    /// [`Error::SecondLighting`](crate::Error::SecondLighting) where the first drew and the second drew
    /// nothing (its own depth or stencil test rejected it) though pixels
    /// have a second layer, and where a second lighting into the own
    /// target cleared or wrote the second layer's depth it holds (so lit
    /// the second layer as background) (default `true`). The queries are active from
    /// the end of `resolve` to the start of `begin_second_layer` and from
    /// its end to the start of `finish_second_layer`; a host that runs
    /// occlusion queries of its own there, or whose second lighting draws
    /// no fragments while something between `resolve` and its first
    /// lighting does (a compute-shader lighting after a fragment SSAO
    /// pass), turns it off.
    pub check_second_lighting: bool,
    /// What [`MsaaRetrofit::begin_frame`](crate::MsaaRetrofit::begin_frame) clears the multisampled twins to
    /// (`None`, the default: it clears nothing, and the host clears its
    /// G-buffer through [`MsaaRetrofit::framebuffer`](crate::MsaaRetrofit::framebuffer) as it cleared its own
    /// framebuffer). A host that clears its G-buffer's textures through
    /// another framebuffer, or per attachment with values of its own,
    /// never clears the twins: it declares its clear values here and calls
    /// `begin_frame` each frame.
    pub twin_clear: Option<TwinClear>,
    /// With two layers: colour attachments the second layer need not
    /// carry, because the host's lighting does not read them or reads the
    /// same value for both surfaces (an object ID, velocity, a decal mask).
    /// They are not resolved for the second layer (fewer draw buffers and
    /// less work), and during the second lighting the host's image holds
    /// the first layer's value there. Default: none.
    pub second_layer_omits: Vec<ColorAttachment>,
    /// With two layers: the colour the host's lit target shows where its
    /// lighting writes nothing (its clear colour, for a host that leaves its
    /// sky or background to `glClear`). The own target of
    /// [`MsaaRetrofit::begin_second_layer_own_target`](crate::MsaaRetrofit::begin_second_layer_own_target)
    /// starts cleared to it. `None` (the default): the own target starts as
    /// a copy of the output's lit first layer, as the output holds it for a
    /// second lighting into it without a clear; a pixel the second lighting
    /// leaves unwritten then mixes to the first layer's value. Never the
    /// host's last `glClearColor`, which may be another target's.
    pub lit_clear: Option<[f32; 4]>,
}

/// The values a host clears its G-buffer to, for
/// [`MsaaRetrofit::begin_frame`](crate::MsaaRetrofit::begin_frame) to clear the multisampled twins to
/// ([`RetrofitOptions::twin_clear`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TwinClear {
    /// Per colour attachment, its clear value (`glClearBufferfv`'s; an
    /// integer attachment takes the values as integers); an attachment not
    /// listed is cleared to 0.
    pub colors: Vec<(ColorAttachment, [f32; 4])>,
    /// The depth clear value (1 for standard depth, 0 for reversed-Z).
    pub depth: f32,
    /// The stencil clear value, for a depth-stencil host.
    pub stencil: i32,
}

impl Default for TwinClear {
    /// Colours 0, depth 1, stencil 0.
    fn default() -> Self {
        TwinClear {
            colors: Vec::new(),
            depth: 1.0,
            stencil: 0,
        }
    }
}

/// A host's normal attachment and its encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NormalAttachment {
    /// The attachment.
    pub attachment: ColorAttachment,
    /// How it stores a normal.
    pub encoding: NormalEncoding,
}

impl Default for RetrofitOptions {
    fn default() -> Self {
        RetrofitOptions {
            samples: 4,
            rules: Vec::new(),
            position_attachment: None,
            position_space: PositionSpace::View,
            resolve: ResolveSettings::default(),
            stencil: StencilCopy::Auto,
            memory_budget: None,
            normal_attachment: None,
            layer_mix: LayerMix::Auto,
            restore_first_layer: FirstLayerRestore::Everything,
            check_second_lighting: true,
            twin_clear: None,
            second_layer_omits: Vec::new(),
            lit_clear: None,
        }
    }
}

/// The space of a host's position attachment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PositionSpace {
    /// View space: the key is `−z`, as it is.
    #[default]
    View,
    /// World space (the most-copied deferred tutorial's layout): the key is
    /// view space's `−z`, from each frame's view matrix.
    World,
}
