//! The C API's misuse fuzzer: random call sequences over a real context,
//! with the host's GL state compared around every call. One sequence in
//! three drives the Rust API (`MsaaRetrofit`) the same way, leaving out
//! what its types cannot express ([`Api::Rust`]).
//!
//! A sequence is drawn from a `u64` seed (the kit's `Rng`): a host
//! G-buffer (one to three colour attachments, depth with or without
//! stencil), then calls in any order: `dmsaa_retrofit_new` with options in
//! and out of range, framebuffer ids that are the host's, 0, no
//! framebuffer, or one without depth, and loaders that return null for one
//! function; resolves with perspective, orthographic, NaN or null
//! projections; the second layer's calls in and out of order with good and
//! bad outputs; `set_options`, `refresh`, the getters, null handles and
//! `dmsaa_destroy`; between them the host re-allocates one attachment at
//! another size, deletes one, puts its G-buffer back, draws, and leaves
//! random GL state behind (per-buffer blend enables and colour masks,
//! stencil functions with references 0..255 while a framebuffer without
//! stencil is bound, scissor, viewport, bindings, ...).
//!
//! Around every call: the GL state snapshot (`gl_state`, indexed state and
//! the stencil references included) is unchanged, `glGetError` is clean,
//! no call panics, a failure has a one-line message, a failed
//! `dmsaa_retrofit_new` leaves `*out` null and nothing allocated. After a
//! failed call on a handle, and at the end, the host puts its G-buffer
//! back and `dmsaa_refresh` must succeed and the next resolve give the
//! right frame: every attachment and the depth of a uniform draw come back
//! as the host's own clear of them.
//!
//! [`run_sequence`] runs one and returns its failures; [`shrink`] drops
//! calls while a failure stays; the slow tier's test runs sequences in
//! child processes (a crash or a hang is that sequence's) and prints each
//! failure's shrunk sequence with the command that replays it.

use deferred_msaa::gbuffer::MemoryBudget;
use deferred_msaa::resolve::{NormalEncoding, ResolveMethod, ResolveRule, StencilCopy, Window};
use deferred_msaa::{
    ColorAttachment, DepthMode, FirstLayerRestore, Frame, LayerMix, MsaaRetrofit, NormalAttachment,
    PositionSpace, RetrofitOptions,
};
use deferred_msaa_capi as c;
use deferred_msaa_lab::context::HeadlessContext;
use deferred_msaa_testkit::{Rng, projection};
use glow::HasContext;
use std::ffi::{CStr, c_char, c_void};

use super::gl_state::GlState;

/// Width and height of the host's G-buffer, and the other size it is
/// re-allocated at.
const SIZE: (i32, i32) = (40, 24);
const OTHER_SIZE: (i32, i32) = (32, 24);

/// A framebuffer id no one generated.
const NOT_A_FRAMEBUFFER: u32 = 70_001;

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

fn pick<T: Copy>(rng: &mut Rng, items: &[T]) -> T {
    items[rng.below(items.len() as u32) as usize]
}

