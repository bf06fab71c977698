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

use super::gl_state::GlState;
use deferred_msaa::gl::live_objects;
use deferred_msaa::{Error, Frame, MsaaRetrofit, RetrofitOptions};
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_testkit::Rng;
use deferred_msaa_testkit::random_host::{
    DepthPoint, HostIncomplete, HostSpec, Limits, RandomHost, Storage, ValueKind,
};
use glow::HasContext;
use std::collections::BTreeMap;

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

/// The host framebuffer's own set-up: what is attached where, its draw
/// buffers and read buffer. Read with the bindings put back.
fn fbo_setup(gl: &glow::Context, fbo: glow::Framebuffer) -> Vec<i32> {
    unsafe {
        let previous = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING) as u32;
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
        let max = gl
            .get_parameter_i32(glow::MAX_COLOR_ATTACHMENTS)
            .clamp(1, 32) as u32;
        let mut out = Vec::new();
        for point in (0..max)
            .map(|i| glow::COLOR_ATTACHMENT0 + i)
            .chain([glow::DEPTH_ATTACHMENT, glow::STENCIL_ATTACHMENT])
        {
            let p = |pname| {
                gl.get_framebuffer_attachment_parameter_i32(glow::READ_FRAMEBUFFER, point, pname)
            };
            let kind = p(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE);
            out.push(kind);
            if kind != glow::NONE as i32 {
                out.push(p(glow::FRAMEBUFFER_ATTACHMENT_OBJECT_NAME));
                if kind == glow::TEXTURE as i32 {
                    out.push(p(glow::FRAMEBUFFER_ATTACHMENT_TEXTURE_LEVEL));
                    out.push(p(glow::FRAMEBUFFER_ATTACHMENT_TEXTURE_LAYER));
                }
            }
        }
        out.push(gl.get_parameter_i32(glow::READ_BUFFER));
        let draw = gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING) as u32;
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(fbo));
        for i in 0..gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(1, 32) as u32 {
            out.push(gl.get_parameter_i32(glow::DRAW_BUFFER0 + i));
        }
        gl.bind_framebuffer(
            glow::DRAW_FRAMEBUFFER,
            std::num::NonZeroU32::new(draw).map(glow::NativeFramebuffer),
        );
        gl.bind_framebuffer(
            glow::READ_FRAMEBUFFER,
            std::num::NonZeroU32::new(previous).map(glow::NativeFramebuffer),
        );
        out
    }
}

/// One image of the host's framebuffer read back: 4 values a pixel (or 1
/// for depth and stencil), as bytes.
#[derive(Clone, Debug, PartialEq)]
struct Plane {
    name: String,
    /// Bytes per pixel.
    bpp: usize,
    raw: Vec<u8>,
    /// Whether the resolve selects one sample of it (integer, stencil).
    selected: bool,
    /// Whether the geometry pass writes it.
    drawn: bool,
    /// How far a 32-bit unsigned normalised depth may move: the resolve
    /// writes depth through `gl_FragDepth`, a float of 24 bits, so the
    /// 32-bit value comes back within one float step of its own, never bit
    /// for bit (0 for every other plane: exact).
    slack: f32,
}

impl Plane {
    fn texel(&self, i: usize) -> &[u8] {
        &self.raw[i * self.bpp..(i + 1) * self.bpp]
    }

    /// Pixel `i` of `other` holds this plane's value at pixel `j`.
    fn same(&self, j: usize, other: &Plane, i: usize) -> bool {
        let (a, b) = (self.texel(j), other.texel(i));
        if self.slack == 0.0 {
            return a == b;
        }
        let f = |t: &[u8]| f32::from_ne_bytes([t[0], t[1], t[2], t[3]]);
        (f(a) - f(b)).abs() <= self.slack
    }
}

/// The geometry pass of a random host: two faces of constant values.
struct Geometry {
    program: glow::Program,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    face: Option<glow::UniformLocation>,
    /// The front triangle in window coordinates of a unit square ((0,0)
    /// bottom left, (1,1) top right).
    triangle: [[f32; 2]; 3],
}

/// How far the front triangle's side face reaches out from its first edge,
/// in pixels: a sliver that a pixel's samples meet now and then, so that
/// pixels of three surfaces (the front face, its side, the back face) occur
/// as a thin box's silhouette has them.
const SIDE_PX: f32 = 0.35;

