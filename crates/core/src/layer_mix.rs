//! How the two lit layers are mixed by the second layer's coverage, and the
//! forward target's samples averaged: the blend domain the host declares
//! ([`LayerMix`]) and the GLSL both passes share (`mix_domain.glsl`).

use crate::gl::ShaderSource;
use crate::gl::format::ComponentType;
use crate::lit_output::LitOutput;
use crate::{Error, Result};
use glow::HasContext;

/// What the host's lit values mean, and so how the two lit layers are
/// mixed by the second layer's coverage `α` (and the forward target's
/// samples averaged): in the light a screen would emit for them, as far as
/// the declaration says. GL state cannot tell what a host's values mean;
/// declare it (docs/hosts.md says which to declare for the common engine
/// styles).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum LayerMix {
    /// Inferred (default) where GL state can tell what the values mean,
    /// refused where it cannot:
    /// - an sRGB output the host writes with `GL_FRAMEBUFFER_SRGB` on (GL
    ///   decodes and encodes): linear light;
    /// - an 8-bit (or other fixed-point) output written as stored (`RGBA8`,
    ///   framebuffer 0, or an sRGB image with `GL_FRAMEBUFFER_SRGB` off):
    ///   [`LayerMix::SrgbEncoded`], since such an output holds display
    ///   values (the host's shader encodes, or no tonemap follows);
    /// - a floating-point (HDR) output: its tonemap decides the domain and
    ///   GL cannot see it, so the first call that mixes into it
    ///   ([`MsaaRetrofit::begin_second_layer`](crate::MsaaRetrofit::begin_second_layer),
    ///   `begin_forward`) returns [`Error::LayerMixUndeclared`](crate::Error::LayerMixUndeclared)
    ///   naming the declarations to choose from
    ///   ([`LayerMix::Curve`], [`LayerMix::Tonemapped`], [`LayerMix::Linear`]).
    ///
    /// docs/hosts.md measures each engine style with `Auto` and with each
    /// declaration.
    #[default]
    Auto,
    /// Linear values: `mix(first, second, α)` as the output stores them
    /// (linear light, such as an output a later pass encodes, or values
    /// to be mixed as they are).
    Linear,
    /// sRGB-encoded display values (the host's shader encodes, or writes
    /// display values with no encoding at all, as most LDR programs do;
    /// or an sRGB image written with `GL_FRAMEBUFFER_SRGB` off): decoded,
    /// mixed in linear light, encoded again.
    SrgbEncoded,
    /// In the domain of `T(x) = x / (1 + max3(x))`, mapped back with
    /// `T⁻¹(y) = y / (1 − max3(y))`: a bright layer cannot swamp a dark one,
    /// as after a tonemap (the resolve's `BlendHdr` domain).
    Tonemapped,
    /// In the domain of the host's own tonemap curve: GLSL defining
    /// `vec3 dmsaa_curve(vec3 hdr)` and its inverse
    /// `vec3 dmsaa_curve_inverse(vec3 display)`, with no uniforms.
    Curve(String),
}

/// The blend domain's GLSL, shared with the forward target's resolve:
/// `mix_domain.glsl`.
pub const MIX_DOMAIN_GLSL: &str = include_str!("mix_domain.glsl");

/// The blend domains the mix and the forward resolve are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MixKind {
    Linear,
    Tonemapped,
    Curve,
    SrgbEncoded,
}

impl MixKind {
    pub(crate) fn define(self) -> &'static str {
        match self {
            MixKind::Linear => "MIX_LINEAR",
            MixKind::Tonemapped => "MIX_TONEMAPPED",
            MixKind::Curve => "MIX_CURVE",
            MixKind::SrgbEncoded => "MIX_SRGB_ENCODED",
        }
    }

    /// The domain `mix` blends `output`'s values in, as the crate reads
    /// them (where the host's writes went through GL's sRGB encoding, the
    /// crate's reads are decoded: linear light already), or, for
    /// [`LayerMix::Auto`] into a floating-point output, the error naming
    /// what to declare.
    pub(crate) fn of(mix: &LayerMix, output: &LitOutput) -> Result<MixKind> {
        let float = matches!(output.format.properties().component, ComponentType::Float);
        Ok(match mix {
            LayerMix::Curve(_) => MixKind::Curve,
            LayerMix::Tonemapped => MixKind::Tonemapped,
            LayerMix::Linear => MixKind::Linear,
            LayerMix::SrgbEncoded | LayerMix::Auto if output.srgb_writes => MixKind::Linear,
            LayerMix::SrgbEncoded => MixKind::SrgbEncoded,
            LayerMix::Auto if float => {
                return Err(Error::LayerMixUndeclared {
                    format: output.format.name(),
                });
            }
            LayerMix::Auto => MixKind::SrgbEncoded,
        })
    }
}

/// The shader source up to the blend domain's functions: its define, the
/// host's curve for [`MixKind::Curve`], `mix_domain.glsl`.
pub(crate) fn mix_domain_source(kind: MixKind, curve: Option<&str>) -> ShaderSource {
    let mut source = ShaderSource::new().define(kind.define(), "1");
    if let (MixKind::Curve, Some(curve)) = (kind, curve) {
        source = source.part("LayerMix::Curve", curve);
    }
    source.part("mix_domain.glsl", MIX_DOMAIN_GLSL)
}

/// `GL_FRAMEBUFFER_SRGB` on or off.
pub(crate) fn set_srgb(gl: &glow::Context, on: bool) {
    unsafe {
        if on {
            gl.enable(glow::FRAMEBUFFER_SRGB);
        } else {
            gl.disable(glow::FRAMEBUFFER_SRGB);
        }
    }
}
