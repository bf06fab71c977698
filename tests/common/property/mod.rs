//! The property test over random host G-buffers (the generator is the test
//! kit's `random_host`), shared by both tiers: the fast tier runs a few
//! hundred seeds, the slow tier more than a thousand.
//!
//! For each host: `MsaaRetrofit::new` succeeds or refuses with a typed
//! one-line error naming the attachment and the GL enum. On success a
//! geometry pass of two constant-value faces (one over the whole image,
//! one triangle in front of part of it) is drawn into the retrofit's
//! framebuffer and resolved, and inside the faces every attachment holds
//! bit for bit what the same pass drawn straight into the host's
//! framebuffer holds; integer attachments and the stencil hold one face's
//! value exactly at the edges too; what no draw buffer reaches is
//! untouched. The host's GL state (and its framebuffer's set-up) is the
//! same around `new`, `resolve`, the second layer's calls, `set_options`
//! and `refresh` after a resize, `glGetError` is clean after each, and the
//! crate's live objects are back to zero after `destroy`.
//!
//! The runner is the kit's seeded generator with a shrinker of its own
//! (docs/testing.md says why not the `proptest` crate): a failing host is
//! made smaller (attachments dropped, sizes halved, depth and options
//! simplified) while it still fails, and printed with the command that
//! replays its seed.