/// The value a face writes to attachment `k` (as a GLSL expression).
fn face_value(seed: u64, k: usize, face: u32, kind: ValueKind) -> String {
    let mut rng = Rng::new(seed.wrapping_mul(1_000_003) ^ (k as u64 * 131 + face as u64 * 7 + 1));
    let mut v = [0f32; 4];
    let mut i = [0i64; 4];
    for c in 0..4 {
        v[c] = match kind {
            ValueKind::Unorm => rng.unit(),
            ValueKind::Snorm => rng.range(-1.0, 1.0),
            ValueKind::Float { unsigned: true } => rng.range(0.0, 8.0),
            _ => rng.range(-8.0, 8.0),
        };
        // Small enough for every integer format (RGB10_A2UI's alpha has 2 bits).
        i[c] = match kind {
            ValueKind::Int if c == 3 => rng.below(3) as i64 - 1,
            ValueKind::Int => rng.below(81) as i64 - 40,
            _ if c == 3 => rng.below(4) as i64,
            _ => rng.below(81) as i64,
        };
    }
    match kind {
        ValueKind::Int => format!("ivec4({}, {}, {}, {})", i[0], i[1], i[2], i[3]),
        ValueKind::Uint => format!("uvec4({}u, {}u, {}u, {}u)", i[0], i[1], i[2], i[3]),
        _ => format!("vec4({:.8}, {:.8}, {:.8}, {:.8})", v[0], v[1], v[2], v[3]),
    }
}

const VERTEX: &str = "#version 150
in vec3 position;
void main() { gl_Position = vec4(position, 1.0); }
";

