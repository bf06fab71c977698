//! The timing: the retrofit's resolve against `glBlitFramebuffer`, each
//! method's runs interleaved, with their statistics.

use crate::common::quantile;
use crate::setup::*;
use deferred_msaa::gbuffer::GBufferLayout;
use deferred_msaa::gl::{GpuTimer, TimerKind, check_error};
use deferred_msaa::{Error, MsaaRetrofit};
use deferred_msaa_testkit::Host;
use glow::HasContext;
use std::time::Instant;

#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Method {
    ResolveFast,
    ResolveNoFast,
    Blit,
}

impl Method {
    pub(crate) const ALL: [Method; 3] = [Method::ResolveFast, Method::ResolveNoFast, Method::Blit];
    pub(crate) fn key(self) -> &'static str {
        match self {
            Method::ResolveFast => "resolve_fast",
            Method::ResolveNoFast => "resolve_nofast",
            Method::Blit => "blit",
        }
    }
    pub(crate) fn label(self, colors: usize) -> String {
        match self {
            Method::ResolveFast => "resolve (median, smooth), fast path on".into(),
            Method::ResolveNoFast => "resolve (median, smooth), fast path off".into(),
            Method::Blit => format!("{colors}x glBlitFramebuffer + depth"),
        }
    }
}

/// One layout's retrofit at one count, ready to time.
pub(crate) struct Timed {
    pub(crate) key: &'static str,
    pub(crate) label: &'static str,
    pub(crate) layout: GBufferLayout,
    pub(crate) host: Host,
    pub(crate) msaa: MsaaRetrofit,
}

/// The hardware resolve: one blit per colour attachment, then depth (a
/// multisampled depth blit takes one sample; GL_NEAREST as required).
pub(crate) fn blit_resolve(gl: &glow::Context, t: &Timed, width: u32, height: u32) {
    let (w, h) = (width as i32, height as i32);
    let colors = t.layout.colors.len() as u32;
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(t.msaa.framebuffer()));
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(t.host.fbo.raw()));
        for k in 0..colors {
            gl.read_buffer(glow::COLOR_ATTACHMENT0 + k);
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0 + k]);
            gl.blit_framebuffer(
                0,
                0,
                w,
                h,
                0,
                0,
                w,
                h,
                glow::COLOR_BUFFER_BIT,
                glow::NEAREST,
            );
        }
        gl.blit_framebuffer(
            0,
            0,
            w,
            h,
            0,
            0,
            w,
            h,
            glow::DEPTH_BUFFER_BIT,
            glow::NEAREST,
        );
        // Both framebuffers' mappings back as their owners made them.
        let all: Vec<u32> = (0..colors).map(|k| glow::COLOR_ATTACHMENT0 + k).collect();
        gl.draw_buffers(&all);
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    }
}

#[derive(Clone, Copy)]
pub(crate) struct Stats {
    pub(crate) median: f64,
    pub(crate) q1: f64,
    pub(crate) q3: f64,
    pub(crate) min: f64,
    pub(crate) max: f64,
}

pub(crate) fn stats(times: &[f64]) -> Option<Stats> {
    if times.is_empty() {
        return None;
    }
    let mut s = times.to_vec();
    s.sort_by(f64::total_cmp);
    Some(Stats {
        median: quantile(&s, 0.5),
        q1: quantile(&s, 0.25),
        q3: quantile(&s, 0.75),
        min: s[0],
        max: s[s.len() - 1],
    })
}

/// The timings of one (count, layout) case.
pub(crate) struct CaseResult {
    pub(crate) samples: u32,
    pub(crate) layout: &'static str,
    pub(crate) label: &'static str,
    pub(crate) gbuffer: Vec<String>,
    pub(crate) colors: usize,
    /// Per method: wall times, query times.
    pub(crate) wall: Vec<Vec<f64>>,
    pub(crate) query: Vec<Vec<f64>>,
}

impl CaseResult {
    pub(crate) fn stats(&self, kind: TimerKind) -> Vec<Option<Stats>> {
        let all = match kind {
            TimerKind::GlTimeElapsed => &self.query,
            TimerKind::FinishWallClock => &self.wall,
        };
        all.iter().map(|t| stats(t)).collect()
    }
    /// Resolve/blit medians, fast path on and off.
    pub(crate) fn ratios(&self, kind: TimerKind) -> Option<(f64, f64)> {
        let st = self.stats(kind);
        let (fast, nofast, blit) = (st[0]?, st[1]?, st[2]?);
        Some((fast.median / blit.median, nofast.median / blit.median))
    }
}