use deferred_msaa::gl::live_objects;
use deferred_msaa::{Error, MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_testkit::Rng;
use deferred_msaa_testkit::random_host::{HostIncomplete, HostSpec, Limits, RandomHost, Storage};
use glow::HasContext;
use std::collections::BTreeMap;

mod frame;
mod geometry;

use frame::{around, clutter, frame_checks, gl_error};
use geometry::Geometry;

/// The variable that replays one seed.
pub const SEED_VAR: &str = "DEFERRED_MSAA_SEED";

/// The variable that prints every seed's host and verdict.
pub const VERBOSE_VAR: &str = "DEFERRED_MSAA_VERBOSE";

/// Every refusal the crate can answer a host layout or its options with:
/// a name, and the words of its message that tell it apart.
pub const REFUSALS: &[(&str, &str)] = &[
    ("driver reports texture 0", "the driver reports texture 0"),
    (
        "driver reports renderbuffer 0",
        "the driver reports renderbuffer 0",
    ),
    ("layered attachment", "is attached layered"),
    ("mip level other than 0", "attached at mip level"),
    (
        "multisampled texture",
        "is already a GL_TEXTURE_2D_MULTISAMPLE",
    ),
    ("texture target", "only GL_TEXTURE_2D and layers"),
    ("multisampled renderbuffer", "is already multisampled"),
    ("default framebuffer", "it is the default framebuffer's"),
    ("unexpected object type", "unexpected object type"),
    ("format without a twin", "no multisampled twin can hold it"),
    ("no depth attachment", "has no depth attachment"),
    ("nothing attached", "has nothing attached at all"),
    ("not a depth format", "not a depth format"),
    ("no colour attachments", "has no colour attachments"),
    (
        "too many colour attachments",
        "colour attachments are supported",
    ),
    ("sizes differ", "all attachments must have one size"),
    (
        "depth format on a colour point",
        "a depth format on a colour attachment",
    ),
    ("nothing drawn", "is in the host framebuffer's draw buffers"),
    ("integer rule", "integer values can only be selected"),
    ("rule for an empty point", "a rule is given for it"),
    ("empty position point", "named as the position attachment"),
    (
        "integer position",
        "the depth key needs a floating-point position",
    ),
    ("empty normal point", "named as the normal attachment"),
    ("integer normal", "the normal test needs a float"),
    (
        "blend-normal on unsigned normalised",
        "`blend-normal` renormalises the stored vector",
    ),
    (
        "signed normal encoding on unsigned normalised",
        "is for signed components, but an unsigned normalised format",
    ),
    (
        "not multisampled by the driver",
        "cannot render to a multisampled texture",
    ),
    ("twin missing", "its multisampled twin is missing"),
    (
        "no draw buffer for the stencil copy",
        "the stencil copy's reference sample",
    ),
    ("two layers: draw buffers", "two layers need at least"),
    ("sample count", "MSAA is not supported for"),
    ("memory budget", "over the memory budget"),
    ("stencil copy unsupported", "copying the host's stencil by"),
];

/// The refusals no generated host can reach, and why (docs/testing.md
/// repeats them).
pub const UNREACHABLE: &[(&str, &str)] = &[
    (
        "driver reports texture 0",
        "an attached texture always has a name; the check guards against a broken driver",
    ),
    (
        "driver reports renderbuffer 0",
        "likewise for renderbuffers",
    ),
    (
        "default framebuffer",
        "a glow::Framebuffer is never 0, so the default framebuffer cannot be passed",
    ),
    (
        "unexpected object type",
        "GL 3.2-4.5 define no attachment object type besides NONE, TEXTURE, RENDERBUFFER and FRAMEBUFFER_DEFAULT",
    ),
    (
        "not a depth format",
        "a colour image at the depth point makes the host's framebuffer incomplete",
    ),
    (
        "depth format on a colour point",
        "a depth image at a colour point makes the host's framebuffer incomplete",
    ),
    (
        "twin missing",
        "an internal invariant: the twins are made from the same list the check walks",
    ),
    (
        "nothing attached",
        "a framebuffer with nothing attached is incomplete, which the generator counts as the host's bug",
    ),
];

/// Why a refusal cannot be reached on this context, where that depends on
/// the driver: its limits, the formats it multisamples, its extensions.
pub fn driver_dependent(gl: &glow::Context, name: &str, limits: Limits) -> Option<String> {
    use deferred_msaa::gl::{Capabilities, Format};
    use deferred_msaa::resolve::StencilCopy;
    match name {
        "too many colour attachments" if limits.color_attachments <= 8 => Some(format!(
            "GL_MAX_COLOR_ATTACHMENTS is {}, no more than the resolve's 8",
            limits.color_attachments
        )),
        "not multisampled by the driver" => {
            let offered = |f: Format| {
                Capabilities::sample_counts_for(gl, f)
                    .iter()
                    .any(|&n| n > 1)
            };
            let none: Vec<_> = Format::ALL
                .iter()
                .filter(|f| !f.is_depth())
                .filter(|&&f| !(offered(f) || f.multisample_stand_in().is_some_and(offered)))
                .collect();
            none.is_empty().then(|| {
                "the driver multisamples every colour format the crate knows, or its stand-in"
                    .to_string()
            })
        }
        // The second layer's resolve splits into as many draws as the draw
        // buffers need; it refuses only below its coverage, depth, seed
        // sample and one colour.
        "two layers: draw buffers" if limits.draw_buffers.min(limits.color_attachments) >= 4 => {
            Some(format!(
                "GL_MAX_DRAW_BUFFERS is {}: the second layer's resolve takes as many draws as its outputs need",
                limits.draw_buffers
            ))
        }
        "stencil copy unsupported" => (StencilCopy::Export.on(gl).is_ok()
            && StencilCopy::BitPasses.on(gl).is_ok())
        .then(|| "the context offers stencil export and stencil texturing".to_string()),
        _ => None,
    }
}

/// What one host came to.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Retrofitted, and every check held.
    Retrofitted,
    /// Refused, well (one line, the attachment and the enum named), for this
    /// reason ([`REFUSALS`]' name).
    Refused(String),
    /// The host's own framebuffer was incomplete (a host bug, not a case).
    HostIncomplete(String),
    /// Some check failed: one line each.
    Failed(Vec<String>),
}

/// Counts over a run of seeds.
#[derive(Debug, Default)]
pub struct Summary {
    /// Hosts retrofitted with every check holding.
    pub retrofitted: usize,
    /// Refusals by reason.
    pub refused: BTreeMap<String, usize>,
    /// Incomplete hosts by status.
    pub incomplete: BTreeMap<String, usize>,
    /// Failures: seed, the shrunk host, the lines.
    pub failures: Vec<(u64, HostSpec, Vec<String>)>,
}