impl Geometry {
    fn new(gl: &glow::Context, host: &RandomHost) -> Geometry {
        let spec = &host.spec;
        let mut decls = String::new();
        let mut writes = [String::new(), String::new()];
        let mut outputs = Vec::new();
        for (i, b) in spec.draw_buffers.iter().enumerate() {
            let Some(point) = b else { continue };
            let k = spec.colors.iter().position(|c| c.point == *point).unwrap();
            let kind = host.kinds[k];
            let ty = match kind {
                ValueKind::Int => "ivec4",
                ValueKind::Uint => "uvec4",
                _ => "vec4",
            };
            decls += &format!("out {ty} o{i};\n");
            for face in 0..2 {
                writes[face as usize] +=
                    &format!("    o{i} = {};\n", face_value(spec.seed, k, face, kind));
            }
            outputs.push((i as u32, format!("o{i}")));
        }
        let fragment = format!(
            "#version 150\nuniform int face;\n{decls}void main() {{\n  if (face == 0) {{\n{}  }} else {{\n{}  }}\n}}\n",
            writes[0], writes[1]
        );
        let mut rng = Rng::new(spec.seed ^ 0x5eed_face);
        let triangle = [
            [rng.range(0.05, 0.45), rng.range(0.05, 0.45)],
            [rng.range(0.55, 0.95), rng.range(0.1, 0.6)],
            [rng.range(0.2, 0.8), rng.range(0.6, 0.95)],
        ];
        let ndc = |p: [f32; 2]| [p[0] * 2.0 - 1.0, p[1] * 2.0 - 1.0];
        let mut vertices: Vec<f32> = Vec::new();
        // The back face: the whole image, two triangles, at depth 0.5.
        for p in [[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]] {
            vertices.extend([p[0], p[1], 0.5]);
        }
        for p in triangle {
            let q = ndc(p);
            vertices.extend([q[0], q[1], -0.25]);
        }
        // The side face: a quad along the first edge, receding from the
        // front face's depth outwards by SIDE_PX pixels. It writes the front
        // face's values (one object's material), at other depths.
        // At the larger of the host's two sizes (it is resized once): no
        // wider than SIDE_PX at either.
        let w = host.width.max(spec.resized.0) as f32;
        let h = host.height.max(spec.resized.1) as f32;
        let centre = [0, 1].map(|c| (triangle[0][c] + triangle[1][c] + triangle[2][c]) / 3.0);
        let (a, b) = (triangle[0], triangle[1]);
        let (dx, dy) = ((b[0] - a[0]) * w, (b[1] - a[1]) * h);
        let len = (dx * dx + dy * dy).sqrt().max(1e-6);
        let mut out = [dy / len, -dx / len];
        let away = [(a[0] - centre[0]) * w, (a[1] - centre[1]) * h];
        if out[0] * away[0] + out[1] * away[1] < 0.0 {
            out = [-out[0], -out[1]];
        }
        let shifted = |p: [f32; 2]| [p[0] + out[0] * SIDE_PX / w, p[1] + out[1] * SIDE_PX / h];
        let side = [(a, -0.25), (b, -0.25), (shifted(b), -0.15)];
        let side2 = [(a, -0.25), (shifted(b), -0.15), (shifted(a), -0.15)];
        for (p, z) in side.into_iter().chain(side2) {
            let q = ndc(p);
            vertices.extend([q[0], q[1], z]);
        }
        unsafe {
            let program = gl.create_program().unwrap();
            let mut shaders = Vec::new();
            for (stage, source) in [
                (glow::VERTEX_SHADER, VERTEX),
                (glow::FRAGMENT_SHADER, fragment.as_str()),
            ] {
                let shader = gl.create_shader(stage).unwrap();
                gl.shader_source(shader, source);
                gl.compile_shader(shader);
                assert!(
                    gl.get_shader_compile_status(shader),
                    "{}\n{source}",
                    gl.get_shader_info_log(shader)
                );
                gl.attach_shader(program, shader);
                shaders.push(shader);
            }
            gl.bind_attrib_location(program, 0, "position");
            for (i, name) in &outputs {
                gl.bind_frag_data_location(program, *i, name);
            }
            gl.link_program(program);
            assert!(
                gl.get_program_link_status(program),
                "{}",
                gl.get_program_info_log(program)
            );
            for s in shaders {
                gl.detach_shader(program, s);
                gl.delete_shader(s);
            }
            let vao = gl.create_vertex_array().unwrap();
            let vbo = gl.create_buffer().unwrap();
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&vertices),
                glow::STATIC_DRAW,
            );
            gl.enable_vertex_attrib_array(0);
            gl.vertex_attrib_pointer_f32(0, 3, glow::FLOAT, false, 12, 0);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            let face = gl.get_uniform_location(program, "face");
            Geometry {
                program,
                vao,
                vbo,
                face,
                triangle,
            }
        }
    }

    /// The host's geometry pass into `fbo`, with the state it sets itself.
    fn draw(&self, gl: &glow::Context, host: &RandomHost, fbo: glow::Framebuffer) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.viewport(0, 0, host.width as i32, host.height as i32);
            for cap in [
                glow::SCISSOR_TEST,
                glow::BLEND,
                glow::CULL_FACE,
                glow::RASTERIZER_DISCARD,
                glow::SAMPLE_MASK,
                glow::POLYGON_OFFSET_FILL,
                glow::FRAMEBUFFER_SRGB,
                glow::SAMPLE_ALPHA_TO_COVERAGE,
                glow::SAMPLE_ALPHA_TO_ONE,
            ] {
                gl.disable(cap);
            }
            gl.enable(glow::MULTISAMPLE);
            gl.polygon_mode(glow::FRONT_AND_BACK, glow::FILL);
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.clear_depth_f64(1.0);
            gl.clear_stencil(0);
            gl.clear(glow::DEPTH_BUFFER_BIT | glow::STENCIL_BUFFER_BIT);
            gl.enable(glow::STENCIL_TEST);
            gl.stencil_op(glow::KEEP, glow::KEEP, glow::REPLACE);
            gl.use_program(Some(self.program));
            gl.bind_vertex_array(Some(self.vao));
            // The back face, then the front triangle with its side face.
            for (face, reference, first, count) in [(0, 0x5A, 0, 3), (1, 0xA5, 3, 9)] {
                gl.stencil_func(glow::ALWAYS, reference, 0xFF);
                gl.uniform_1_i32(self.face.as_ref(), face);
                gl.draw_arrays(glow::TRIANGLES, first, count);
            }
            gl.disable(glow::STENCIL_TEST);
        }
    }

    /// Which face pixel `(x, y)` of a `w` x `h` image lies wholly inside
    /// (0 the back, 1 the front triangle), or `None` on an edge.
    fn face_of(&self, x: u32, y: u32, w: u32, h: u32) -> Option<u32> {
        let c = [x as f32 + 0.5, y as f32 + 0.5];
        let t = self.triangle.map(|p| [p[0] * w as f32, p[1] * h as f32]);
        // Signed distances to the three edges (positive inside, for a
        // counter-clockwise triangle; the sign is fixed by the winding).
        let area =
            (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
        let sign = area.signum();
        let mut min = f32::INFINITY;
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = (dx * dx + dy * dy).sqrt().max(1e-6);
            let d = sign * (dx * (c[1] - a[1]) - dy * (c[0] - a[0])) / len;
            min = min.min(d);
        }
        // Half a pixel's diagonal, with room for rounding, and the side
        // face beyond the first edge.
        let margin = 0.75 + SIDE_PX;
        if min > margin {
            Some(1)
        } else if min < -margin {
            Some(0)
        } else {
            None
        }
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_program(self.program);
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.vbo);
        }
    }
}