/// Option changes: mostly in range, now and then not.
fn random_options(rng: &mut Rng, colors: usize) -> Options {
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

/// The host's G-buffer, its lighting output and the objects its state
/// binds.
struct Host {
    fbo: glow::Framebuffer,
    light_fbo: glow::Framebuffer,
    light: glow::Texture,
    /// Colour textures, then depth; `None` once deleted.
    images: Vec<Option<glow::Texture>>,
    colors: usize,
    stencil: bool,
    program: glow::Program,
    vao: glow::VertexArray,
    buffer: glow::Buffer,
    spare: glow::Texture,
}

const COLOR_FORMATS: [(u32, u32, u32); 3] = [
    (glow::RGBA16F, glow::RGBA, glow::FLOAT),
    (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE),
    (glow::RGBA16F, glow::RGBA, glow::FLOAT),
];

impl Host {
    fn new(gl: &glow::Context, colors: usize, stencil: bool) -> Host {
        unsafe {
            let fbo = gl.create_framebuffer().expect("host framebuffer");
            let mut host = Host {
                fbo,
                light_fbo: gl.create_framebuffer().expect("light framebuffer"),
                light: gl.create_texture().expect("light texture"),
                images: vec![None; colors + 1],
                colors,
                stencil,
                program: host_program(gl),
                vao: gl.create_vertex_array().expect("host vao"),
                buffer: gl.create_buffer().expect("host buffer"),
                spare: gl.create_texture().expect("spare texture"),
            };
            gl.bind_texture(glow::TEXTURE_2D, Some(host.light));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                SIZE.0,
                SIZE.1,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(host.light_fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(host.light),
                0,
            );
            gl.bind_texture(glow::TEXTURE_2D, Some(host.spare));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                4,
                4,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            gl.bind_vertex_array(Some(host.vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(host.buffer));
            gl.buffer_data_size(glow::ARRAY_BUFFER, 64, glow::STATIC_DRAW);
            gl.bind_vertex_array(None);
            host.put_back(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(host.fbo));
            let draw: Vec<u32> = (0..colors as u32)
                .map(|k| glow::COLOR_ATTACHMENT0 + k)
                .collect();
            gl.draw_buffers(&draw);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            host
        }
    }

    /// Image `k` specified at `size` (a new texture where it was deleted)
    /// and attached.
    fn specify(&mut self, gl: &glow::Context, k: usize, size: (i32, i32)) {
        unsafe {
            let texture = match self.images[k] {
                Some(t) => t,
                None => {
                    let t = gl.create_texture().expect("host texture");
                    self.images[k] = Some(t);
                    t
                }
            };
            gl.bind_texture(glow::TEXTURE_2D, Some(texture));
            let (internal, format, ty, point) = if k < self.colors {
                let (i, f, t) = COLOR_FORMATS[k];
                (i, f, t, glow::COLOR_ATTACHMENT0 + k as u32)
            } else if self.stencil {
                (
                    glow::DEPTH24_STENCIL8,
                    glow::DEPTH_STENCIL,
                    glow::UNSIGNED_INT_24_8,
                    glow::DEPTH_STENCIL_ATTACHMENT,
                )
            } else {
                (
                    glow::DEPTH_COMPONENT24,
                    glow::DEPTH_COMPONENT,
                    glow::UNSIGNED_INT,
                    glow::DEPTH_ATTACHMENT,
                )
            };
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                internal as i32,
                size.0,
                size.1,
                0,
                format,
                ty,
                glow::PixelUnpackData::Slice(None),
            );
            for (p, v) in [
                (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
                (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
            ] {
                gl.tex_parameter_i32(glow::TEXTURE_2D, p, v as i32);
            }
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            gl.framebuffer_texture_2d(glow::FRAMEBUFFER, point, glow::TEXTURE_2D, Some(texture), 0);
        }
    }

    /// Every image back at the G-buffer's size, attached.
    fn put_back(&mut self, gl: &glow::Context) {
        for k in 0..self.images.len() {
            self.specify(gl, k, SIZE);
        }
    }

    /// The framebuffer deleted and made again, as an engine does on a
    /// resize, every image attached again with the same draw buffers. GL
    /// need not give the freed name back (Mesa does not): the handles made
    /// for the old one cannot follow, and say so.
    fn recreate(&mut self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            self.fbo = gl.create_framebuffer().expect("host framebuffer");
            self.put_back(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            let draw: Vec<u32> = (0..self.colors as u32)
                .map(|k| glow::COLOR_ATTACHMENT0 + k)
                .collect();
            gl.draw_buffers(&draw);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn delete(&mut self, gl: &glow::Context, k: usize) {
        if let Some(t) = self.images[k].take() {
            unsafe { gl.delete_texture(t) };
        }
    }

    fn fbo_arg(&self, fbo: Fbo) -> u32 {
        match fbo {
            Fbo::Host => self.fbo.0.get(),
            Fbo::Light => self.light_fbo.0.get(),
            Fbo::Zero => 0,
            Fbo::NotAFramebuffer => NOT_A_FRAMEBUFFER,
        }
    }

    /// The uniform values a draw leaves: per colour attachment, then
    /// depth and stencil.
    fn clear(gl: &glow::Context, colors: usize) {
        unsafe {
            for k in 0..colors {
                let v = 0.125 + 0.25 * k as f32;
                gl.clear_buffer_f32_slice(glow::COLOR, k as u32, &[v, 1.0 - v, 0.5, 1.0]);
            }
            gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, 0.375, 0x5A);
        }
    }

    /// What the host's G-buffer holds, every attachment read back as
    /// floats (colours) and depth.
    fn read(&self, gl: &glow::Context) -> Vec<Vec<f32>> {
        let (w, h) = SIZE;
        let mut out = Vec::new();
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.fbo));
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            for k in 0..self.colors {
                gl.read_buffer(glow::COLOR_ATTACHMENT0 + k as u32);
                let mut v = vec![0f32; (w * h * 4) as usize];
                gl.read_pixels(
                    0,
                    0,
                    w,
                    h,
                    glow::RGBA,
                    glow::FLOAT,
                    glow::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut v))),
                );
                out.push(v);
            }
            let mut d = vec![0f32; (w * h) as usize];
            gl.read_pixels(
                0,
                0,
                w,
                h,
                glow::DEPTH_COMPONENT,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(bytemuck::cast_slice_mut(&mut d))),
            );
            out.push(d);
            gl.read_buffer(glow::COLOR_ATTACHMENT0);
        }
        out
    }

    fn destroy(self, gl: &glow::Context) {
        unsafe {
            for t in self.images.into_iter().flatten() {
                gl.delete_texture(t);
            }
            gl.delete_framebuffer(self.fbo);
            gl.delete_framebuffer(self.light_fbo);
            gl.delete_texture(self.light);
            gl.delete_texture(self.spare);
            gl.delete_program(self.program);
            gl.delete_vertex_array(self.vao);
            gl.delete_buffer(self.buffer);
        }
    }
}