impl Summary {
    /// The report the tiers print.
    pub fn report(&self, gl: &glow::Context, limits: Limits) -> String {
        let refused: usize = self.refused.values().sum();
        let incomplete: usize = self.incomplete.values().sum();
        let version = unsafe { gl.get_parameter_string(glow::VERSION) };
        let mut out = format!(
            "random hosts on OpenGL {version}: {} retrofitted, {refused} refused, {incomplete} host-incomplete, {} failed\n",
            self.retrofitted,
            self.failures.len()
        );
        out += "refused, by reason:\n";
        for (reason, n) in &self.refused {
            out += &format!("  {n:5}  {reason}\n");
        }
        out += "host incomplete (not cases), by status:\n";
        for (status, n) in &self.incomplete {
            out += &format!("  {n:5}  {status}\n");
        }
        let missing = self.unreached(gl, limits);
        if !missing.is_empty() {
            out += &format!("refusals not reached: {}\n", missing.join(", "));
        }
        out
    }

    /// The refusals no case reached that are neither unreachable nor
    /// out of this driver's reach.
    pub fn unreached(&self, gl: &glow::Context, limits: Limits) -> Vec<&'static str> {
        REFUSALS
            .iter()
            .map(|(name, _)| *name)
            .filter(|name| !self.refused.contains_key(*name))
            .filter(|name| !UNREACHABLE.iter().any(|(n, _)| n == name))
            .filter(|name| driver_dependent(gl, name, limits).is_none())
            .collect()
    }
}

/// Run `seeds` (or only the one `DEFERRED_MSAA_SEED` names), shrinking and
/// printing each failure with its replay command; `tier` is the test's
/// `cargo test` arguments for that command, up to `--nocapture`.
pub fn run_seeds(ctx: &HeadlessContext, seeds: std::ops::Range<u64>, tier: &str) -> Summary {
    let gl = ctx.gl();
    let limits = Limits::of(gl);
    let seeds: Vec<u64> = match std::env::var(SEED_VAR) {
        Ok(s) => vec![
            s.trim()
                .parse()
                .unwrap_or_else(|_| panic!("{SEED_VAR}={s} is not a seed")),
        ],
        Err(_) => seeds.collect(),
    };
    let mut summary = Summary::default();
    for seed in seeds {
        let spec = HostSpec::generate(seed, limits);
        let verdict = check(ctx, &spec);
        if std::env::var_os(VERBOSE_VAR).is_some() {
            eprintln!("seed {seed}: {verdict:?}\n{}", spec.describe());
        }
        match verdict {
            Verdict::Retrofitted => summary.retrofitted += 1,
            Verdict::Refused(r) => *summary.refused.entry(r).or_default() += 1,
            Verdict::HostIncomplete(s) => *summary.incomplete.entry(s).or_default() += 1,
            Verdict::Failed(lines) => {
                let shrunk = shrink(ctx, spec);
                let lines = match check(ctx, &shrunk) {
                    Verdict::Failed(l) => l,
                    _ => lines,
                };
                eprintln!(
                    "seed {seed} failed:\n  {}\nreplay: {SEED_VAR}={seed} cargo test {tier} --nocapture\nshrunk to:\n{}",
                    lines.join("\n  "),
                    shrunk.describe()
                );
                summary.failures.push((seed, shrunk, lines));
            }
        }
    }
    summary
}

fn options(s: &mut HostSpec, other: bool) -> &mut RetrofitOptions {
    if other {
        &mut s.other_options
    } else {
        &mut s.options
    }
}

