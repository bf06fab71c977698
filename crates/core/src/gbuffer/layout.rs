//! Declarative G-buffer layouts.

use crate::gl::Format;
use crate::resolve::{KeySource, MAX_ATTACHMENTS, ResolveRule, ResolveSlot};
use crate::{Error, Result};

/// One colour attachment: its name, storage and resolve rule. Its index in
/// [`GBufferLayout::colors`] is its colour attachment and fragment output number.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct AttachmentDesc {
    /// Name used in views, dumps and errors (`color`, `position`, …).
    pub name: String,
    /// Internal format.
    pub format: Format,
    /// How its samples become one value.
    pub rule: ResolveRule,
}

impl AttachmentDesc {
    /// An attachment with its format's default rule (integer formats select).
    pub fn new(name: &str, format: Format) -> Self {
        AttachmentDesc {
            name: name.to_string(),
            format,
            rule: ResolveRule::default_for(format),
        }
    }

    /// The same attachment with another rule.
    pub fn with_rule(mut self, rule: ResolveRule) -> Self {
        self.rule = rule;
        self
    }
}

/// A G-buffer layout: colour attachments, the depth format, the key source.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GBufferLayout {
    /// Colour attachments in attachment order.
    pub colors: Vec<AttachmentDesc>,
    /// The depth attachment's format.
    pub depth: Format,
    /// Where the resolve's depth key comes from.
    pub key: KeySource,
}

impl GBufferLayout {
    /// FreeSpace Open's G-buffer exactly (docs/freespace-open.md): colour,
    /// view-space position, normal with gloss in w (not normalised), specular,
    /// emissive, and 24-bit depth; the key comes from the FP16 position.
    pub fn freespace_open() -> Self {
        GBufferLayout {
            colors: vec![
                AttachmentDesc::new("color", Format::Rgba16f),
                AttachmentDesc::new("position", Format::Rgba16f),
                AttachmentDesc::new("normal", Format::Rgba16f).with_rule(ResolveRule::BlendNormal),
                AttachmentDesc::new("specular", Format::Rgba8),
                AttachmentDesc::new("emissive", Format::Rgba16f).with_rule(ResolveRule::BlendHdr),
            ],
            depth: Format::Depth24,
            key: KeySource::Position(ResolveSlot(1)),
        }
    }

    /// The crate's recommended layout: FreeSpace Open's attachments, but the
    /// position in FP32 and depth in 32-bit float, so that distant models
    /// (beyond FP16's 65504) keep their position and their depth detail,
    /// and the normal taken from the reference sample (`select`) rather
    /// than blended.
    ///
    /// Why `select`: at a convex edge inside a model the blended normal,
    /// renormalised, points between the two faces, so a light between
    /// their normals lights it more squarely than either face: edge pixels
    /// come out brighter than the faces they average. Lambert shading is
    /// linear in the normal, so the unbiased value is the average of the
    /// shaded faces, which one face's normal approaches and the renormalised
    /// sum overshoots (docs/bench.md shows what it measures).
    pub fn recommended() -> Self {
        let mut layout = Self::freespace_open();
        layout.colors[1].format = Format::Rgba32f;
        layout.depth = Format::Depth32f;
        layout.colors[2].rule = ResolveRule::Select;
        layout
    }

