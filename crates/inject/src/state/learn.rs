//! `inject --learn`: a first profile written from what the program's GL
//! calls showed (the framebuffers drawn into and their attachments, the
//! matrix uniforms set, the passes in order), for the user to edit.
//! Nothing is retrofitted. Only what was observed is written as a key;
//! what GL calls cannot show (what each attachment holds, how its samples
//! become one, what the lit values mean) is written as a comment marked
//! `?`. A file is always written, or a line says why not: once a G-buffer
//! is found, after a few frames without one, when the context is destroyed,
//! or at the program's exit.

use super::context::{Context, Framebuffer};
use super::run::{say_once, settings};
use std::fmt::Write as _;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static WRITTEN: AtomicBool = AtomicBool::new(false);

/// Frames observed before a profile is written even without a G-buffer.
const FRAMES_BEFORE_GIVING_UP: usize = 3;
static FRAMES: AtomicUsize = AtomicUsize::new(0);

/// At the end of a frame: write the profile once a G-buffer was found (the
/// frame just ended is then a whole frame with it), or after a few frames
/// without one.
pub(super) fn after_frame(cx: &Context) {
    let frames = FRAMES.fetch_add(1, Ordering::Relaxed) + 1;
    if cx.gbuffer.is_none() && frames < FRAMES_BEFORE_GIVING_UP {
        return;
    }
    write(cx, &format!("from frame {frames}"));
}

/// When the program's rendering ends (its context destroyed, or its exit)
/// with no profile written yet: write what was seen.
pub(super) fn at_end(cx: &Context, when: &str) {
    let frames = FRAMES.load(Ordering::Relaxed);
    write(cx, &format!("{when}, after {frames} frame(s)"));
}

/// At exit with no context's state to write from.
pub(super) fn at_end_unseen() {
    if WRITTEN.swap(true, Ordering::Relaxed) {
        return;
    }
    let path = settings()
        .learn
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    say_once(
        "learn",
        &format!(
            "--learn wrote no profile to {path}: no GL context's state was seen (no draw call reached the \
             library)"
        ),
    );
}

fn write(cx: &Context, when: &str) {
    let Some(path) = settings().learn.as_ref() else {
        return;
    };
    if WRITTEN.swap(true, Ordering::Relaxed) {
        return;
    }
    let text = render(cx, when);
    let what = if cx.gbuffer.is_some() || cx.last_gbuffer.is_some() {
        "the G-buffer's signature and the matrix uniforms seen"
    } else {
        "no G-buffer (none was found), only the framebuffers and uniforms seen"
    };
    match std::fs::write(path, text) {
        Ok(()) => say_once(
            "learn",
            &format!(
                "wrote a first profile to {} {when}: it holds {what}; what GL calls cannot show is marked `?` \
                 (unedited, the retrofit runs with the default options: no attachment's meaning, one layer; \
                 edit it as docs/inject.md says)",
                path.display()
            ),
        ),
        Err(e) => say_once(
            "learn",
            &format!("cannot write the profile {}: {e}", path.display()),
        ),
    }
}

