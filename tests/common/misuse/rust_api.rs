//! The same calls through the Rust API (`MsaaRetrofit`), for the sequences
//! drawn with [`Api::Rust`](super::Api::Rust): the C options read into
//! `RetrofitOptions`, and what its types cannot express left out.

use deferred_msaa::gbuffer::MemoryBudget;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::{
    ColorAttachment, DepthMode, FirstLayerRestore, Frame, LayerMix, MsaaRetrofit, NormalAttachment,
    PositionSpace, RetrofitOptions,
};
use deferred_msaa_capi as c;

use super::calls::*;
use super::sequence::*;

/// `options` as the Rust API takes them; `None` where a value has no Rust
/// form (an enumeration out of range, a curve mix without its text).
pub(super) fn rust_options(o: &c::DmsaaOptions) -> Option<(RetrofitOptions, DepthMode, bool)> {
    let get = |items: &[u32], v: u32| items.contains(&v).then_some(v);
    let attachment = |v: i32| match v {
        -1 => Some(None),
        v if v >= 0 => Some(Some(ColorAttachment(v as u32))),
        _ => None,
    };
    let mut options = RetrofitOptions {
        samples: o.samples,
        ..RetrofitOptions::default()
    };
    options.resolve.layers = o.layers;
    options.position_attachment = attachment(o.position_attachment)?;
    let world = match o.world_space_position {
        0 => false,
        1 => true,
        _ => return None,
    };
    options.position_space = if world {
        PositionSpace::World
    } else {
        PositionSpace::View
    };
    let encoding = [
        NormalEncoding::Xyz,
        NormalEncoding::Unorm,
        NormalEncoding::Octahedral,
        NormalEncoding::OctahedralUnorm,
    ]
    .get(o.normal_encoding as usize)
    .copied()?;
    options.normal_attachment =
        attachment(o.normal_attachment)?.map(|attachment| NormalAttachment {
            attachment,
            encoding,
        });
    options.resolve.method = [
        ResolveMethod::Average,
        ResolveMethod::Front,
        ResolveMethod::Median,
        ResolveMethod::Back,
    ]
    .get(o.method as usize)
    .copied()?;
    options.resolve.window = [Window::Hard, Window::Smooth]
        .get(o.window as usize)
        .copied()?;
    for (k, &rule) in o.rules.iter().enumerate() {
        let rule = [
            None,
            Some(ResolveRule::Blend),
            Some(ResolveRule::BlendNormal),
            Some(ResolveRule::BlendHdr),
            Some(ResolveRule::Select),
        ]
        .get(rule as usize)
        .copied()?;
        if let Some(rule) = rule {
            options.rules.push((ColorAttachment(k as u32), rule));
        }
    }
    options.stencil = [
        StencilCopy::Auto,
        StencilCopy::Export,
        StencilCopy::BitPasses,
        StencilCopy::Blit,
    ]
    .get(o.stencil_copy as usize)
    .copied()?;
    options.layer_mix = match get(&[0, 1, 2], o.layer_mix)? {
        0 => LayerMix::Auto,
        1 => LayerMix::Linear,
        _ => LayerMix::Tonemapped,
    };
    options.restore_first_layer = [
        FirstLayerRestore::Nothing,
        FirstLayerRestore::Everything,
        FirstLayerRestore::DepthAndStencil,
    ]
    .get(o.restore_first_layer as usize)
    .copied()?;
    let strict = o.memory_budget_strict == 1;
    options.memory_budget = match o.memory_budget_bytes {
        c::DMSAA_MEMORY_BUDGET_NONE => None,
        c::DMSAA_MEMORY_BUDGET_DRIVER => Some(MemoryBudget {
            bytes: None,
            strict,
        }),
        bytes => Some(MemoryBudget {
            bytes: Some(bytes),
            strict,
        }),
    };
    let depth_mode = [
        DepthMode::Standard,
        DepthMode::ZeroToOne,
        DepthMode::ReversedZ,
    ]
    .get(o.depth_mode as usize)
    .copied()?;
    Some((options, depth_mode, world))
}