/// Every image of the host's framebuffer, read back.
fn read_planes(gl: &glow::Context, host: &RandomHost) -> Vec<Plane> {
    let spec = &host.spec;
    let n = (host.width * host.height) as usize;
    let mut planes = Vec::new();
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(host.fbo));
        gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.pixel_store_i32(glow::PACK_ROW_LENGTH, 0);
        let read = |name: String, format: u32, ty: u32, bpp: usize, selected, drawn| {
            let mut raw = vec![0u8; n * bpp];
            gl.read_pixels(
                0,
                0,
                host.width as i32,
                host.height as i32,
                format,
                ty,
                glow::PixelPackData::Slice(Some(&mut raw)),
            );
            Plane {
                name,
                bpp,
                raw,
                selected,
                drawn,
                slack: 0.0,
            }
        };
        for (c, kind) in spec.colors.iter().zip(&host.kinds) {
            gl.read_buffer(glow::COLOR_ATTACHMENT0 + c.point);
            let (format, ty) = match kind {
                ValueKind::Int => (glow::RGBA_INTEGER, glow::INT),
                ValueKind::Uint => (glow::RGBA_INTEGER, glow::UNSIGNED_INT),
                _ => (glow::RGBA, glow::FLOAT),
            };
            planes.push(read(
                format!("GL_COLOR_ATTACHMENT{} ({})", c.point, c.format.name),
                format,
                ty,
                16,
                kind.is_integer(),
                spec.draw_buffers.contains(&Some(c.point)),
            ));
        }
        if let Some(d) = &spec.depth {
            if d.point != DepthPoint::Stencil {
                planes.push(read(
                    format!("depth ({})", d.format.name),
                    glow::DEPTH_COMPONENT,
                    glow::FLOAT,
                    4,
                    false,
                    true,
                ));
                let p = |pname| {
                    gl.get_framebuffer_attachment_parameter_i32(
                        glow::READ_FRAMEBUFFER,
                        glow::DEPTH_ATTACHMENT,
                        pname,
                    )
                };
                if p(glow::FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE) == 32
                    && p(glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE)
                        == glow::UNSIGNED_NORMALIZED as i32
                {
                    if let Some(depth) = planes.last_mut() {
                        depth.slack = f32::EPSILON;
                    }
                }
            }
        }
        if spec.has_stencil() {
            planes.push(read(
                "stencil".into(),
                glow::STENCIL_INDEX,
                glow::UNSIGNED_BYTE,
                1,
                true,
                true,
            ));
        }
        gl.read_buffer(glow::COLOR_ATTACHMENT0);
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    }
    planes
}

/// Compare the retrofit's planes with the host's own render.
fn compare(
    what: &str,
    geometry: &Geometry,
    host: &RandomHost,
    reference: &[Plane],
    got: &[Plane],
    failures: &mut Vec<String>,
) {
    let (w, h) = (host.width, host.height);
    let faces: Vec<Option<u32>> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| geometry.face_of(x, y, w, h))
        .collect();
    for (r, g) in reference.iter().zip(got) {
        // The value each face has wholly inside it, for the edges' check.
        let inside: Vec<Option<&[u8]>> = (0..2)
            .map(|f| faces.iter().position(|&p| p == Some(f)).map(|i| r.texel(i)))
            .collect();
        let mut bad = 0;
        let mut first = None;
        for (i, face) in faces.iter().enumerate() {
            let ok = if !r.drawn || face.is_some() {
                r.same(i, g, i)
            } else if r.selected {
                // On an edge a selected value is one sample's: one face's.
                match (inside[0], inside[1]) {
                    (Some(a), Some(b)) => g.texel(i) == a || g.texel(i) == b,
                    _ => true,
                }
            } else {
                true
            };
            if !ok {
                bad += 1;
                first.get_or_insert(i);
            }
        }
        if let Some(i) = first {
            let rule = if !r.drawn {
                "untouched"
            } else if faces[i].is_some() {
                "bit for bit inside a face"
            } else {
                "one face's value at an edge"
            };
            failures.push(format!(
                "{what}: {}: {bad} pixels not {rule}; first at ({}, {}): host {:?}, retrofit {:?}",
                r.name,
                i as u32 % w,
                i as u32 / w,
                r.texel(i),
                g.texel(i)
            ));
        }
    }
}