/// Simpler hosts than `spec`: one change each.
fn simpler(spec: &HostSpec) -> Vec<HostSpec> {
    let mut out = Vec::new();
    let mut push = |f: &dyn Fn(&mut HostSpec)| {
        let mut s = spec.clone();
        f(&mut s);
        if s != *spec {
            out.push(s);
        }
    };
    for i in 0..spec.colors.len() {
        push(&|s| {
            let p = s.colors.remove(i).point;
            for b in &mut s.draw_buffers {
                if *b == Some(p) {
                    *b = None;
                }
            }
        });
    }
    push(&|s| s.draw_buffers.retain(Option::is_some));
    push(&|s| {
        while s.draw_buffers.len() > 1 && s.draw_buffers.last() == Some(&None) {
            s.draw_buffers.pop();
        }
    });
    push(&|s| s.depth = None);
    push(&|s| {
        if let Some(d) = &mut s.depth {
            d.storage = Storage::Texture;
        }
    });
    push(&|s| {
        s.width = s.width.div_ceil(2);
        s.resized = (s.width, s.height);
    });
    push(&|s| {
        s.height = s.height.div_ceil(2);
        s.resized = (s.width, s.height);
    });
    push(&|s| s.resized = (s.width, s.height));
    for i in 0..spec.colors.len() {
        push(&|s| s.colors[i].storage = Storage::Texture);
        push(&|s| s.colors[i].size = None);
        push(&|s| {
            s.colors[i].format =
                deferred_msaa_testkit::random_host::HostFormat::named("GL_RGBA8").unwrap()
        });
    }
    push(&|s| s.other_options = s.options.clone());
    for other in [false, true] {
        push(&|s| options(s, other).resolve.layers = 1);
        push(&|s| options(s, other).rules.clear());
        push(&|s| options(s, other).position_attachment = None);
        push(&|s| options(s, other).normal_attachment = None);
        push(&|s| options(s, other).memory_budget = None);
        push(&|s| {
            let o = options(s, other);
            o.resolve = deferred_msaa::resolve::ResolveSettings {
                layers: o.resolve.layers,
                ..Default::default()
            };
        });
    }
    out
}

/// The smallest host found from `spec` that still fails.
pub fn shrink(ctx: &HeadlessContext, spec: HostSpec) -> HostSpec {
    let mut best = spec;
    for _ in 0..200 {
        let next = simpler(&best)
            .into_iter()
            .find(|s| matches!(check(ctx, s), Verdict::Failed(_)));
        match next {
            Some(s) => best = s,
            None => break,
        }
    }
    best
}

/// The refusal's name in [`REFUSALS`], or why it is not a good refusal.
fn classify(error: &Error, spec: &HostSpec) -> Result<String, String> {
    let text = error.to_string();
    if !matches!(
        error,
        Error::Retrofit { .. }
            | Error::UnsupportedFormat { .. }
            | Error::UnsupportedSampleCount { .. }
            | Error::MemoryBudget { .. }
            | Error::Unsupported { .. }
    ) {
        return Err(format!("a failure, not a refusal: {text}"));
    }
    if text.lines().count() != 1 {
        return Err(format!("the refusal is not one line: {text}"));
    }
    let hex = text.match_indices("0x").any(|(i, _)| {
        !text[..i].ends_with(|c: char| c.is_ascii_alphanumeric())
            && text[i + 2..].starts_with(|c: char| c.is_ascii_hexdigit())
    });
    if hex {
        return Err(format!("the refusal names an enum in hex: {text}"));
    }
    let name = REFUSALS
        .iter()
        .find(|(_, words)| text.contains(words))
        .map(|(name, _)| name.to_string())
        .ok_or_else(|| format!("not a refusal the crate states: {error:?}: {text}"))?;
    let names_point = |a: &str| {
        a.starts_with("GL_") && a.ends_with("ATTACHMENT")
            || a.starts_with("GL_COLOR_ATTACHMENT")
            || a == "GL_DRAW_BUFFER0"
    };
    match error {
        Error::Retrofit { attachment, .. } if !names_point(attachment) => {
            return Err(format!("the refusal names no attachment point: {text}"));
        }
        Error::UnsupportedFormat {
            attachment, format, ..
        } => {
            if !names_point(attachment) {
                return Err(format!("the refusal names no attachment point: {text}"));
            }
            // The format as the host asked for it, by its GL name.
            let asked = attachment
                .strip_prefix("GL_COLOR_ATTACHMENT")
                .and_then(|n| n.parse::<u32>().ok())
                .and_then(|n| spec.color(n))
                .map(|c| c.format.name)
                .or_else(|| {
                    (!attachment.starts_with("GL_COLOR"))
                        .then(|| spec.depth.as_ref().map(|d| d.format.name))
                        .flatten()
                });
            match asked {
                Some(asked) if asked == format => {}
                _ => {
                    return Err(format!(
                        "the refusal does not name the format the host asked for ({asked:?}): {text}"
                    ));
                }
            }
        }
        Error::Retrofit { .. }
        | Error::UnsupportedSampleCount { .. }
        | Error::MemoryBudget { .. }
        | Error::Unsupported { .. } => {}
        other => return Err(format!("a failure, not a refusal: {other:?}: {text}")),
    }
    Ok(name)
}