fn host_program(gl: &glow::Context) -> glow::Program {
    unsafe {
        let program = gl.create_program().expect("host program");
        let mut shaders = Vec::new();
        for (stage, source) in [
            (
                glow::VERTEX_SHADER,
                "#version 150\nvoid main() { gl_Position = vec4(0.0); }\n",
            ),
            (
                glow::FRAGMENT_SHADER,
                "#version 150\nout vec4 o;\nvoid main() { o = vec4(1.0); }\n",
            ),
        ] {
            let shader = gl.create_shader(stage).expect("host shader");
            gl.shader_source(shader, source);
            gl.compile_shader(shader);
            gl.attach_shader(program, shader);
            shaders.push(shader);
        }
        gl.link_program(program);
        for shader in shaders {
            gl.detach_shader(program, shader);
            gl.delete_shader(shader);
        }
        program
    }
}

/// Leave random state behind, as a host's frame does.
fn dirty(gl: &glow::Context, host: &Host, seed: u64) {
    let mut rng = Rng::new(seed);
    let draw_buffers = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) }.max(1) as u32;
    let units =
        unsafe { gl.get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS) }.clamp(1, 32) as u32;
    let flip = |rng: &mut Rng| rng.below(2) == 0;
    unsafe {
        for _ in 0..1 + rng.below(8) {
            match rng.below(20) {
                18 | 19 if super::gl_state::has_viewport_arrays(gl) => {
                    let count = gl.get_parameter_i32(glow::MAX_VIEWPORTS).clamp(1, 64) as u32;
                    let i = rng.below(count);
                    if rng.below(2) == 0 {
                        gl.viewport_f32_slice(
                            i,
                            1,
                            &[[
                                rng.below(8) as f32,
                                rng.below(8) as f32,
                                1.0 + rng.below(50) as f32,
                                0.5 + rng.below(50) as f32,
                            ]],
                        );
                        gl.scissor_slice(
                            i,
                            1,
                            &[[rng.below(8) as i32, 0, 1 + rng.below(30) as i32, 4]],
                        );
                    } else if flip(&mut rng) {
                        gl.enable_draw_buffer(glow::SCISSOR_TEST, i);
                    } else {
                        gl.disable_draw_buffer(glow::SCISSOR_TEST, i);
                    }
                }
                0 => {
                    let i = rng.below(draw_buffers);
                    if flip(&mut rng) {
                        gl.enable_draw_buffer(glow::BLEND, i);
                    } else {
                        gl.disable_draw_buffer(glow::BLEND, i);
                    }
                }
                1 => {
                    let i = rng.below(draw_buffers);
                    let m = rng.below(16);
                    gl.color_mask_draw_buffer(i, m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
                }
                2 => {
                    let face = pick(&mut rng, &[glow::FRONT, glow::BACK, glow::FRONT_AND_BACK]);
                    let func = pick(&mut rng, &[glow::EQUAL, glow::LESS, glow::NOTEQUAL]);
                    gl.stencil_func_separate(face, func, rng.below(256) as i32, rng.below(256));
                }
                3 => {
                    let face = pick(&mut rng, &[glow::FRONT, glow::BACK]);
                    gl.stencil_op_separate(face, glow::ZERO, glow::INCR, glow::REPLACE);
                    gl.stencil_mask_separate(face, rng.below(256));
                }
                4 => {
                    let cap = pick(
                        &mut rng,
                        &[
                            glow::BLEND,
                            glow::CULL_FACE,
                            glow::SCISSOR_TEST,
                            glow::STENCIL_TEST,
                            glow::DEPTH_TEST,
                            glow::FRAMEBUFFER_SRGB,
                            glow::RASTERIZER_DISCARD,
                            glow::POLYGON_OFFSET_FILL,
                            glow::SAMPLE_ALPHA_TO_COVERAGE,
                            glow::SAMPLE_MASK,
                            glow::COLOR_LOGIC_OP,
                            glow::CLIP_DISTANCE0,
                        ],
                    );
                    if flip(&mut rng) {
                        gl.enable(cap);
                    } else {
                        gl.disable(cap);
                    }
                }
                5 => gl.scissor(
                    rng.below(8) as i32,
                    rng.below(8) as i32,
                    1 + rng.below(30) as i32,
                    1 + rng.below(30) as i32,
                ),
                6 => gl.viewport(
                    rng.below(8) as i32,
                    rng.below(8) as i32,
                    1 + rng.below(50) as i32,
                    1 + rng.below(50) as i32,
                ),
                7 => {
                    let f = pick(&mut rng, &[None, Some(host.fbo), Some(host.light_fbo)]);
                    let target = pick(
                        &mut rng,
                        &[
                            glow::FRAMEBUFFER,
                            glow::DRAW_FRAMEBUFFER,
                            glow::READ_FRAMEBUFFER,
                        ],
                    );
                    gl.bind_framebuffer(target, f);
                }
                8 => gl.use_program(pick(&mut rng, &[None, Some(host.program)])),
                9 => gl.bind_vertex_array(pick(&mut rng, &[None, Some(host.vao)])),
                10 => {
                    gl.active_texture(glow::TEXTURE0 + rng.below(units));
                    gl.bind_texture(glow::TEXTURE_2D, pick(&mut rng, &[None, Some(host.spare)]));
                }
                11 => gl.depth_func(pick(&mut rng, &[glow::LESS, glow::GEQUAL, glow::ALWAYS])),
                12 => gl.depth_mask(flip(&mut rng)),
                13 => gl.polygon_mode(
                    glow::FRONT_AND_BACK,
                    pick(&mut rng, &[glow::FILL, glow::LINE]),
                ),
                14 => {
                    gl.pixel_store_i32(glow::PACK_ALIGNMENT, pick(&mut rng, &[1, 2, 4, 8]));
                    gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, pick(&mut rng, &[1, 2, 4, 8]));
                }
                15 => gl.bind_buffer(
                    glow::ARRAY_BUFFER,
                    pick(&mut rng, &[None, Some(host.buffer)]),
                ),
                16 => gl.clear_stencil(rng.below(256) as i32),
                _ => gl.color_mask(
                    flip(&mut rng),
                    flip(&mut rng),
                    flip(&mut rng),
                    flip(&mut rng),
                ),
            }
        }
    }
}