/// Time both layouts at `samples`, interleaved round-robin over every
/// (layout, method) pair; each round starts one pair later.
#[allow(clippy::too_many_arguments)]
pub(crate) fn time_count(
    gl: &glow::Context,
    samples: u32,
    layouts_here: &[(&'static str, &'static str, GBufferLayout)],
    model: &Model,
    args: &Args,
    wall: &mut GpuTimer,
    query: &mut Option<GpuTimer>,
    started: Instant,
) -> Result<Vec<CaseResult>, Error> {
    let mut timed: Vec<Timed> = Vec::new();
    let built = (|| -> Result<(), Error> {
        for (key, label, layout) in layouts_here {
            let host = host_for(gl, layout, model)?;
            let msaa =
                match MsaaRetrofit::new(gl, host.fbo.raw(), &options_for(layout, samples, false)) {
                    Ok(m) => m,
                    Err(e) => {
                        host.destroy(gl);
                        return Err(e);
                    }
                };
            let mut t = Timed {
                key,
                label,
                layout: layout.clone(),
                host,
                msaa,
            };
            // Both permutations compiled now, so switching later only picks one.
            let ready = draw_into(gl, &t.host, t.msaa.begin_frame(gl)?, model).and_then(|()| {
                let real = t.msaa.samples();
                if real == samples {
                    Ok(())
                } else {
                    Err(Error::invalid(format!("asked for {samples}x, got {real}x")))
                }
            });
            timed.push(t);
            ready?;
            let last = timed.len() - 1;
            let fast = options_for(&timed[last].layout, samples, true);
            timed[last].msaa.set_options(gl, &fast)?;
        }
        Ok(())
    })();
    let result = built.and_then(|()| {
        let frame = model.frame();
        let items: Vec<(usize, Method)> = (0..timed.len())
            .flat_map(|l| Method::ALL.iter().map(move |&m| (l, m)))
            .collect();
        let mut once =
            |timed: &mut [Timed], (l, m): (usize, Method)| -> Result<(f64, Option<f64>), Error> {
                let t = &mut timed[l];
                let want_fast = m == Method::ResolveFast;
                if m != Method::Blit && t.msaa.options().resolve.fast_path != want_fast {
                    let o = options_for(&t.layout, samples, want_fast);
                    t.msaa.set_options(gl, &o)?;
                }
                // A frame as a host draws it, outside the timed stretch: the
                // resolve requires begin_frame and a cleared, drawn twin.
                let fbo = t.msaa.begin_frame(gl)?;
                draw_into(gl, &t.host, fbo, model)?;
                wall.begin(gl);
                if let Some(q) = query.as_mut() {
                    q.begin(gl);
                }
                let ran = match m {
                    Method::ResolveFast | Method::ResolveNoFast => t.msaa.resolve(gl, &frame),
                    Method::Blit => {
                        blit_resolve(gl, t, model.width, model.height);
                        Ok(())
                    }
                };
                // The query is ended even on an error, so the next count can begin one.
                let q_ms = query.as_mut().map(|q| q.end(gl));
                let w_ms = wall.end(gl);
                ran?;
                check_error(gl, &format!("{} {} at {samples}x", t.key, m.key()))?;
                Ok((w_ms, q_ms))
            };
        for _ in 0..args.warmup {
            for &item in &items {
                once(&mut timed, item)?;
            }
        }
        let mut wall_ms = vec![Vec::with_capacity(args.runs); items.len()];
        let mut query_ms = vec![Vec::with_capacity(args.runs); items.len()];
        let every = (args.runs / 4).max(1);
        for round in 0..args.runs {
            for i in 0..items.len() {
                let k = (round + i) % items.len();
                let (w, q) = once(&mut timed, items[k])?;
                wall_ms[k].push(w);
                if let Some(q) = q {
                    query_ms[k].push(q);
                }
            }
            if (round + 1) % every == 0 || round + 1 == args.runs {
                eprintln!(
                    "[time] {samples}x: round {}/{} ({:.0} s)",
                    round + 1,
                    args.runs,
                    started.elapsed().as_secs_f64()
                );
            }
        }
        Ok(timed
            .iter()
            .enumerate()
            .map(|(l, t)| {
                let of = |all: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
                    Method::ALL
                        .iter()
                        .map(|&m| {
                            items
                                .iter()
                                .position(|&it| it == (l, m))
                                .map(|k| all[k].clone())
                                .unwrap_or_default()
                        })
                        .collect()
                };
                CaseResult {
                    samples,
                    layout: t.key,
                    label: t.label,
                    gbuffer: describe_layout(&t.layout),
                    colors: t.layout.colors.len(),
                    wall: of(&wall_ms),
                    query: of(&query_ms),
                }
            })
            .collect())
    });
    for t in timed {
        t.msaa.destroy(gl);
        t.host.destroy(gl);
    }
    result
}
