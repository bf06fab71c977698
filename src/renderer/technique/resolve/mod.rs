//! The resolve methods (`average`, `front`, `median`, `back`;
//! [`AaMode::Resolve`]): the G-buffer pass draws into the retrofit's
//! multisampled twins, which [`MsaaRetrofit::resolve`] writes back into the
//! G-buffer; lighting is per pixel. With two layers
//! ([`ResolveSettings::layers`](crate::resolve::ResolveSettings::layers))
//! the renderer, as a host of the retrofit, lights the second layer with the
//! same lighting pass, only where the layer's coverage is above 0 (the
//! retrofit's selection stencil attached to the HDR target, or, where the
//! retrofit has none, a mask of its own, `second_layer_mask.frag`), and
//! the retrofit mixes the two lit layers after the tonemap curve.

mod second_layer_mask;
mod slow_path;

use super::contract::{
    ComplexPixelsInput, FrameParts, LightingStep, Setup, Technique, resolve_twins,
};
use crate::frame::Frame as ResolveFrame;
use crate::gl::{
    Attachment, Format, Framebuffer, GlObject, GpuTimer, Handle, Made, Texture2d, TextureRef,
};
use crate::renderer::frame_pass::Pass;
use crate::renderer::options::{AaMode, RenderOptions};
use crate::renderer::pass::shared::{LightTarget, StencilSelect};
use crate::renderer::timing::timed;
use crate::resolve::{ResolveMethod, ResolveSettings, Window};
use crate::retrofit::MsaaRetrofit;
use crate::second_layer::SECOND_LAYER_SELECTED;
use crate::{Error, Result};
use second_layer_mask::SecondLayerMaskPass;
use std::any::Any;

/// The depth-aware resolve of the multisampled G-buffer.
#[derive(Debug, Default)]
pub(crate) struct Resolve {
    /// The second layer's mask program, built when two layers are first used.
    mask: Option<SecondLayerMaskPass>,
    /// The HDR texture with a stencil mask, for the second lighting; made by
    /// the first frame after a change of options.
    targets: Option<MaskedHdr>,
    /// The HDR texture with the retrofit's own selection stencil attached,
    /// where the retrofit has one: the second lighting is masked by it and
    /// the renderer's mask pass is not needed.
    shared: Option<SharedSelection>,
}

/// The HDR texture with the retrofit's selection stencil
/// ([`MsaaRetrofit::second_layer_selection`]).
#[derive(Debug)]
struct SharedSelection {
    /// The selection texture it was made for.
    stencil: glow::Texture,
    fbo: Framebuffer,
}

impl GlObject for SharedSelection {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.fbo.handles(out);
    }
}

/// The HDR texture with a stencil attachment of its own.
#[derive(Debug)]
struct MaskedHdr {
    stencil: Texture2d,
    fbo: Framebuffer,
}

impl GlObject for MaskedHdr {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.stencil.handles(out);
        self.fbo.handles(out);
    }
}

impl MaskedHdr {
    fn new(gl: &glow::Context, hdr: &Texture2d) -> Result<Self> {
        Made::build(gl, |made| {
            let stencil = made.keep(Texture2d::new(
                gl,
                "second layer stencil mask",
                Format::Depth24Stencil8,
                hdr.width,
                hdr.height,
            )?);
            let fbo = made.keep(Framebuffer::new(
                gl,
                "hdr with the second layer's stencil mask",
                &[
                    (Attachment::Color(0), TextureRef::from(hdr)),
                    (Attachment::DepthStencil, TextureRef::from(&stencil)),
                ],
                &[Some(0)],
            )?);
            Ok(MaskedHdr { stencil, fbo })
        })
    }

    fn destroy(self, gl: &glow::Context) {
        self.fbo.destroy(gl);
        self.stencil.destroy(gl);
    }
}

/// The HDR framebuffer with the retrofit's selection `stencil` attached
/// (in `shared`), made again when the retrofit's selection texture changed.
fn shared_selection(
    shared: &mut Option<SharedSelection>,
    gl: &glow::Context,
    hdr: &Texture2d,
    stencil: TextureRef,
) -> Result<glow::Framebuffer> {
    if shared.as_ref().is_some_and(|s| s.stencil != stencil.raw) {
        if let Some(old) = shared.take() {
            old.fbo.destroy(gl);
        }
    }
    if shared.is_none() {
        let fbo = Framebuffer::new(
            gl,
            "hdr with the retrofit's second-layer selection",
            &[
                (Attachment::Color(0), TextureRef::from(hdr)),
                (Attachment::DepthStencil, stencil),
            ],
            &[Some(0)],
        )?;
        *shared = Some(SharedSelection {
            stencil: stencil.raw,
            fbo,
        });
    }
    shared
        .as_ref()
        .map(|s| s.fbo.raw())
        .ok_or_else(|| Error::invalid("the shared selection framebuffer was not made"))
}