/// The host's own state, random: what it leaves bound and enabled when it
/// calls the retrofit.
fn clutter(gl: &glow::Context, rng: &mut Rng, host: &RandomHost, geometry: &Geometry) {
    unsafe {
        let fbo = match rng.below(3) {
            0 => None,
            _ => Some(host.fbo),
        };
        gl.bind_framebuffer(glow::FRAMEBUFFER, fbo);
        let flip = |rng: &mut Rng, cap: u32, percent: u32| {
            if rng.below(100) < percent {
                gl.enable(cap)
            } else {
                gl.disable(cap)
            }
        };
        flip(rng, glow::BLEND, 40);
        flip(rng, glow::SCISSOR_TEST, 40);
        flip(rng, glow::CULL_FACE, 40);
        flip(rng, glow::DEPTH_TEST, 50);
        flip(rng, glow::STENCIL_TEST, 30);
        flip(rng, glow::FRAMEBUFFER_SRGB, 30);
        flip(rng, glow::RASTERIZER_DISCARD, 10);
        flip(rng, glow::POLYGON_OFFSET_FILL, 10);
        flip(rng, glow::SAMPLE_ALPHA_TO_COVERAGE, 10);
        gl.blend_func(glow::SRC_ALPHA, glow::ONE_MINUS_SRC_ALPHA);
        gl.scissor(1, 1, 3, 2);
        gl.viewport(2, 1, 7, 5);
        gl.cull_face(if rng.below(2) == 0 {
            glow::FRONT
        } else {
            glow::BACK
        });
        gl.depth_func(glow::LEQUAL);
        gl.depth_mask(rng.below(2) == 0);
        gl.stencil_func(glow::EQUAL, 3, 0x0F);
        gl.stencil_mask(0x3C);
        gl.color_mask(true, rng.below(2) == 0, true, false);
        if rng.below(10) == 0 {
            gl.polygon_mode(glow::FRONT_AND_BACK, glow::LINE);
        }
        gl.clear_color(0.25, 0.5, 0.125, 1.0);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, [1, 2, 4, 8][rng.below(4) as usize]);
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, [1, 2, 4, 8][rng.below(4) as usize]);
        gl.use_program(Some(geometry.program));
        gl.bind_vertex_array(Some(geometry.vao));
        gl.bind_buffer(glow::ARRAY_BUFFER, Some(geometry.vbo));
        gl.active_texture(glow::TEXTURE0 + rng.below(4));
    }
}

fn gl_error(gl: &glow::Context, after: &str, failures: &mut Vec<String>) {
    let e = unsafe { gl.get_error() };
    if e != glow::NO_ERROR {
        failures.push(format!("glGetError is 0x{e:04X} after {after}"));
        while unsafe { gl.get_error() } != glow::NO_ERROR {}
    }
}

/// Call `f` in the host's random state and check what it left: the host's
/// state, its framebuffer's set-up, glGetError.
fn around<T>(
    gl: &glow::Context,
    what: &str,
    host: &RandomHost,
    failures: &mut Vec<String>,
    f: impl FnOnce() -> T,
) -> T {
    let setup = fbo_setup(gl, host.fbo);
    let before = GlState::capture(gl);
    let out = f();
    let after = GlState::capture(gl);
    gl_error(gl, what, failures);
    for d in before.differences(&after) {
        failures.push(format!("{what} changed the host's state: {d}"));
    }
    if fbo_setup(gl, host.fbo) != setup {
        failures.push(format!("{what} changed the host framebuffer's set-up"));
    }
    out
}

fn frame(host: &RandomHost) -> Frame {
    let projection = deferred_msaa_testkit::projection::perspective(
        0.8,
        host.width as f64 / host.height as f64,
        0.5,
        Some(100.0),
    );
    let mut identity = [0f32; 16];
    for i in 0..4 {
        identity[i * 5] = 1.0;
    }
    deferred_msaa_testkit::projection::frame(&projection, false).with_view(identity)
}

/// A lit output of the host's size and its "lighting": a constant colour.
struct Lit {
    texture: glow::Texture,
    fbo: glow::Framebuffer,
}

/// What the host's first and second lighting write.
const LIT: [[u8; 4]; 2] = [[51, 102, 204, 255], [255, 0, 102, 255]];

