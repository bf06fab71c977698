//! A sequence: what it is made of (the calls, their handles, options,
//! projections and the host's moves between them) and how a seed draws one.

use deferred_msaa_capi as c;
use deferred_msaa_testkit::Rng;

/// Width and height of the host's G-buffer, and the other size it is
/// re-allocated at.
pub(super) const SIZE: (i32, i32) = (40, 24);
pub(super) const OTHER_SIZE: (i32, i32) = (32, 24);

/// A framebuffer id no one generated. Mesa hands out names counting up
/// from 1 in each context, and a worker runs thousands of sequences in
/// one context, each making framebuffers (70 001 was reached in one run
/// once the crate made more per call): far above any count a run makes.
pub(super) const NOT_A_FRAMEBUFFER: u32 = 0x7fff_0001;

/// Which handle a call is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// Slot 0 or 1 (null where it holds none).
    Slot(usize),
    /// A null pointer.
    Null,
}

/// What `host_fbo` or an output is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fbo {
    /// The host's G-buffer.
    Host,
    /// The host's lighting output (no depth).
    Light,
    /// 0.
    Zero,
    /// A name no one generated.
    NotAFramebuffer,
}

/// A projection argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The perspective the handle's depth mode calls for.
    Perspective,
    /// An orthographic matrix.
    Orthographic,
    /// NaNs.
    NaN,
    /// Null.
    Null,
}

/// One option set, as changes to `dmsaa_options_default()`.
#[derive(Clone, Debug, PartialEq)]
pub struct Options(pub Vec<(u8, i64)>);

/// One step of a sequence.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// `dmsaa_retrofit_new` into a free slot (with `missing`, a loader that
    /// returns null for that entry of `REQUIRED_FUNCTIONS`).
    New {
        /// The framebuffer.
        fbo: Fbo,
        /// The options.
        options: Options,
        /// Index of the function the loader leaves out.
        missing: Option<usize>,
    },
    /// `dmsaa_destroy`.
    Destroy(Which),
    /// `dmsaa_framebuffer`, `dmsaa_samples`, `dmsaa_second_layer_selection`.
    Getters(Which),
    /// `dmsaa_resolve`.
    Resolve(Which, Projection, bool),
    /// `dmsaa_begin_second_layer`.
    Begin(Which, Fbo, bool),
    /// `dmsaa_finish_second_layer`.
    Finish(Which, Fbo),
    /// `dmsaa_set_options`.
    SetOptions(Which, Options),
    /// `dmsaa_refresh`.
    Refresh(Which),
    /// The host's geometry pass into a handle's framebuffer.
    Draw(Which),
    /// The host leaves random GL state behind.
    Dirty(u64),
    /// The host leaves one setting behind.
    Set(Setting),
    /// The host re-allocates one attachment (colour `k`, or depth past the
    /// colours) at the other size.
    Reallocate(usize),
    /// The host deletes one attachment's texture.
    Delete(usize),
    /// The host puts its G-buffer back (new textures for deleted ones).
    PutBack,
    /// The host deletes its framebuffer and makes it again (the same name).
    Recreate,
    /// The host puts its G-buffer back and a handle must recover.
    Recover(Which),
    /// A whole frame in order: draw, resolve, and the second layer's
    /// begin and (when it says to light) finish into the lighting output.
    Frame(Which),
}

/// A setting a host leaves behind, named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    /// Blending on for draw buffer `i` alone (`glDisable(GL_BLEND)`, then
    /// `glEnablei(GL_BLEND, i)`).
    BlendOnlyOn(u32),
    /// `glColorMaski(i, 0, 0, 0, 0)`.
    MaskOff(u32),
    /// `glStencilFuncSeparate` with these front and back references.
    StencilReferences(i32, i32),
    /// `glBindFramebuffer(GL_FRAMEBUFFER, 0)`.
    DefaultFramebuffer,
    /// With viewport arrays: viewport and scissor box `i` of their own, and
    /// the scissor test on for `i` alone.
    Viewport(u32),
}

/// Every entry point a loader may leave out: the required ones, then the
/// conditional ones.
pub fn loader_names() -> Vec<&'static str> {
    deferred_msaa_lab::gl::REQUIRED_FUNCTIONS
        .iter()
        .copied()
        .chain(
            deferred_msaa_lab::gl::CONDITIONAL_FUNCTIONS
                .iter()
                .map(|(name, _, _)| *name),
        )
        .collect()
}

/// The API a sequence drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Api {
    /// The C entry points.
    C,
    /// `MsaaRetrofit` itself; steps the Rust types cannot express (null
    /// pointers, a zero framebuffer, a loader, enumeration values out of
    /// range) are left out.
    Rust,
}

/// A sequence: its host and its calls.
#[derive(Clone, Debug)]
pub struct Sequence {
    /// The seed it was drawn from.
    pub seed: u64,
    /// The API it drives.
    pub api: Api,
    /// Colour attachments (1 to 3).
    pub colors: usize,
    /// Depth with stencil.
    pub stencil: bool,
    /// The calls.
    pub ops: Vec<Op>,
}

pub(super) fn pick<T: Copy>(rng: &mut Rng, items: &[T]) -> T {
    items[rng.below(items.len() as u32) as usize]
}