impl Run<'_> {
    /// One Rust API call with the checks around it (as [`Run::call`]; a
    /// panic is caught and is a failure); whether it succeeded.
    pub(super) fn call_rust(
        &mut self,
        index: usize,
        name: &str,
        f: impl FnOnce(&mut Self) -> deferred_msaa::Result<()>,
    ) -> bool {
        let mut outcome = None;
        self.in_rust_call = true;
        self.call(index, name, |run| {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(run)));
            let status = match &result {
                Ok(Ok(())) => c::DmsaaStatus::Ok,
                Ok(Err(_)) => c::DmsaaStatus::InvalidArgument,
                Err(_) => c::DmsaaStatus::Panic,
            };
            outcome = Some(result);
            status
        });
        self.in_rust_call = false;
        match outcome {
            Some(Ok(Ok(()))) => true,
            Some(Ok(Err(e))) => {
                let message = e.to_string();
                let driver_log = matches!(
                    e,
                    deferred_msaa::Error::ShaderCompile { .. }
                        | deferred_msaa::Error::ProgramLink { .. }
                );
                if message.trim().is_empty() || (message.contains('\n') && !driver_log) {
                    self.fail(index, format!("{name} failed with the message {message:?}"));
                }
                if std::env::var_os("DEFERRED_MSAA_VERBOSE").is_some() {
                    eprintln!("call {index}: {name}: {message}");
                }
                false
            }
            Some(Err(_)) => {
                self.fail(index, format!("{name} panicked"));
                false
            }
            None => false,
        }
    }

    /// The Rust API's form of `op`; `false` for the host's own steps,
    /// which [`Run::step`] takes as they are. Steps with no Rust form do
    /// nothing.
    pub(super) fn step_rust(&mut self, index: usize, op: &Op) -> bool {
        let gl = self.gl;
        let live = |run: &Self, which: &Which| match which {
            Which::Slot(k) if run.retrofits[*k].is_some() => Some(*k),
            _ => None,
        };
        match op {
            Op::New {
                fbo,
                options,
                missing: None,
            } => {
                let Some(k) = self.retrofits.iter().position(Option::is_none) else {
                    return true;
                };
                let c_options = options.apply();
                let (Some((options, _, _)), Some(fbo)) = (
                    rust_options(&c_options),
                    std::num::NonZeroU32::new(self.host.fbo_arg(*fbo)),
                ) else {
                    return true;
                };
                let before = deferred_msaa::gl::live_objects().total();
                let ok = self.call_rust(index, "MsaaRetrofit::new", |run| {
                    let r = MsaaRetrofit::new(gl, glow::NativeFramebuffer(fbo), &options)?;
                    run.retrofits[k] = Some((r, c_options));
                    Ok(())
                });
                if !ok && deferred_msaa::gl::live_objects().total() != before {
                    self.fail(index, "a failed MsaaRetrofit::new left GL objects".into());
                }
            }
            // A loader is the Rust host's own business.
            Op::New { .. } => {}
            Op::Destroy(which) => {
                if let Some(k) = live(self, which) {
                    self.call_rust(index, "MsaaRetrofit::destroy", |run| {
                        if let Some((r, _)) = run.retrofits[k].take() {
                            r.destroy(gl);
                        }
                        Ok(())
                    });
                }
            }
            Op::Getters(which) => {
                if let Some(k) = live(self, which) {
                    self.call_rust(index, "MsaaRetrofit getters", |run| {
                        if let Some((r, _)) = &run.retrofits[k] {
                            let _ = (r.framebuffer(), r.samples(), r.second_layer_selection());
                        }
                        Ok(())
                    });
                }
            }
            Op::Resolve(which, kind, with_view) => {
                if *kind != Projection::Null {
                    self.resolve_rust(index, which, *kind, *with_view);
                }
            }
            Op::Begin(which, output, _) | Op::Finish(which, output) => {
                let Some(k) = live(self, which) else {
                    return true;
                };
                let output = std::num::NonZeroU32::new(self.host.fbo_arg(*output))
                    .map(glow::NativeFramebuffer);
                let begin = matches!(op, Op::Begin(..));
                let name = if begin {
                    "MsaaRetrofit::begin_second_layer"
                } else {
                    "MsaaRetrofit::finish_second_layer"
                };
                self.call_rust(index, name, |run| match run.retrofits[k].as_mut() {
                    Some((r, _)) if begin => r.begin_second_layer(gl, output).map(|_| ()),
                    Some((r, _)) => r.finish_second_layer(gl, output),
                    None => Ok(()),
                });
            }
            Op::SetOptions(which, options) => {
                let Some(k) = live(self, which) else {
                    return true;
                };
                let c_options = options.apply();
                let Some((options, _, _)) = rust_options(&c_options) else {
                    return true;
                };
                self.call_rust(index, "MsaaRetrofit::set_options", |run| {
                    match run.retrofits[k].as_mut() {
                        Some((r, o)) => {
                            r.set_options(gl, &options)?;
                            *o = c_options;
                            Ok(())
                        }
                        None => Ok(()),
                    }
                });
            }
            Op::Refresh(which) => {
                if let Some(k) = live(self, which) {
                    self.call_rust(index, "MsaaRetrofit::refresh", |run| {
                        match run.retrofits[k].as_mut() {
                            Some((r, _)) => r.refresh(gl),
                            None => Ok(()),
                        }
                    });
                }
            }
            Op::Draw(which) => {
                if let Some(k) = live(self, which) {
                    if let Some(fbo) = self.begin_rust(index, k) {
                        self.draw_into(fbo);
                    }
                }
            }
            Op::Recover(which) => {
                self.host.put_back(gl);
                let Some(k) = live(self, which) else {
                    return true;
                };
                let made_for = self.retrofits[k].as_ref().map(|(r, _)| r.host().fbo);
                if made_for != Some(self.host.fbo) {
                    // The host made its framebuffer again under another name:
                    // the retrofit refuses, saying its framebuffer is gone.
                    let mut message = String::new();
                    let refused =
                        !self.call_rust(index, "MsaaRetrofit::refresh (framebuffer gone)", |run| {
                            match run.retrofits[k].as_mut().map(|(r, _)| r.refresh(gl)) {
                                Some(Err(e)) => {
                                    message = e.to_string();
                                    Err(e)
                                }
                                _ => Ok(()),
                            }
                        });
                    if !refused || !message.contains("no longer a framebuffer object") {
                        self.fail(
                            index,
                            format!("refresh with the framebuffer deleted: {message:?}"),
                        );
                    }
                    return true;
                }
                let ok = self.call_rust(index, "MsaaRetrofit::refresh (recovery)", |run| match run
                    .retrofits[k]
                    .as_mut()
                {
                    Some((r, _)) => r.refresh(gl),
                    None => Ok(()),
                });
                if !ok {
                    self.fail(
                        index,
                        "no recovery: MsaaRetrofit::refresh failed with the G-buffer put back"
                            .into(),
                    );
                    return true;
                }
                let expected = self.expected_frame();
                if let Some(fbo) = self.begin_rust(index, k) {
                    self.draw_into(fbo);
                }
                if self.resolve_rust(index, which, Projection::Perspective, true) {
                    self.check_frame(index, &expected);
                } else {
                    self.fail(
                        index,
                        "no recovery: MsaaRetrofit::resolve failed after refresh".into(),
                    );
                }
            }
            Op::Frame(which) => {
                self.step_rust(index, &Op::Draw(*which));
                self.resolve_rust(index, which, Projection::Perspective, true);
                self.step_rust(index, &Op::Begin(*which, Fbo::Light, false));
                self.step_rust(index, &Op::Finish(*which, Fbo::Light));
            }
            Op::Dirty(_)
            | Op::Set(_)
            | Op::Reallocate(_)
            | Op::Delete(_)
            | Op::PutBack
            | Op::Recreate => {
                return false;
            }
        }
        true
    }

    /// A Rust API `begin_frame` of retrofit `k`: the framebuffer to draw
    /// the frame into, where it succeeded.
    fn begin_rust(&mut self, index: usize, k: usize) -> Option<glow::Framebuffer> {
        let gl = self.gl;
        let mut fbo = None;
        self.call_rust(index, "MsaaRetrofit::begin_frame", |run| {
            if let Some((r, _)) = run.retrofits[k].as_mut() {
                fbo = Some(r.begin_frame(gl)?);
            }
            Ok(())
        });
        fbo
    }

    /// A Rust API resolve of `which`'s retrofit (if it has one); whether it
    /// succeeded.
    pub(super) fn resolve_rust(
        &mut self,
        index: usize,
        which: &Which,
        kind: Projection,
        view: bool,
    ) -> bool {
        let gl = self.gl;
        let Which::Slot(k) = *which else {
            return false;
        };
        let Some(options) = self.retrofits[k].as_ref().map(|(_, o)| *o) else {
            return false;
        };
        let Some((_, depth_mode, _)) = rust_options(&options) else {
            return false;
        };
        let (projection, v) = matrices(kind, &options);
        let mut frame = Frame::from_matrix(projection).with_depth_mode(depth_mode);
        if view {
            frame = frame.with_view(v);
        }
        self.call_rust(index, "MsaaRetrofit::resolve", |run| {
            match run.retrofits[k].as_mut() {
                Some((r, _)) => r.resolve(gl, &frame),
                None => Ok(()),
            }
        })
    }
}