fn two_layers(aa: &AaMode) -> bool {
    matches!(aa, AaMode::Resolve(s) if s.layers == 2)
}

/// The bytes two layers add for `options`: the retrofit's second layer
/// (its colours and the first layer's copy in the layout's formats, the
/// copy of depth, the R32F depth, the R16F coverage, the D24S8 selection,
/// the R8 complex flag, the R8UI seed sample where depth has stencil, two
/// lit RGBA16F copies) and the renderer's D24S8 stencil mask, as
/// `MsaaRetrofit::second_layer_bytes` counts them once made.
pub(crate) fn second_layer_bytes(options: &RenderOptions) -> u64 {
    if !two_layers(&options.aa) {
        return 0;
    }
    let layout = &options.layout;
    let colours: u64 = layout
        .colors
        .iter()
        .map(|a| u64::from(a.format.bytes_per_texel()))
        .sum();
    let depth = u64::from(layout.depth.bytes_per_texel());
    let seed = u64::from(layout.depth.has_stencil());
    let per_pixel = 2 * colours + depth + 4 + 2 + 4 + 1 + seed + 2 * 8 + 4;
    per_pixel * u64::from(options.width) * u64::from(options.height)
}

impl Technique for Resolve {
    fn prepare(
        &mut self,
        gl: &glow::Context,
        setup: &Setup<'_>,
        frame: Option<FrameParts<'_>>,
    ) -> Result<()> {
        if !two_layers(&setup.options.aa) {
            return Ok(());
        }
        if self.mask.is_none() {
            self.mask = Some(SecondLayerMaskPass::new(gl)?);
        }
        if let (None, Some(frame)) = (&self.targets, frame) {
            self.targets = Some(MaskedHdr::new(gl, &frame.targets.hdr.texture)?);
        }
        Ok(())
    }

    fn options_changed(&mut self, gl: &glow::Context, _active: bool) {
        if let Some(t) = self.targets.take() {
            t.destroy(gl);
        }
        if let Some(s) = self.shared.take() {
            s.fbo.destroy(gl);
        }
    }

    fn after_geometry(
        &self,
        gl: &glow::Context,
        retrofit: Option<&mut MsaaRetrofit>,
        resolve_frame: &ResolveFrame,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        resolve_twins(gl, retrofit, resolve_frame, timer)
    }

    /// With two layers: the retrofit's three calls around the same
    /// lighting pass, masked to the pixels the second layer covers.
    fn second_lighting(
        &mut self,
        gl: &glow::Context,
        retrofit: Option<&mut MsaaRetrofit>,
        step: &LightingStep<'_>,
        timer: &mut GpuTimer,
    ) -> Result<f64> {
        let Some(retrofit) = retrofit.filter(|_| two_layers(&step.frame.aa)) else {
            return Ok(0.0);
        };
        let (Some(mask), Some(targets)) = (&self.mask, &self.targets) else {
            return Err(Error::invalid(
                "the second layer's mask was not prepared for this frame",
            ));
        };
        let hdr = &step.frame.targets.hdr;
        let output = Some(hdr.fbo.raw());
        timed(gl, timer, || {
            if !retrofit.begin_second_layer(gl, output)? {
                return Ok(());
            }
            let coverage = retrofit.second_layer_coverage().ok_or_else(|| {
                Error::invalid("two layers, but the retrofit has no second layer")
            })?;
            let target = LightTarget {
                fbo: targets.fbo.raw(),
                width: hdr.texture.width,
                height: hdr.texture.height,
                stencil: StencilSelect::All,
            };
            // The retrofit's selection stencil, where it has one, masks the
            // second lighting as it is; else the renderer's own mask.
            let selection = retrofit.second_layer_selection();
            let shared = match selection {
                Some(stencil) => Some(shared_selection(
                    &mut self.shared,
                    gl,
                    &hdr.texture,
                    stencil,
                )?),
                None => None,
            };
            // The renderer's own steps go into the retrofit's profile
            // beside the retrofit's (when profiling).
            let profile = retrofit.profile_mut();
            let masked = match shared {
                Some(fbo) => LightTarget {
                    fbo,
                    stencil: StencilSelect::Equal(SECOND_LAYER_SELECTED),
                    ..target
                },
                None => profile.time(gl, "second layer: the renderer's mask", || {
                    mask.draw(gl, target, step.fullscreen, coverage)
                })?,
            };
            profile.time(gl, "second layer: the renderer's second lighting", || {
                step.light_per_pixel_into(gl, masked)
            })?;
            Ok(retrofit.finish_second_layer(gl, output)?)
        })
    }

    fn memory(&self, options: &RenderOptions) -> u64 {
        second_layer_bytes(options)
    }