/// A TOML string.
fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The profile's text: what was seen, as comments, then the tables of
/// what was observed, with the keys not inferred marked `?`.
pub(super) fn render(cx: &Context, when: &str) -> String {
    let mut out = String::new();
    let program = std::env::args().next().unwrap_or_default();
    let _ = writeln!(
        out,
        "# Written by `deferred-msaa inject --learn` {when} of {program}."
    );
    let _ = writeln!(out, "# Framebuffers drawn into:");
    let mut names: Vec<_> = cx.framebuffers.iter().filter(|(_, f)| f.drawn).collect();
    names.sort_by_key(|(n, _)| **n);
    for (n, f) in &names {
        let _ = writeln!(
            out,
            "#   {n}: {} colour attachment(s) ({}), {} texture(s){}{}{}",
            f.colour_attachments,
            f.formats.join(", "),
            f.colour_textures.len(),
            if f.depth { ", depth" } else { "" },
            if f.layered {
                ", layers of one texture"
            } else {
                ""
            },
            if cx.gbuffer == Some(**n) {
                "  <- the G-buffer"
            } else {
                ""
            }
        );
    }
    let _ = writeln!(
        out,
        "# Matrix uniforms set: {}",
        if cx.matrices_set.is_empty() {
            "none".to_string()
        } else {
            cx.matrices_set.join(", ")
        }
    );
    let passes = if cx.last_frame.is_empty() {
        &cx.passes
    } else {
        &cx.last_frame
    };
    let passes: Vec<String> = passes
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
        "# Keys marked `?` could not be inferred from GL calls: set them (docs/inject.md).\n"
    );
    let gbuffer = cx
        .gbuffer
        .and_then(|g| cx.framebuffers.get(&g))
        .or(cx.last_gbuffer.as_ref());
    if cx.gbuffer.is_none() && gbuffer.is_some() {
        let _ = if cx.gbuffers_deleted > 1 {
            writeln!(
                out,
                "# The G-buffer was deleted {} times: its signature is the last one seen. A G-buffer made\n\
                 # and deleted for each image is retrofitted only with this signature (docs/inject.md).\n",
                cx.gbuffers_deleted
            )
        } else {
            writeln!(
                out,
                "# The G-buffer was deleted before this was written (at the program's end?): its\n\
                 # signature is the one it had.\n"
            )
        };
    }
    match gbuffer {
        Some(f) => gbuffer_tables(&mut out, f),
        None => {
            let _ = writeln!(
                out,
                "# [framebuffer] ? no G-buffer was found: name its signature (colour_textures, depth,\n\
                 # formats) from the framebuffers above.\n"
            );
        }
    }
    let _ = writeln!(out, "[projection]");
    // No uniform named `projection`, but one whose value is a perspective
    // projection times a view that is not the identity: a view-projection
    // product, which the library takes apart.
    let exact_projection = cx
        .matrices_set
        .iter()
        .any(|n| n.eq_ignore_ascii_case("projection"));
    let products: Vec<&String> = cx
        .matrices_set
        .iter()
        .filter(|n| {
            cx.matrix_values
                .get(*n)
                .is_some_and(crate::camera::is_view_projection_product)
        })
        .collect();
    match (exact_projection, products.as_slice()) {
        (false, [name]) => {
            let _ = writeln!(
                out,
                "view_projection_uniform = {}   # its value is a perspective projection times a view",
                quoted(name)
            );
        }
        (false, [_, _, ..]) => {
            let names: Vec<String> = products.iter().map(|n| quoted(n)).collect();
            let _ = writeln!(
                out,
                "# view_projection_uniform = ?  several uniforms held a perspective projection times a view \
                 ({}): a shadow pass's or a reflection's as well as the camera's? name the camera's",
                names.join(", ")
            );
        }
        _ => match (
            exact_projection || !products.is_empty(),
            cx.seen_camera_blocks().as_slice(),
        ) {
            (false, [block]) => {
                let _ = writeln!(
                    out,
                    "block_binding = {}   # the uniform buffer bound there was written a perspective projection\n\
                     offset = {}",
                    block.binding, block.offset
                );
                if let Some(v) = block.view_offset {
                    let _ = writeln!(out, "view_offset = {v}   # and a rigid view beside it");
                }
            }
            (false, [_, _, ..]) => {
                let bindings: Vec<String> = cx
                    .seen_camera_blocks()
                    .iter()
                    .map(|b| format!("{} (byte {})", b.binding, b.offset))
                    .collect();
                let _ = writeln!(
                    out,
                    "# block_binding = ?  uniform blocks at bindings {} each hold a perspective projection: \
                     a shadow or reflection camera beside the view's? name the camera's, with its offset",
                    bindings.join(", ")
                );
            }
            _ => projection_keys(&mut out, cx),
        },
    }
    let _ = writeln!(
        out,
        "\n# [retrofit] ?  not inferred: layers (1 or 2), layer_mix (what the lit values mean:\n\
         # linear, tonemapped, srgb-encoded, or curve with layer_mix_curve), depth_mode; unset, the\n\
         # defaults apply."
    );
    out
}

/// The `uniform` and `view_uniform` keys, from the matrix uniforms' names.
fn projection_keys(out: &mut String, cx: &Context) {
    for (key, word) in [("uniform", "projection"), ("view_uniform", "view")] {
        let exact = cx
            .matrices_set
            .iter()
            .find(|n| n.eq_ignore_ascii_case(word));
        let like = cx
            .matrices_set
            .iter()
            .find(|n| n.to_ascii_lowercase().contains(word));
        let _ = match (exact, like) {
            (Some(name), _) => writeln!(out, "{key} = {}", quoted(name)),
            (None, Some(name)) => writeln!(
                out,
                "# {key} = ?  {} was set: the {word} matrix alone, or a product? name the uniform that holds it",
                quoted(name)
            ),
            (None, None) => writeln!(
                out,
                "# {key} = ?  no matrix uniform named like {word:?} was set; name it, or give a fixed matrix"
            ),
        };
    }
}

/// The G-buffer's signature (observed) and one table per colour texture
/// (its index observed; its meaning and rule not).
fn gbuffer_tables(out: &mut String, f: &Framebuffer) {
    let formats: Vec<String> = f.formats.iter().map(|s| quoted(s)).collect();
    let _ = writeln!(
        out,
        "[framebuffer]\ncolour_textures = {}\ndepth = {}\nformats = [{}]\n",
        f.colour_textures.len(),
        f.depth,
        formats.join(", ")
    );
    for &(index, _) in &f.colour_textures {
        let two_channels = f.channels.iter().any(|&(k, n)| k == index && n == 2);
        let _ = writeln!(
            out,
            "[[attachment]]\nindex = {index}\n\
             # meaning = ?  \"position\" (with world_space), \"normal\" (with encoding), or \"albedo\"/\"other\"\n\
             # rule = ?     \"default\", \"blend\", \"blend-normal\", \"blend-hdr\", \"select\"{}\n",
            if two_channels {
                "\n# two channels: an encoded normal (encoding = \"octahedral-unorm\"?) or a motion vector; with\n\
                 # no rule stated it is taken from one sample (\"select\")"
            } else {
                ""
            }
        );
    }
}