impl Lit {
    fn new(gl: &glow::Context, w: u32, h: u32) -> Lit {
        unsafe {
            let texture = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D, Some(texture));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                w as i32,
                h as i32,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_texture(glow::TEXTURE_2D, None);
            let fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(texture),
                0,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            Lit { texture, fbo }
        }
    }

    /// The host's lighting: its output cleared to `colour` with its own
    /// state (a clear is all the property needs of it: the mix must keep
    /// the first lighting's value wherever a pixel has one cluster).
    fn light(&self, gl: &glow::Context, w: u32, h: u32, colour: [u8; 4]) {
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            gl.viewport(0, 0, w as i32, h as i32);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::RASTERIZER_DISCARD);
            gl.color_mask(true, true, true, true);
            let c = colour.map(|v| v as f32 / 255.0);
            gl.clear_buffer_f32_slice(glow::COLOR, 0, &c);
        }
    }

    fn read(&self, gl: &glow::Context, w: u32, h: u32) -> Vec<u8> {
        let mut raw = vec![0u8; (w * h * 4) as usize];
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.fbo));
            gl.read_buffer(glow::COLOR_ATTACHMENT0);
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
            gl.read_pixels(
                0,
                0,
                w as i32,
                h as i32,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut raw)),
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        raw
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.texture);
        }
    }
}

/// Draw, resolve and compare; with two layers, the three calls around the
/// host's lighting too.
fn frame_checks(
    gl: &glow::Context,
    what: &str,
    rng: &mut Rng,
    host: &RandomHost,
    geometry: &Geometry,
    msaa: &mut MsaaRetrofit,
    failures: &mut Vec<String>,
) {
    geometry.draw(gl, host, host.fbo);
    let reference = read_planes(gl, host);
    geometry.draw(gl, host, msaa.framebuffer());
    clutter(gl, rng, host, geometry);
    let resolved = around(gl, &format!("{what}: resolve"), host, failures, || {
        msaa.resolve(gl, &frame(host))
    });
    if let Err(e) = resolved {
        failures.push(format!("{what}: resolve failed: {e}"));
        return;
    }
    let planes = read_planes(gl, host);
    compare(what, geometry, host, &reference, &planes, failures);
    if msaa.options().resolve.layers != 2 {
        return;
    }
    let (w, h) = (host.width, host.height);
    let lit = Lit::new(gl, w, h);
    lit.light(gl, w, h, LIT[0]);
    let first_lit = lit.read(gl, w, h);
    clutter(gl, rng, host, geometry);
    let begun = around(
        gl,
        &format!("{what}: begin_second_layer"),
        host,
        failures,
        || msaa.begin_second_layer(gl, Some(lit.fbo)),
    );
    match begun {
        Ok(true) => {}
        Ok(false) => failures.push(format!("{what}: begin_second_layer did nothing")),
        Err(e) => failures.push(format!("{what}: begin_second_layer failed: {e}")),
    }
    lit.light(gl, w, h, LIT[1]);
    clutter(gl, rng, host, geometry);
    let finished = around(
        gl,
        &format!("{what}: finish_second_layer"),
        host,
        failures,
        || msaa.finish_second_layer(gl, Some(lit.fbo)),
    );
    if let Err(e) = finished {
        failures.push(format!("{what}: finish_second_layer failed: {e}"));
    }
    let restore = msaa.options().restore_first_layer;
    if restore.restores_depth() {
        let back = read_planes(gl, host);
        let depth_or_stencil = |p: &Plane| p.name == "stencil" || p.name.starts_with("depth (");
        for (a, b) in planes
            .iter()
            .zip(&back)
            .filter(|(a, _)| restore.restores_colors() || depth_or_stencil(a))
        {
            if a.raw != b.raw {
                failures.push(format!(
                    "{what}: {} is not the first layer again after finish_second_layer",
                    a.name
                ));
            }
        }
    }
    // Where a pixel has one cluster the mix is the first lighting's, and
    // inside a face it has one.
    let mixed = lit.read(gl, w, h);
    for i in 0..(w * h) as usize {
        if geometry.face_of(i as u32 % w, i as u32 / w, w, h).is_some()
            && mixed[i * 4..i * 4 + 4] != first_lit[i * 4..i * 4 + 4]
        {
            failures.push(format!(
                "{what}: the mixed image changed pixel ({}, {}) inside a face: {:?}, lit {:?}",
                i as u32 % w,
                i as u32 / w,
                &mixed[i * 4..i * 4 + 4],
                &first_lit[i * 4..i * 4 + 4]
            ));
            break;
        }
    }
    lit.destroy(gl);
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