/// The GL state a sequence starts from: GL's defaults for what [`dirty`]
/// changes.
fn reset(gl: &glow::Context) {
    unsafe {
        let draw_buffers = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).max(1) as u32;
        for i in 0..draw_buffers {
            gl.disable_draw_buffer(glow::BLEND, i);
            gl.color_mask_draw_buffer(i, true, true, true, true);
        }
        gl.stencil_func(glow::ALWAYS, 0, 0xFF);
        gl.stencil_op(glow::KEEP, glow::KEEP, glow::KEEP);
        gl.stencil_mask(0xFF);
        for cap in [
            glow::CULL_FACE,
            glow::SCISSOR_TEST,
            glow::STENCIL_TEST,
            glow::DEPTH_TEST,
            glow::FRAMEBUFFER_SRGB,
            glow::RASTERIZER_DISCARD,
            glow::POLYGON_OFFSET_FILL,
            glow::SAMPLE_ALPHA_TO_COVERAGE,
            glow::SAMPLE_MASK,
            glow::COLOR_LOGIC_OP,
            glow::CLIP_DISTANCE0,
        ] {
            gl.disable(cap);
        }
        gl.scissor(0, 0, SIZE.0, SIZE.1);
        gl.viewport(0, 0, SIZE.0, SIZE.1);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.use_program(None);
        gl.bind_vertex_array(None);
        gl.active_texture(glow::TEXTURE0);
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.depth_func(glow::LESS);
        gl.depth_mask(true);
        gl.polygon_mode(glow::FRONT_AND_BACK, glow::FILL);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 4);
        gl.bind_buffer(glow::ARRAY_BUFFER, None);
        gl.clear_stencil(0);
        while gl.get_error() != glow::NO_ERROR {}
    }
}

thread_local! {
    /// Calls by name: how many returned OK, how many another status.
    static STATS: std::cell::RefCell<std::collections::BTreeMap<String, (u64, u64)>> =
        Default::default();
}

/// How many library calls were checked on this thread since the last
/// time this was asked.
pub fn take_call_count() -> u64 {
    STATS.with(|s| {
        let s = std::mem::take(&mut *s.borrow_mut());
        s.values().map(|(ok, other)| ok + other).sum()
    })
}