    /// The index of a colour attachment by name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.colors.iter().position(|a| a.name == name)
    }

    /// The colour attachment by name.
    pub fn attachment(&self, name: &str) -> Option<&AttachmentDesc> {
        self.colors.iter().find(|a| a.name == name)
    }

    /// The attachment the key is read from, if the key comes from a position.
    pub fn key_attachment(&self) -> Option<&AttachmentDesc> {
        match self.key {
            KeySource::Position(ResolveSlot(k)) | KeySource::WorldPosition(ResolveSlot(k)) => {
                self.colors.get(k)
            }
            KeySource::Depth => None,
        }
    }

    /// Bytes one sample occupies across all attachments and depth.
    pub fn bytes_per_sample(&self) -> u64 {
        self.colors
            .iter()
            .map(|a| a.format.bytes_per_texel() as u64)
            .sum::<u64>()
            + self.depth.bytes_per_texel() as u64
    }

    /// Bytes of a `width`×`height` G-buffer with `samples` samples per pixel.
    pub fn bytes(&self, width: u32, height: u32, samples: u32) -> u64 {
        self.bytes_per_sample() * width as u64 * height as u64 * samples.max(1) as u64
    }

    /// Check the layout can work: names unique, formats fit their roles,
    /// integer formats select, the key attachment exists.
    pub fn validate(&self) -> Result<()> {
        if self.colors.is_empty() {
            return Err(Error::Layout("no colour attachments".into()));
        }
        if self.colors.len() > MAX_ATTACHMENTS {
            return Err(Error::Layout(format!(
                "{} colour attachments; at most {MAX_ATTACHMENTS} are supported",
                self.colors.len()
            )));
        }
        if !self.depth.is_depth() {
            return Err(Error::UnsupportedFormat {
                attachment: "depth".into(),
                format: self.depth.name().into(),
                reason: "the depth attachment needs a DEPTH_COMPONENT or DEPTH_STENCIL format"
                    .into(),
            });
        }
        for (i, a) in self.colors.iter().enumerate() {
            if self.colors[..i].iter().any(|b| b.name == a.name) {
                return Err(Error::Layout(format!(
                    "attachment name `{}` is used twice",
                    a.name
                )));
            }
            if a.format.is_depth() {
                return Err(Error::UnsupportedFormat {
                    attachment: a.name.clone(),
                    format: a.format.name().into(),
                    reason: "a colour attachment needs a colour format".into(),
                });
            }
            if ResolveRule::default_for(a.format) == ResolveRule::Select
                && a.rule != ResolveRule::Select
            {
                return Err(Error::UnsupportedFormat {
                    attachment: a.name.clone(),
                    format: a.format.name().into(),
                    reason: format!(
                        "integer values can only be selected, not resolved by `{}`",
                        a.rule
                    ),
                });
            }
        }
        if let KeySource::Position(ResolveSlot(k)) | KeySource::WorldPosition(ResolveSlot(k)) =
            self.key
        {
            match self.colors.get(k) {
                None => {
                    return Err(Error::Layout(format!(
                        "the depth key reads colour attachment {k}, which does not exist"
                    )));
                }
                Some(a) if ResolveRule::default_for(a.format) == ResolveRule::Select => {
                    return Err(Error::UnsupportedFormat {
                        attachment: a.name.clone(),
                        format: a.format.name().into(),
                        reason: "the depth key needs a floating-point position".into(),
                    });
                }
                Some(_) => {}
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn freespace_open_layout_is_40_bytes_per_sample() {
        let fso = GBufferLayout::freespace_open();
        fso.validate().unwrap();
        assert_eq!(fso.bytes_per_sample(), 8 + 8 + 8 + 4 + 8 + 4);
        // FreeSpace Open's figure: about 332 MB at 1080p 4x.
        let mb = fso.bytes(1920, 1080, 4) as f64 / 1e6;
        assert!((mb - 332.0).abs() < 1.0, "{mb}");
    }

    #[test]
    fn recommended_layout_is_valid_and_wide() {
        let rec = GBufferLayout::recommended();
        rec.validate().unwrap();
        assert_eq!(
            rec.key_attachment().map(|a| a.format),
            Some(Format::Rgba32f)
        );
        assert_eq!(rec.depth, Format::Depth32f);
    }

    #[test]
    fn bad_layouts_name_the_attachment() {
        let mut l = GBufferLayout::freespace_open();
        l.colors[3] =
            AttachmentDesc::new("material", Format::Rgba8ui).with_rule(ResolveRule::Blend);
        let e = l.validate().unwrap_err().to_string();
        assert!(e.contains("material") && e.contains("RGBA8UI"), "{e}");
        let mut l = GBufferLayout::freespace_open();
        l.key = KeySource::Position(ResolveSlot(9));
        assert!(l.validate().is_err());
        let mut l = GBufferLayout::freespace_open();
        l.depth = Format::Rgba8;
        assert!(l.validate().unwrap_err().to_string().contains("depth"));
    }
}