/// Everything one host is put through.
pub fn check(ctx: &HeadlessContext, spec: &HostSpec) -> Verdict {
    let gl = ctx.gl();
    let mut failures = Vec::new();
    // Counted from what is live before (0 but after a leaking case), so
    // that a leak is blamed on the case that made it.
    let start = live_objects();
    let mut host = match RandomHost::build(gl, spec) {
        Ok(h) => h,
        Err(HostIncomplete(status)) => return Verdict::HostIncomplete(status),
    };
    let geometry = Geometry::new(gl, &host);
    let mut rng = Rng::new(spec.seed ^ 0xC1u64);
    clutter(gl, &mut rng, &host, &geometry);
    let made = around(gl, "MsaaRetrofit::new", &host, &mut failures, || {
        MsaaRetrofit::new(gl, host.fbo, &spec.options)
    });
    let verdict = match made {
        Err(e) => {
            let live = live_objects();
            if live != start {
                failures.push(format!(
                    "GL objects left after a refusal: {live:?}, {start:?} before"
                ));
            }
            match classify(&e, spec) {
                Ok(reason) => Verdict::Refused(reason),
                Err(line) => {
                    failures.push(line);
                    Verdict::Failed(Vec::new())
                }
            }
        }
        Ok(mut msaa) => {
            frame_checks(
                gl,
                "first frame",
                &mut rng,
                &host,
                &geometry,
                &mut msaa,
                &mut failures,
            );
            clutter(gl, &mut rng, &host, &geometry);
            let changed = around(gl, "set_options", &host, &mut failures, || {
                msaa.set_options(gl, &spec.other_options)
            });
            if let Err(e) = &changed {
                // A refusal of the new options leaves the old ones working.
                if let Err(line) = classify(e, spec) {
                    failures.push(format!("set_options: {line}"));
                }
            }
            frame_checks(
                gl,
                "after set_options",
                &mut rng,
                &host,
                &geometry,
                &mut msaa,
                &mut failures,
            );
            let (w, h) = spec.resized;
            host.resize(gl, w, h);
            clutter(gl, &mut rng, &host, &geometry);
            let refreshed = around(gl, "refresh", &host, &mut failures, || msaa.refresh(gl));
            match refreshed {
                Ok(()) => frame_checks(
                    gl,
                    "after resize and refresh",
                    &mut rng,
                    &host,
                    &geometry,
                    &mut msaa,
                    &mut failures,
                ),
                Err(e) => {
                    if let Err(line) = classify(&e, spec) {
                        failures.push(format!("refresh: {line}"));
                    }
                }
            }
            around(gl, "destroy", &host, &mut failures, || msaa.destroy(gl));
            let live = live_objects();
            if live != start {
                failures.push(format!(
                    "GL objects left after destroy: {live:?}, {start:?} before"
                ));
            }
            Verdict::Retrofitted
        }
    };
    geometry.destroy(gl);
    host.destroy(gl);
    gl_error(gl, "the host's clean-up", &mut failures);
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    if failures.is_empty() {
        verdict
    } else {
        Verdict::Failed(failures)
    }
}
