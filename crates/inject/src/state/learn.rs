//! `inject --learn`: a first profile written from one observed frame (the
//! framebuffers drawn into and their attachments, the matrix uniforms set,
//! the passes in order), for the user to edit. Nothing is retrofitted.

use super::context::Context;
use super::run::{say_once, settings};
use crate::profile::{Attachment, FramebufferMatch, Profile, Projection, Retrofit};
use std::fmt::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};

static WRITTEN: AtomicBool = AtomicBool::new(false);

/// Frames observed before a profile is written even without a G-buffer.
const FRAMES_BEFORE_GIVING_UP: usize = 3;
static FRAMES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// At the end of a frame: write the profile once a G-buffer was found (the
/// frame just ended is then a whole frame with it), or after a few frames
/// without one.
pub(crate) fn after_frame(cx: &Context) {
    let Some(path) = settings().learn.as_ref() else {
        return;
    };
    let frames = FRAMES.fetch_add(1, Ordering::Relaxed) + 1;
    if WRITTEN.load(Ordering::Relaxed) || (cx.gbuffer.is_none() && frames < FRAMES_BEFORE_GIVING_UP)
    {
        return;
    }
    WRITTEN.store(true, Ordering::Relaxed);
    let text = render(cx, frames);
    match std::fs::write(path, text) {
        Ok(()) => say_once(
            "learn",
            &format!(
                "wrote a first profile to {} (edit it: docs/inject.md)",
                path.display()
            ),
        ),
        Err(e) => say_once(
            "learn",
            &format!("cannot write the profile {}: {e}", path.display()),
        ),
    }
}

/// The profile's text: what was seen, as comments, then the tables.
pub(crate) fn render(cx: &Context, frame: usize) -> String {
    let mut out = String::new();
    let program = std::env::args().next().unwrap_or_default();
    let _ = writeln!(
        out,
        "# Written by `deferred-msaa inject --learn` from frame {frame} of {program}."
    );
    let _ = writeln!(out, "# Framebuffers drawn into:");
    let mut names: Vec<_> = cx.framebuffers.iter().filter(|(_, f)| f.drawn).collect();
    names.sort_by_key(|(n, _)| **n);
    for (n, f) in &names {
        let _ = writeln!(
            out,
            "#   {n}: {} colour attachment(s) ({}), {} texture(s){}{}",
            f.colour_attachments,
            f.formats.join(", "),
            f.colour_textures.len(),
            if f.depth { ", depth" } else { "" },
            if cx.gbuffer == Some(**n) {
                "  <- the G-buffer"
            } else {
                ""
            }
        );
    }
    let _ = writeln!(out, "# Matrix uniforms set: {}", cx.matrices_set.join(", "));
    let passes: Vec<String> = cx
        .last_frame
        .iter()
        .map(|p| {
            format!(
                "framebuffer {} (program {}, {} draw(s))",
                p.framebuffer, p.program, p.draws
            )
        })
        .collect();
    let _ = writeln!(
        out,
        "# Passes of the frame, in order: {}",
        passes.join(", ")
    );
    let _ = writeln!(
        out,
        "# What the attachments hold cannot be seen from GL calls: set each one's meaning\n\
         # (\"position\" with world_space, \"normal\" with encoding) and rule, and what the\n\
         # lit values mean (layer_mix), as docs/inject.md says.\n"
    );
    let gbuffer = cx.gbuffer.and_then(|g| cx.framebuffers.get(&g));
    let profile = Profile {
        framebuffer: gbuffer.map(|f| FramebufferMatch {
            colour_textures: f.colour_textures.len() as u32,
            depth: f.depth,
            formats: f.formats.clone(),
        }),
        attachments: gbuffer
            .map(|f| {
                f.colour_textures
                    .iter()
                    .map(|&(index, _)| Attachment {
                        index,
                        meaning: Some("other".into()),
                        rule: Some("default".into()),
                        ..Attachment::default()
                    })
                    .collect()
            })
            .unwrap_or_default(),
        projection: Some(Projection {
            uniform: Some(pick(&cx.matrices_set, "projection")),
            view_uniform: Some(pick(&cx.matrices_set, "view")),
            ..Projection::default()
        }),
        retrofit: Some(Retrofit {
            layers: Some(1),
            layer_mix: Some("auto".into()),
            ..Retrofit::default()
        }),
        lighting: None,
    };
    if gbuffer.is_none() {
        let _ = writeln!(
            out,
            "# No G-buffer was found: add a [framebuffer] table naming its signature.\n"
        );
    }
    out.push_str(&toml::to_string(&profile).unwrap_or_default());
    out
}

/// The uniform whose name contains `word` (case-insensitive), else `word`.
fn pick(names: &[String], word: &str) -> String {
    names
        .iter()
        .find(|n| n.eq_ignore_ascii_case(word))
        .or_else(|| names.iter().find(|n| n.to_ascii_lowercase().contains(word)))
        .cloned()
        .unwrap_or_else(|| word.to_string())
}