/// The calls made on this thread since the last call, by name: OK and
/// other statuses, one line.
pub fn take_stats() -> String {
    STATS.with(|s| {
        let s = std::mem::take(&mut *s.borrow_mut());
        s.iter()
            .map(|(name, (ok, other))| format!("{name} {ok} OK / {other} not"))
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// Whether a failed `dmsaa_retrofit_new` was refused by the C layer's own
/// checks, which come before any GL call (null pointers, options out of
/// range, a zero framebuffer): every refusal after those is GL's.
fn before_gl(status: c::DmsaaStatus, message: &str) -> bool {
    status == c::DmsaaStatus::NullPointer
        || (status == c::DmsaaStatus::InvalidArgument
            && !message.contains("is not a framebuffer object"))
}

/// What the loader is given as user data.
struct Loader<'a> {
    context: &'a HeadlessContext,
    missing: Option<&'static str>,
}

unsafe extern "C" fn load(name: *const c_char, user: *mut c_void) -> *const c_void {
    // SAFETY: `user` is the `Loader` the fuzzer passed with this function,
    // alive for the call; `name` is the library's NUL-terminated name.
    let (loader, name) = unsafe { (&*(user as *const Loader<'_>), CStr::from_ptr(name)) };
    let name = name.to_str().unwrap_or("");
    if loader.missing == Some(name) {
        return std::ptr::null();
    }
    loader.context.get_proc_address(name)
}

/// What the fuzzer knows of a live handle.
struct Handle {
    raw: *mut c::DmsaaRetrofit,
    options: c::DmsaaOptions,
    /// The framebuffer it was made for.
    fbo: u32,
}

/// The calling thread's `dmsaa_last_error()`.
pub fn last_message() -> String {
    last_error()
}

fn last_error() -> String {
    // SAFETY: the library's NUL-terminated message.
    unsafe { CStr::from_ptr(c::dmsaa_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// The projection (and view) a handle with `options` is given.
fn matrices(kind: Projection, options: &c::DmsaaOptions) -> ([f32; 16], [f32; 16]) {
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let m = match kind {
        Projection::Orthographic => {
            let mut m = [0.0; 16];
            m[0] = 1.0;
            m[5] = 1.0;
            m[10] = -1.0;
            m[15] = 1.0;
            m
        }
        Projection::NaN => [f64::NAN; 16],
        _ if options.depth_mode == c::DMSAA_DEPTH_REVERSED_Z => {
            projection::perspective_reversed(1.0, aspect, 0.1, Some(100.0))
        }
        _ => projection::perspective(1.0, aspect, 0.1, Some(100.0)),
    };
    let mut view = [0f32; 16];
    for i in 0..4 {
        view[i * 5] = 1.0;
    }
    (projection::to_f32(&m), view)
}

/// One sequence's run: the handles, the host, the failures found.
struct Run<'a> {
    gl: &'a glow::Context,
    context: &'a HeadlessContext,
    host: Host,
    slots: [Option<Handle>; 2],
    /// The Rust API's handles, for a sequence of [`Api::Rust`].
    retrofits: [Option<(MsaaRetrofit, c::DmsaaOptions)>; 2],
    api: Api,
    /// A Rust API call is under way: its message is its error's, checked by
    /// [`Run::call_rust`], not `dmsaa_last_error`.
    in_rust_call: bool,
    failures: Vec<String>,
}

impl Run<'_> {
    fn handle(&self, which: Which) -> *mut c::DmsaaRetrofit {
        match which {
            Which::Slot(k) => self.slots[k]
                .as_ref()
                .map_or(std::ptr::null_mut(), |h| h.raw),
            Which::Null => std::ptr::null_mut(),
        }
    }

    fn fail(&mut self, index: usize, what: String) {
        self.failures.push(format!("call {index}: {what}"));
    }

    /// Run one library call with the checks around it; its status.
    fn call(
        &mut self,
        index: usize,
        name: &str,
        f: impl FnOnce(&mut Self) -> c::DmsaaStatus,
    ) -> c::DmsaaStatus {
        let gl = self.gl;
        // The host's own GL calls must be clean, or the check after is moot.
        let pending = unsafe { gl.get_error() };
        if pending != glow::NO_ERROR {
            self.fail(
                index,
                format!("the fuzzer's host left GL error 0x{pending:04X}"),
            );
            while unsafe { gl.get_error() } != glow::NO_ERROR {}
        }
        let before = GlState::capture(gl);
        let status = f(self);
        // A Rust call's outcome, by its own words.
        let outcome = match (self.in_rust_call, status) {
            (false, status) => format!("{status:?}"),
            (true, c::DmsaaStatus::Ok) => "Ok".into(),
            (true, c::DmsaaStatus::Panic) => "a panic".into(),
            (true, _) => "Err".into(),
        };
        STATS.with(|s| {
            let mut s = s.borrow_mut();
            let entry = s.entry(name.to_string()).or_default();
            if status == c::DmsaaStatus::Ok {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        });
        let error = unsafe { gl.get_error() };
        if error != glow::NO_ERROR {
            self.fail(
                index,
                format!("{name} returned {outcome} and left GL error 0x{error:04X}"),
            );
            while unsafe { gl.get_error() } != glow::NO_ERROR {}
        }
        let after = GlState::capture(gl);
        for d in before.differences(&after) {
            self.fail(index, format!("{name} ({outcome}) changed {d}"));
        }
        if self.in_rust_call {
            return status;
        }
        if status == c::DmsaaStatus::Panic {
            self.fail(index, format!("{name} panicked: {}", last_error()));
        }
        if std::env::var_os("DEFERRED_MSAA_VERBOSE").is_some() {
            let message = if status == c::DmsaaStatus::Ok {
                String::new()
            } else {
                last_error()
            };
            eprintln!("call {index}: {name}: {status:?} {message}");
        }
        if status != c::DmsaaStatus::Ok {
            let message = last_error();
            let driver_log = status == c::DmsaaStatus::Gl
                && (message.contains("failed to compile") || message.contains("failed to link"));
            if message.trim().is_empty() || (message.contains('\n') && !driver_log) {
                self.fail(
                    index,
                    format!("{name} returned {status:?} with the message {message:?}"),
                );
            }
        }
        status
    }

    fn new_handle(&mut self, index: usize, fbo: Fbo, options: &Options, missing: Option<usize>) {
        let Some(slot) = self.slots.iter().position(Option::is_none) else {
            return;
        };
        let c_options = options.apply();
        let names = loader_names();
        let missing = missing.map(|k| names[k % names.len()]);
        // A conditional function is called (and so needed) only where the
        // context offers it.
        let needed = missing.filter(|name| {
            deferred_msaa_lab::gl::REQUIRED_FUNCTIONS.contains(name)
                || deferred_msaa_lab::gl::first_missing_conditional_function(self.gl, |n| {
                    if n == *name {
                        std::ptr::null()
                    } else {
                        self.context.get_proc_address(n)
                    }
                })
                .is_some()
        });
        let loader = Loader {
            context: self.context,
            missing,
        };
        let host_fbo = self.host.fbo_arg(fbo);
        let live = c::dmsaa_live_objects();
        let mut out: *mut c::DmsaaRetrofit = std::ptr::NonNull::dangling().as_ptr();
        let status = self.call(index, "dmsaa_retrofit_new", |_| unsafe {
            c::dmsaa_retrofit_new(
                Some(load),
                &loader as *const Loader<'_> as *mut c_void,
                host_fbo,
                &c_options,
                &mut out,
            )
        });
        if status == c::DmsaaStatus::Ok {
            if out.is_null() {
                self.fail(
                    index,
                    "dmsaa_retrofit_new returned OK and a null handle".into(),
                );
                return;
            }
            if let Some(name) = needed {
                self.fail(
                    index,
                    format!("dmsaa_retrofit_new succeeded without {name}"),
                );
            }
            self.slots[slot] = Some(Handle {
                raw: out,
                options: c_options,
                fbo: host_fbo,
            });
            return;
        }
        if !out.is_null() {
            self.fail(
                index,
                format!("a failed dmsaa_retrofit_new ({status:?}) left *out set"),
            );
        }
        if c::dmsaa_live_objects() != live {
            self.fail(
                index,
                format!(
                    "a failed dmsaa_retrofit_new ({status:?}) left {} GL objects",
                    c::dmsaa_live_objects() - live
                ),
            );
        }
        if let Some(name) = needed {
            let message = last_error();
            if !before_gl(status, &message)
                && (status != c::DmsaaStatus::Unsupported || !message.contains(name))
            {
                self.fail(
                    index,
                    format!("a loader without {name}: {status:?}, {message:?}"),
                );
            }
        }
        if fbo == Fbo::NotAFramebuffer
            && missing.is_none()
            && !before_gl(status, &last_error())
            && !last_error().contains("is not a framebuffer object")
        {
            self.fail(
                index,
                format!(
                    "a name that is no framebuffer was refused as: {}",
                    last_error()
                ),
            );
        }
    }

    /// The host puts its G-buffer back; `which`'s handle must refresh and
    /// resolve a uniform draw into the values the host's own clear gives.
    fn recover(&mut self, index: usize, which: Which) {
        let gl = self.gl;
        self.host.put_back(gl);
        let Which::Slot(k) = which else {
            return;
        };
        let Some((options, fbo)) = self.slots[k].as_ref().map(|h| (h.options, h.fbo)) else {
            return;
        };
        let raw = self.handle(which);
        if fbo != self.host.fbo.0.get() {
            // The host made its framebuffer again under another name: the
            // handle refuses, saying its framebuffer is gone.
            let status = self.call(index, "dmsaa_refresh (framebuffer gone)", |_| unsafe {
                c::dmsaa_refresh(raw)
            });
            if status != c::DmsaaStatus::InvalidArgument
                || !last_error().contains("no longer a framebuffer object")
            {
                self.fail(
                    index,
                    format!(
                        "dmsaa_refresh with the framebuffer deleted: {status:?}: {}",
                        last_error()
                    ),
                );
            }
            return;
        }
        let status = self.call(index, "dmsaa_refresh (recovery)", |_| unsafe {
            c::dmsaa_refresh(raw)
        });
        if status != c::DmsaaStatus::Ok {
            self.fail(
                index,
                format!(
                    "no recovery: with the G-buffer put back, dmsaa_refresh returned {status:?}: {}",
                    last_error()
                ),
            );
            return;
        }
        let expected = self.expected_frame();
        self.draw(index, which);
        let (projection, view) = matrices(Projection::Perspective, &options);
        let status = self.call(index, "dmsaa_resolve (recovery)", |_| unsafe {
            c::dmsaa_resolve(raw, projection.as_ptr(), view.as_ptr())
        });
        if status != c::DmsaaStatus::Ok {
            self.fail(
                index,
                format!(
                    "no recovery: after dmsaa_refresh, dmsaa_resolve returned {status:?}: {}",
                    last_error()
                ),
            );
            return;
        }
        self.check_frame(index, &expected);
    }

    /// The host's own clear of its G-buffer, read back: what a resolve of
    /// the uniform draw must give. The images are cleared to something
    /// else after, so that the resolve must write them.
    fn expected_frame(&mut self) -> Vec<Vec<f32>> {
        let gl = self.gl;
        unsafe {
            reset(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.host.fbo));
            Host::clear(gl, self.host.colors);
        }
        let expected = self.host.read(gl);
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.host.fbo));
            for k in 0..self.host.colors {
                gl.clear_buffer_f32_slice(glow::COLOR, k as u32, &[0.0; 4]);
            }
            gl.clear_buffer_depth_stencil(glow::DEPTH_STENCIL, 0, 1.0, 0);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
        expected
    }

    /// Every attachment and the depth bit for bit as `expected`.
    fn check_frame(&mut self, index: usize, expected: &[Vec<f32>]) {
        let got = self.host.read(self.gl);
        for (k, (g, e)) in got.iter().zip(expected).enumerate() {
            if let Some(p) = g
                .iter()
                .zip(e)
                .position(|(a, b)| a.to_bits() != b.to_bits())
            {
                let what = if k < self.host.colors {
                    format!("colour attachment {k}")
                } else {
                    "depth".to_string()
                };
                self.fail(
                    index,
                    format!(
                        "no recovery: the resolved {what} is {} at value {p}, the host's own {}",
                        g[p], e[p]
                    ),
                );
                return;
            }
        }
    }

    /// The host's geometry pass into `which`'s framebuffer: a uniform
    /// value per attachment.
    fn draw(&mut self, index: usize, which: Which) {
        let raw = self.handle(which);
        let mut fbo = 0u32;
        let status = self.call(index, "dmsaa_framebuffer", |_| unsafe {
            c::dmsaa_framebuffer(raw, &mut fbo)
        });
        if status != c::DmsaaStatus::Ok {
            return;
        }
        let Some(fbo) = std::num::NonZeroU32::new(fbo).map(glow::NativeFramebuffer) else {
            self.fail(index, "dmsaa_framebuffer gave 0".into());
            return;
        };
        self.draw_into(fbo);
    }

    /// The uniform draw into a multisampled framebuffer.
    fn draw_into(&mut self, fbo: glow::Framebuffer) {
        let gl = self.gl;
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            let draw_buffers = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).max(1) as u32;
            for i in 0..draw_buffers {
                gl.color_mask_draw_buffer(i, true, true, true, true);
            }
            gl.color_mask(true, true, true, true);
            gl.disable(glow::SCISSOR_TEST);
            gl.disable(glow::RASTERIZER_DISCARD);
            gl.depth_mask(true);
            gl.stencil_mask(0xFF);
            Host::clear(gl, self.host.colors);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
    }

    fn step(&mut self, index: usize, op: &Op) {
        let gl = self.gl;
        if self.api == Api::Rust && self.step_rust(index, op) {
            return;
        }
        match op {
            Op::New {
                fbo,
                options,
                missing,
            } => self.new_handle(index, *fbo, options, *missing),
            Op::Destroy(which) => {
                let raw = self.handle(*which);
                self.call(index, "dmsaa_destroy", |_| {
                    unsafe { c::dmsaa_destroy(raw) };
                    c::DmsaaStatus::Ok
                });
                if let Which::Slot(k) = which {
                    self.slots[*k] = None;
                }
            }
            Op::Getters(which) => {
                let raw = self.handle(*which);
                let mut value = 0u32;
                type Getter =
                    unsafe extern "C" fn(*mut c::DmsaaRetrofit, *mut u32) -> c::DmsaaStatus;
                let getters: [(&str, Getter); 3] = [
                    ("dmsaa_framebuffer", c::dmsaa_framebuffer),
                    ("dmsaa_samples", c::dmsaa_samples),
                    (
                        "dmsaa_second_layer_selection",
                        c::dmsaa_second_layer_selection,
                    ),
                ];
                for (name, f) in getters {
                    let status = self.call(index, name, |_| unsafe { f(raw, &mut value) });
                    if raw.is_null() != (status == c::DmsaaStatus::NullPointer) {
                        self.fail(index, format!("{name} on {which:?}: {status:?}"));
                    }
                }
            }
            Op::Resolve(which, kind, with_view) => {
                let raw = self.handle(*which);
                let options = match which {
                    Which::Slot(k) => self.slots[*k]
                        .as_ref()
                        .map_or_else(|| c::dmsaa_options_default(), |h| h.options),
                    Which::Null => c::dmsaa_options_default(),
                };
                let (projection, view) = matrices(*kind, &options);
                let p = if *kind == Projection::Null {
                    std::ptr::null()
                } else {
                    projection.as_ptr()
                };
                let v = if *with_view {
                    view.as_ptr()
                } else {
                    std::ptr::null()
                };
                self.call(index, "dmsaa_resolve", |_| unsafe {
                    c::dmsaa_resolve(raw, p, v)
                });
            }
            Op::Begin(which, output, null_run) => {
                let raw = self.handle(*which);
                let output = self.host.fbo_arg(*output);
                let mut run = false;
                let run_ptr: *mut bool = if *null_run {
                    std::ptr::null_mut()
                } else {
                    &mut run
                };
                self.call(index, "dmsaa_begin_second_layer", |_| unsafe {
                    c::dmsaa_begin_second_layer(raw, output, run_ptr)
                });
            }
            Op::Finish(which, output) => {
                let raw = self.handle(*which);
                let output = self.host.fbo_arg(*output);
                self.call(index, "dmsaa_finish_second_layer", |_| unsafe {
                    c::dmsaa_finish_second_layer(raw, output)
                });
            }
            Op::SetOptions(which, options) => {
                let raw = self.handle(*which);
                let c_options = options.apply();
                let status = self.call(index, "dmsaa_set_options", |_| unsafe {
                    c::dmsaa_set_options(raw, &c_options)
                });
                if let (c::DmsaaStatus::Ok, Which::Slot(k)) = (status, which) {
                    if let Some(h) = self.slots[*k].as_mut() {
                        h.options = c_options;
                    }
                }
            }
            Op::Refresh(which) => {
                let raw = self.handle(*which);
                self.call(index, "dmsaa_refresh", |_| unsafe { c::dmsaa_refresh(raw) });
            }
            Op::Draw(which) => self.draw(index, *which),
            Op::Dirty(seed) => {
                dirty(gl, &self.host, *seed);
                // A host may leave state GL refuses (a deleted name bound):
                // not the library's concern.
                while unsafe { gl.get_error() } != glow::NO_ERROR {}
            }
            Op::Set(setting) => unsafe {
                match *setting {
                    Setting::BlendOnlyOn(i) => {
                        gl.disable(glow::BLEND);
                        gl.enable_draw_buffer(glow::BLEND, i);
                    }
                    Setting::MaskOff(i) => gl.color_mask_draw_buffer(i, false, false, false, false),
                    Setting::StencilReferences(front, back) => {
                        gl.stencil_func_separate(glow::FRONT, glow::EQUAL, front, 0xFF);
                        gl.stencil_func_separate(glow::BACK, glow::GEQUAL, back, 0x7F);
                    }
                    Setting::DefaultFramebuffer => gl.bind_framebuffer(glow::FRAMEBUFFER, None),
                    Setting::Viewport(i) => {
                        if super::gl_state::has_viewport_arrays(gl) {
                            let k = i as i32;
                            gl.viewport_f32_slice(i, 1, &[[1.0 + k as f32, 2.0, 7.5, 9.0]]);
                            gl.scissor_slice(i, 1, &[[k, 3, 5, 6]]);
                            gl.disable(glow::SCISSOR_TEST);
                            gl.enable_draw_buffer(glow::SCISSOR_TEST, i);
                        }
                    }
                }
            },
            Op::Reallocate(k) => {
                let k = (*k).min(self.host.colors);
                self.host.specify(gl, k, OTHER_SIZE);
            }
            Op::Delete(k) => {
                let k = (*k).min(self.host.colors);
                self.host.delete(gl, k);
            }
            Op::PutBack => self.host.put_back(gl),
            Op::Recreate => self.host.recreate(gl),
            Op::Recover(which) => self.recover(index, *which),
            Op::Frame(which) => {
                self.draw(index, *which);
                self.step(index, &Op::Resolve(*which, Projection::Perspective, true));
                let raw = self.handle(*which);
                let output = self.host.light_fbo.0.get();
                let mut run = false;
                let status = self.call(index, "dmsaa_begin_second_layer", |_| unsafe {
                    c::dmsaa_begin_second_layer(raw, output, &mut run)
                });
                if status == c::DmsaaStatus::Ok && run {
                    self.step(index, &Op::Finish(*which, Fbo::Light));
                }
            }
        }
    }
}

/// `options` as the Rust API takes them; `None` where a value has no Rust
/// form (an enumeration out of range, a curve mix without its text).
fn rust_options(o: &c::DmsaaOptions) -> Option<(RetrofitOptions, DepthMode, bool)> {
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
    fn call_rust(
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
    fn step_rust(&mut self, index: usize, op: &Op) -> bool {
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
                    if let Some(fbo) = self.retrofits[k].as_ref().map(|(r, _)| r.framebuffer()) {
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
                if let Some(fbo) = self.retrofits[k].as_ref().map(|(r, _)| r.framebuffer()) {
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

    /// A Rust API resolve of `which`'s retrofit (if it has one); whether it
    /// succeeded.
    fn resolve_rust(&mut self, index: usize, which: &Which, kind: Projection, view: bool) -> bool {
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

/// Run `sequence` on `context` (current on this thread); its failures,
/// empty when every check held.
pub fn run_sequence(context: &HeadlessContext, sequence: &Sequence) -> Vec<String> {
    let gl = context.gl();
    reset(gl);
    let live = c::dmsaa_live_objects();
    let host = Host::new(gl, sequence.colors, sequence.stencil);
    let mut run = Run {
        gl,
        context,
        host,
        slots: [None, None],
        retrofits: [None, None],
        api: sequence.api,
        in_rust_call: false,
        failures: Vec::new(),
    };
    let end = sequence.ops.len();
    for (index, op) in sequence.ops.iter().enumerate() {
        run.step(index, op);
    }
    for k in 0..2 {
        if run.slots[k].is_some() || run.retrofits[k].is_some() {
            run.step(end, &Op::Recover(Which::Slot(k)));
            run.step(end, &Op::Destroy(Which::Slot(k)));
        }
    }
    if c::dmsaa_live_objects() != live {
        run.failures.push(format!(
            "{} GL objects of the library's left after every handle was destroyed",
            c::dmsaa_live_objects() - live
        ));
    }
    let Run { host, failures, .. } = run;
    host.destroy(gl);
    reset(gl);
    failures
}

/// The smallest sequence found that still fails (dropping one call at a
/// time while a failure stays): the indices of the calls kept, and its
/// failures.
pub fn shrink(context: &HeadlessContext, sequence: &Sequence) -> (Vec<usize>, Vec<String>) {
    let mut keep: Vec<usize> = (0..sequence.ops.len()).collect();
    let mut failures = run_sequence(context, sequence);
    let mut i = keep.len();
    while i > 0 {
        i -= 1;
        let mut fewer = keep.clone();
        fewer.remove(i);
        let f = run_sequence(context, &sequence.only(&fewer));
        if !f.is_empty() {
            keep = fewer;
            failures = f;
        }
    }
    (keep, failures)
}

/// `keep` as the replay variable's value: `SEED:i,j,k`.
pub fn replay_value(seed: u64, keep: &[usize]) -> String {
    let list: Vec<String> = keep.iter().map(usize::to_string).collect();
    format!("{seed}:{}", list.join(","))
}