    /// The pixels the resolve took its slow path on, found by running the
    /// last frame's resolve again into a scratch mask.
    fn complex_pixels(
        &self,
        gl: &glow::Context,
        input: ComplexPixelsInput<'_>,
    ) -> Result<Option<image::GrayImage>> {
        let Some(retrofit) = input.retrofit else {
            return Ok(None);
        };
        slow_path::slow_path_mask(gl, retrofit, &input.resolve_frame).map(Some)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn destroy(self: Box<Self>, gl: &glow::Context) {
        if let Some(t) = self.targets {
            t.destroy(gl);
        }
        if let Some(s) = self.shared {
            s.fbo.destroy(gl);
        }
        if let Some(m) = self.mask {
            m.destroy(gl);
        }
    }
}

/// What is known of the resolve methods before anything is built.
pub(crate) struct Kind;

impl super::kind::Kind for Kind {
    fn name(&self) -> &'static str {
        "resolve"
    }

    fn methods(&self) -> &'static [&'static str] {
        &["average", "front", "median", "back", "upper-median"]
    }

    fn renders(&self, aa: &AaMode) -> bool {
        matches!(aa, AaMode::Resolve(_))
    }

    fn method_name(&self, aa: &AaMode) -> &'static str {
        match aa {
            AaMode::Resolve(s) => s.method.name(),
            _ => self.name(),
        }
    }

    /// The window (`:hard`, `:smooth`), `:c=F` (when given without `c_in`,
    /// `c_in` becomes `min(2.5, c/2)`), `:c_in=F` (also `c-in`), `:nofast`,
    /// the fast path's opt-in tests (`:position-uniformity`,
    /// `:plane-uniformity`), `:layers=2` and `:normal-threshold=F`.
    fn parse(&self, method: &str, options: &[&str], spec: &str) -> Result<AaMode> {
        let method: ResolveMethod = method.parse()?;
        let mut settings = ResolveSettings {
            method,
            ..ResolveSettings::default()
        };
        let mut c_in_given = false;
        for option in options {
            match option.split_once('=') {
                None if *option == "hard" => settings.window = Window::Hard,
                None if *option == "smooth" => settings.window = Window::Smooth,
                None if *option == "nofast" => settings.fast_path = false,
                None if matches!(*option, "position-uniformity" | "position_uniformity") => {
                    settings.position_uniformity = true
                }
                None if matches!(*option, "plane-uniformity" | "plane_uniformity") => {
                    settings.plane_uniformity = true
                }
                Some(("layers", v)) => {
                    settings.layers = match v.trim() {
                        "1" => 1,
                        "2" => 2,
                        _ => {
                            return Err(Error::invalid(format!(
                                "method `{spec}`: `layers={v}`: 1 or 2 resolved layers are accepted"
                            )));
                        }
                    };
                    if settings.layers == 2 && method == ResolveMethod::Average {
                        return Err(Error::invalid(format!(
                            "method `{spec}`: average weighs every sample, so it has one cluster and no second layer; use front, median, back or upper-median"
                        )));
                    }
                }
                Some(("normal-threshold" | "normal_threshold", v)) => {
                    settings.normal_threshold = parse_number(spec, "normal-threshold", v)?
                }
                Some(("c", v)) => settings.c = parse_number(spec, "c", v)?,
                Some(("c_in" | "c-in", v)) => {
                    settings.c_in = parse_number(spec, "c_in", v)?;
                    c_in_given = true;
                }
                _ => {
                    return Err(Error::invalid(format!(
                        "method `{spec}`: unknown option `:{option}` (the resolve methods take {})",
                        OPTIONS_HELP
                    )));
                }
            }
        }
        if !c_in_given {
            settings.c_in = settings.c_in.min(settings.c * 0.5);
        }
        settings
            .validate()
            .map_err(|e| Error::invalid(format!("method `{spec}`: {e}")))?;
        Ok(AaMode::Resolve(settings))
    }

    fn options_help(&self) -> Option<&'static str> {
        Some(OPTIONS_HELP)
    }

    fn draws_into_twins(&self) -> bool {
        true
    }

    fn lighting_passes(&self, aa: &AaMode) -> Vec<Pass> {
        if two_layers(aa) {
            vec![Pass::Lighting, Pass::SecondLayer]
        } else {
            vec![Pass::Lighting]
        }
    }

    fn build(&self) -> Box<dyn Technique> {
        Box::new(Resolve::default())
    }
}

/// The options of [`Kind::parse`], for error messages.
const OPTIONS_HELP: &str = ":hard, :smooth, :c=F, :c_in=F, :nofast, :position-uniformity, :plane-uniformity, :layers=2, :normal-threshold=F";

/// `value` of option `key` as a finite number.
fn parse_number(spec: &str, key: &str, value: &str) -> Result<f64> {
    value
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            Error::invalid(format!(
                "method `{spec}`: `{key}={value}` is not a finite number"
            ))
        })
}
