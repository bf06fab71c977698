//! What one resolve reads and writes: its colour slots, the depth key's
//! source, its inputs and its extra outputs.

use super::settings::{NormalEncoding, ResolveRule};
use crate::ColorAttachment;
use crate::gl::TextureRef;

/// The most colour attachments one resolve handles (GL 3.2 guarantees 8 draw buffers).
pub const MAX_ATTACHMENTS: usize = 8;

/// A colour input of the resolve by position: slot `k` is the `k`-th
/// texture of [`ResolveInputs::colors`] and goes to the target's draw
/// buffer `k`. A host names its attachments by [`ColorAttachment`] instead;
/// the retrofit maps one to the other.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ResolveSlot(pub usize);

/// Where the per-sample depth key comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum KeySource {
    /// `z = −position.z` of the colour input in this slot (view-space position).
    Position(ResolveSlot),
    /// `z = −(view · position).z` of the colour input in this slot
    /// (world-space position; the view matrix comes with each frame).
    WorldPosition(ResolveSlot),
    /// The depth attachment, linearised with the projection.
    Depth,
}

/// What a resolve writes besides the resolved attachments and depth, to
/// the draw buffers after the attachments', in this order. `true` and
/// `false` convert to the complex-pixel mask alone, or nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ExtraOutputs {
    /// 1.0 where the pixel took the slow path, else 0.0 (a float target).
    pub complex: bool,
    /// 1.0 where a sample lies outside the pixel's cluster (its weight is
    /// 0: the pixel may have a second layer), else 0.0 (a float target).
    pub outside: bool,
    /// The index of the pixel's reference sample (0 where it took one
    /// sample), to an unsigned-integer target: how the host's stencil is
    /// copied from the reference sample.
    pub reference: bool,
}

impl From<bool> for ExtraOutputs {
    fn from(complex: bool) -> Self {
        ExtraOutputs {
            complex,
            outside: false,
            reference: false,
        }
    }
}

/// The inputs of one resolve.
#[derive(Clone, Debug)]
pub struct ResolveInputs<'a> {
    /// The multisampled depth texture (or its per-sample layer array).
    pub depth: TextureRef,
    /// The multisampled colour textures, in slot order (slot `k` is written
    /// to the target's draw buffer `k`).
    pub colors: &'a [TextureRef],
    /// The attachment each colour input stands for, in the same order: how
    /// [`SelectionFlag::attachment`](super::SelectionFlag::attachment) finds its slot.
    pub attachments: &'a [ColorAttachment],
    /// One rule per colour texture.
    pub rules: &'a [ResolveRule],
    /// Where the depth key comes from.
    pub key: KeySource,
    /// Sample count; for layer arrays, the number of layers.
    pub samples: u32,
    /// The colour input holding normals and their encoding: clusters split
    /// by normal too, with one layer or two ([`ResolveSettings::normal_threshold`](super::ResolveSettings::normal_threshold)).
    pub normal: Option<(ResolveSlot, NormalEncoding)>,
}

impl ResolveInputs<'_> {
    /// The slot holding `attachment`, if it is an input.
    pub fn slot_of(&self, attachment: ColorAttachment) -> Option<ResolveSlot> {
        self.attachments
            .iter()
            .position(|a| *a == attachment)
            .map(ResolveSlot)
    }

    pub(super) fn attachment_list(&self) -> String {
        let names: Vec<String> = self.attachments.iter().map(|a| a.name()).collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    }
}