/// Option changes: mostly in range, now and then not.
pub(super) fn random_options(rng: &mut Rng, colors: usize) -> Options {
    let mut changes = Vec::new();
    if rng.below(3) == 0 {
        // Two layers, for the second layer's calls.
        changes.push((1, 2));
    }
    let count = rng.below(4);
    for _ in 0..count {
        let field = rng.below(14) as u8;
        let bad = rng.below(8) == 0;
        let value = match field {
            0 => pick(rng, &[1, 2, 4, if bad { 0 } else { 4 }, 8]),
            1 => {
                if bad {
                    3
                } else {
                    pick(rng, &[1, 2])
                }
            }
            2 | 4 => {
                if bad {
                    pick(rng, &[-2, colors as i64 + 1])
                } else {
                    rng.below(colors as u32 + 1) as i64 - 1
                }
            }
            3 => i64::from(rng.below(if bad { 3 } else { 2 })),
            5 => i64::from(rng.below(if bad { 5 } else { 4 })),
            6 => i64::from(rng.below(if bad { 5 } else { 4 })),
            7 => i64::from(rng.below(if bad { 3 } else { 2 })),
            8 => i64::from(rng.below(colors as u32 + 1)) * 8 + i64::from(rng.below(5)),
            9 => i64::from(rng.below(if bad { 5 } else { 4 })),
            10 => i64::from(rng.below(if bad { 5 } else { 3 })),
            11 => i64::from(rng.below(if bad { 4 } else { 3 })),
            12 => pick(rng, &[0, 1, 2, 1 << 12]),
            _ => i64::from(rng.below(if bad { 4 } else { 3 })),
        };
        changes.push((field, value));
    }
    Options(changes)
}

impl Options {
    /// The C options these changes make.
    pub fn apply(&self) -> c::DmsaaOptions {
        let mut o = c::dmsaa_options_default();
        for &(field, v) in &self.0 {
            match field {
                0 => o.samples = v as u32,
                1 => o.layers = v as u32,
                2 => o.position_attachment = v as i32,
                3 => o.world_space_position = v as u8,
                4 => o.normal_attachment = v as i32,
                5 => o.normal_encoding = v as u32,
                6 => o.method = v as u32,
                7 => o.window = v as u32,
                8 => o.rules[(v / 8) as usize % c::DMSAA_MAX_RULES] = (v % 8) as u32,
                9 => o.stencil_copy = v as u32,
                10 => o.layer_mix = v as u32,
                11 => o.restore_first_layer = v as u32,
                12 => o.memory_budget_bytes = v as u64,
                _ => o.depth_mode = v as u32,
            }
        }
        o
    }
}

impl Sequence {
    /// The sequence of `seed`.
    pub fn generate(seed: u64) -> Sequence {
        let mut rng = Rng::new(seed ^ 0x6d69_7375_7365);
        let colors = 1 + rng.below(3) as usize;
        let stencil = rng.below(2) == 0;
        let count = 8 + rng.below(40);
        let which = |rng: &mut Rng| match rng.below(12) {
            0 => Which::Null,
            k => Which::Slot(usize::from(k > 8)),
        };
        let mut ops = Vec::new();
        if rng.below(4) != 0 {
            // Mostly a handle to misuse from the start.
            ops.push(Op::New {
                fbo: Fbo::Host,
                options: random_options(&mut rng, colors),
                missing: None,
            });
        }
        for _ in 0..count {
            let op = match rng.below(31) {
                0..=3 => Op::New {
                    fbo: match rng.below(10) {
                        0 => Fbo::Zero,
                        1 => Fbo::NotAFramebuffer,
                        2 => Fbo::Light,
                        _ => Fbo::Host,
                    },
                    options: random_options(&mut rng, colors),
                    missing: (rng.below(8) == 0)
                        .then(|| rng.below(loader_names().len() as u32) as usize),
                },
                4 => Op::Destroy(which(&mut rng)),
                5 => Op::Getters(which(&mut rng)),
                6..=9 => Op::Resolve(
                    which(&mut rng),
                    match rng.below(10) {
                        0 => Projection::Orthographic,
                        1 => Projection::NaN,
                        2 => Projection::Null,
                        _ => Projection::Perspective,
                    },
                    rng.below(6) != 0,
                ),
                10 | 11 => Op::Begin(
                    which(&mut rng),
                    pick(
                        &mut rng,
                        &[Fbo::Light, Fbo::Light, Fbo::Zero, Fbo::NotAFramebuffer],
                    ),
                    rng.below(10) == 0,
                ),
                12 | 13 => Op::Finish(
                    which(&mut rng),
                    pick(&mut rng, &[Fbo::Light, Fbo::Light, Fbo::Zero, Fbo::Host]),
                ),
                14 | 15 => Op::SetOptions(which(&mut rng), random_options(&mut rng, colors)),
                16 => Op::Refresh(which(&mut rng)),
                17..=19 => Op::Draw(which(&mut rng)),
                20..=24 => Op::Dirty(rng.next_u64()),
                25 => Op::Reallocate(rng.below(colors as u32 + 1) as usize),
                26 => Op::Delete(rng.below(colors as u32 + 1) as usize),
                27 => Op::PutBack,
                28 => Op::Frame(which(&mut rng)),
                29 if rng.below(2) == 0 => Op::Recreate,
                _ => Op::Recover(which(&mut rng)),
            };
            ops.push(op);
        }
        Sequence {
            seed,
            // One sequence in three drives the Rust API.
            api: if seed % 3 == 2 { Api::Rust } else { Api::C },
            colors,
            stencil,
            ops,
        }
    }

    /// The same sequence with only the calls at `keep`.
    pub fn only(&self, keep: &[usize]) -> Sequence {
        Sequence {
            ops: keep.iter().map(|&i| self.ops[i].clone()).collect(),
            ..self.clone()
        }
    }

    /// One call a line, numbered.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "seed {} ({:?} API): {} colour attachment(s), depth {}\n",
            self.seed,
            self.api,
            self.colors,
            if self.stencil {
                "GL_DEPTH24_STENCIL8"
            } else {
                "GL_DEPTH_COMPONENT24"
            }
        );
        for (i, op) in self.ops.iter().enumerate() {
            s.push_str(&format!("  {i}: {op:?}\n"));
        }
        s
    }
}
