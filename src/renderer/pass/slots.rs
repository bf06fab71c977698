//! Which colour attachment of the G-buffer holds what the renderer writes,
//! and the shader defines and outputs that follow from it.

use crate::gbuffer::GBufferLayout;
use crate::{Error, Result};

/// The colour attachment numbers of the attachments the renderer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GBufferSlots {
    pub(crate) color: u32,
    pub(crate) position: u32,
    pub(crate) normal: u32,
    /// `None`: the layout has none (the scene-adaptive plan left it out).
    pub(crate) specular: Option<u32>,
    /// `None`: the layout has none (the scene-adaptive plan left it out).
    pub(crate) emissive: Option<u32>,
}

impl GBufferSlots {
    pub(crate) fn of(layout: &GBufferLayout) -> Result<Self> {
        let find = |name: &str| {
            layout.index_of(name).map(|k| k as u32).ok_or_else(|| {
                Error::Layout(format!(
                    "the renderer writes an attachment named `{name}`, which this layout lacks (it has: {})",
                    layout
                        .colors
                        .iter()
                        .map(|a| a.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
        };
        Ok(GBufferSlots {
            color: find("color")?,
            position: find("position")?,
            normal: find("normal")?,
            specular: layout.index_of("specular").map(|k| k as u32),
            emissive: layout.index_of("emissive").map(|k| k as u32),
        })
    }

    /// The model shader's outputs the layout has, with their attachment numbers.
    pub(crate) fn outputs(&self) -> Vec<(&'static str, u32)> {
        let mut outputs = vec![
            ("o_color", self.color),
            ("o_position", self.position),
            ("o_normal", self.normal),
        ];
        outputs.extend(self.specular.map(|k| ("o_specular", k)));
        outputs.extend(self.emissive.map(|k| ("o_emissive", k)));
        outputs
    }

    /// The defines the model and lighting shaders are compiled with for
    /// this attachment set: `GBUFFER_NO_SPECULAR`, `GBUFFER_NO_EMISSIVE`
    /// (none for the full layout).
    pub(crate) fn defines(&self) -> Vec<(String, String)> {
        let mut d = Vec::new();
        if self.specular.is_none() {
            d.push(("GBUFFER_NO_SPECULAR".to_string(), "1".to_string()));
        }
        if self.emissive.is_none() {
            d.push(("GBUFFER_NO_EMISSIVE".to_string(), "1".to_string()));
        }
        d
    }
}
