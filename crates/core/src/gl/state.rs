//! The host's GL state that the crate's passes change, captured before and
//! put back after: the crate runs inside the host's context and must leave it
//! as it found it.

use crate::{Error, Result};
use glow::HasContext;
use std::ffi::c_void;
use std::num::NonZeroU32;
use std::sync::atomic::{AtomicPtr, Ordering};

/// Texture targets whose binding a pass may change on a unit.
const TEXTURE_TARGETS: [(u32, u32); 3] = [
    (glow::TEXTURE_2D, glow::TEXTURE_BINDING_2D),
    (glow::TEXTURE_2D_ARRAY, glow::TEXTURE_BINDING_2D_ARRAY),
    (
        glow::TEXTURE_2D_MULTISAMPLE,
        glow::TEXTURE_BINDING_2D_MULTISAMPLE,
    ),
];

/// Capabilities a full-screen pass must have off, and that are put back.
const PASS_OFF: [u32; 18] = [
    glow::BLEND,
    glow::CULL_FACE,
    glow::SCISSOR_TEST,
    glow::STENCIL_TEST,
    glow::SAMPLE_MASK,
    glow::SAMPLE_ALPHA_TO_COVERAGE,
    glow::SAMPLE_ALPHA_TO_ONE,
    glow::RASTERIZER_DISCARD,
    glow::COLOR_LOGIC_OP,
    glow::POLYGON_OFFSET_FILL,
    glow::CLIP_DISTANCE0,
    glow::CLIP_DISTANCE1,
    glow::CLIP_DISTANCE2,
    glow::CLIP_DISTANCE3,
    glow::CLIP_DISTANCE4,
    glow::CLIP_DISTANCE5,
    glow::CLIP_DISTANCE6,
    glow::CLIP_DISTANCE7,
];

/// `glIsEnabledi` and `glGetBooleani_v`, which glow does not wrap, as
/// [`load_state_functions`] stored them (null until then), and
/// `glGetFloati_v` and `glGetIntegeri_v` with room for four values, for the
/// viewport arrays of GL 4.1 (null where the loader has none).
static IS_ENABLEDI: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_BOOLEANI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_FLOATI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());
static GET_INTEGERI_V: AtomicPtr<c_void> = AtomicPtr::new(std::ptr::null_mut());

type IsEnabledi = unsafe extern "system" fn(target: u32, index: u32) -> u8;
type GetBooleaniV = unsafe extern "system" fn(target: u32, index: u32, data: *mut u8);
type GetFloatiV = unsafe extern "system" fn(target: u32, index: u32, data: *mut f32);
type GetIntegeriV = unsafe extern "system" fn(target: u32, index: u32, data: *mut i32);

/// Load the two GL 3.0 entry points glow does not wrap and the saved state
/// needs to read each draw buffer's blend enable and colour mask
/// (`glIsEnabledi`, `glGetBooleani_v`), through the host's loader, and,
/// where it has them, `glGetFloati_v` and `glGetIntegeri_v`, to read each
/// viewport, scissor box and scissor test of GL 4.1's viewport arrays. The
/// pointers are kept for the whole process: GL entry points from
/// `eglGetProcAddress` and `glXGetProcAddress` are the same for every
/// context. Call it once, with any context current, before making a
/// retrofit (the C API does). Without it the per-buffer blend enables are
/// read through `glGetIntegeri_v`, the colour mask is read and put back
/// as buffer 0's for every draw buffer, and with viewport arrays every
/// viewport, scissor box and scissor test as the first's.
///
/// Errors: [`Error::Unsupported`] naming the first function the loader
/// returned null for (none is stored then).
pub fn load_state_functions(mut loader: impl FnMut(&str) -> *const c_void) -> Result<()> {
    let is_enabledi = loader("glIsEnabledi");
    let get_booleani_v = loader("glGetBooleani_v");
    for (name, pointer) in [
        ("glIsEnabledi", is_enabledi),
        ("glGetBooleani_v", get_booleani_v),
    ] {
        if pointer.is_null() {
            return Err(Error::Unsupported {
                feature: format!("reading the host's per-draw-buffer state with {name}"),
                requires: "OpenGL 3.0".into(),
                found: format!("a loader that returns null for {name}"),
            });
        }
    }
    IS_ENABLEDI.store(is_enabledi.cast_mut(), Ordering::Release);
    GET_BOOLEANI_V.store(get_booleani_v.cast_mut(), Ordering::Release);
    GET_FLOATI_V.store(loader("glGetFloati_v").cast_mut(), Ordering::Release);
    GET_INTEGERI_V.store(loader("glGetIntegeri_v").cast_mut(), Ordering::Release);
    Ok(())
}

/// The stored `glIsEnabledi` and `glGetBooleani_v`, when both are there.
fn indexed_queries() -> Option<(IsEnabledi, GetBooleaniV)> {
    let is_enabledi = IS_ENABLEDI.load(Ordering::Acquire);
    let get_booleani_v = GET_BOOLEANI_V.load(Ordering::Acquire);
    if is_enabledi.is_null() || get_booleani_v.is_null() {
        return None;
    }
    // SAFETY: stored only by `load_state_functions`, non-null pointers the
    // loader returned for exactly these names, whose GL signatures these are.
    unsafe {
        Some((
            std::mem::transmute::<*mut c_void, IsEnabledi>(is_enabledi),
            std::mem::transmute::<*mut c_void, GetBooleaniV>(get_booleani_v),
        ))
    }
}

/// Every viewport, scissor box and scissor test of a context with viewport
/// arrays (GL 4.1 or `GL_ARB_viewport_array`), `0..GL_MAX_VIEWPORTS`:
/// `glViewport`, `glScissor` and `glEnable(GL_SCISSOR_TEST)` set them all.
#[derive(Clone, Debug, PartialEq)]
struct ViewportArrays {
    viewports: Vec<[f32; 4]>,
    scissors: Vec<[i32; 4]>,
    scissor_tests: Vec<bool>,
}

impl ViewportArrays {
    /// Read them; `None` without viewport arrays or without the loaded
    /// queries ([`load_state_functions`]).
    fn capture(gl: &glow::Context) -> Option<Self> {
        let version = gl.version();
        if (version.major, version.minor) < (4, 1)
            && !gl.supported_extensions().contains("GL_ARB_viewport_array")
        {
            return None;
        }
        let (is_enabledi, _) = indexed_queries()?;
        let (floats, ints) = (
            GET_FLOATI_V.load(Ordering::Acquire),
            GET_INTEGERI_V.load(Ordering::Acquire),
        );
        if floats.is_null() || ints.is_null() {
            return None;
        }
        // SAFETY: non-null pointers the loader returned for these names,
        // whose GL signatures these are; each query below writes four values.
        let (get_floati_v, get_integeri_v) = unsafe {
            (
                std::mem::transmute::<*mut c_void, GetFloatiV>(floats),
                std::mem::transmute::<*mut c_void, GetIntegeriV>(ints),
            )
        };
        unsafe {
            let count = gl.get_parameter_i32(glow::MAX_VIEWPORTS).clamp(1, 64) as u32;
            Some(ViewportArrays {
                viewports: (0..count)
                    .map(|i| {
                        let mut v = [0f32; 4];
                        get_floati_v(glow::VIEWPORT, i, v.as_mut_ptr());
                        v
                    })
                    .collect(),
                scissors: (0..count)
                    .map(|i| {
                        let mut v = [0i32; 4];
                        get_integeri_v(glow::SCISSOR_BOX, i, v.as_mut_ptr());
                        v
                    })
                    .collect(),
                scissor_tests: (0..count)
                    .map(|i| is_enabledi(glow::SCISSOR_TEST, i) != 0)
                    .collect(),
            })
        }
    }

    /// Put them back (`glViewportArrayv`, `glScissorArrayv`, `glEnablei`).
    fn restore(&self, gl: &glow::Context) {
        unsafe {
            gl.viewport_f32_slice(0, self.viewports.len() as i32, &self.viewports);
            gl.scissor_slice(0, self.scissors.len() as i32, &self.scissors);
            for (i, &on) in self.scissor_tests.iter().enumerate() {
                if on {
                    gl.enable_draw_buffer(glow::SCISSOR_TEST, i as u32);
                } else {
                    gl.disable_draw_buffer(glow::SCISSOR_TEST, i as u32);
                }
            }
        }
    }
}

/// Each draw buffer's blend enable and colour mask, `0..GL_MAX_DRAW_BUFFERS`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DrawBufferState {
    /// `glIsEnabledi(GL_BLEND, i)`.
    pub blend: Vec<bool>,
    /// `glGetBooleani_v(GL_COLOR_WRITEMASK, i)`; `None` where the indexed
    /// query is not loaded ([`load_state_functions`]), and the
    /// non-indexed mask, buffer 0's, is what is read and put back.
    pub color_masks: Option<Vec<[bool; 4]>>,
    /// `glGetBooleanv(GL_COLOR_WRITEMASK)`: buffer 0's.
    pub color_mask: [bool; 4],
}

impl DrawBufferState {
    /// Read it.
    pub fn capture(gl: &glow::Context) -> Self {
        unsafe {
            let buffers = gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS).clamp(1, 32) as u32;
            let mut mask = [0i32; 4];
            gl.get_parameter_i32_slice(glow::COLOR_WRITEMASK, &mut mask);
            let color_mask = mask.map(|c| c != 0);
            match indexed_queries() {
                Some((is_enabledi, get_booleani_v)) => DrawBufferState {
                    blend: (0..buffers)
                        .map(|i| is_enabledi(glow::BLEND, i) != 0)
                        .collect(),
                    color_masks: Some(
                        (0..buffers)
                            .map(|i| {
                                let mut m = [0u8; 4];
                                get_booleani_v(glow::COLOR_WRITEMASK, i, m.as_mut_ptr());
                                m.map(|c| c != 0)
                            })
                            .collect(),
                    ),
                    color_mask,
                },
                None => DrawBufferState {
                    // One value per buffer: glow's single-integer query fits.
                    blend: (0..buffers)
                        .map(|i| gl.get_parameter_indexed_i32(glow::BLEND, i) != 0)
                        .collect(),
                    color_masks: None,
                    color_mask,
                },
            }
        }
    }

    /// Put it back, buffer by buffer (`glEnablei`/`glDisablei`,
    /// `glColorMaski`).
    pub fn restore(&self, gl: &glow::Context) {
        unsafe {
            for (i, &on) in self.blend.iter().enumerate() {
                if on {
                    gl.enable_draw_buffer(glow::BLEND, i as u32);
                } else {
                    gl.disable_draw_buffer(glow::BLEND, i as u32);
                }
            }
            match &self.color_masks {
                Some(masks) => {
                    for (i, [r, g, b, a]) in masks.iter().copied().enumerate() {
                        gl.color_mask_draw_buffer(i as u32, r, g, b, a);
                    }
                }
                None => {
                    let [r, g, b, a] = self.color_mask;
                    gl.color_mask(r, g, b, a);
                }
            }
        }
    }
}

/// Stencil state by face (front, back).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct StencilFaces {
    /// Func, reference and value mask; `None` where the pass leaves them
    /// alone (see [`SavedState::keep_stencil_func`]).
    func: Option<[[i32; 3]; 2]>,
    /// Fail, depth-fail and pass operations, write mask.
    ops: [[i32; 4]; 2],
}

/// The state a pass changes: bindings, tests, masks and the texture
/// bindings of the units it uses. Dropped without [`Guard`], nothing is put
/// back; through [`SavedState::guard`], everything is, on every way out.
pub struct SavedState {
    framebuffer: i32,
    read_framebuffer: i32,
    /// `PASS_OFF`'s capabilities but `GL_BLEND` (per draw buffer, in
    /// `draw_buffers`), `GL_DEPTH_TEST` and `GL_FRAMEBUFFER_SRGB`.
    capabilities: Vec<(u32, bool)>,
    draw_buffers: DrawBufferState,
    scissor_box: [i32; 4],
    polygon_mode: i32,
    program: i32,
    vertex_array: i32,
    active_texture: i32,
    viewport: [i32; 4],
    /// Every viewport, scissor box and scissor test, with viewport arrays.
    viewport_arrays: Option<ViewportArrays>,
    depth_func: i32,
    depth_mask: bool,
    stencil: StencilFaces,
    /// `GL_STENCIL_CLEAR_VALUE` (the stencil copy's bit passes clear).
    stencil_clear: i32,
    /// Per texture unit `0..units`: the 2D, 2D-array and multisample bindings.
    textures: Vec<[i32; 3]>,
}

/// Something captured that can be put back ([`Guard`]).
pub trait Restore {
    /// Put it back.
    fn restore(&self, gl: &glow::Context);
}

/// Puts captured state back when dropped: at the end of the scope, on an
/// early return with `?`, and while a panic unwinds, so that no way out of
/// a call leaves the host's state changed.
pub struct Guard<'a, S: Restore> {
    gl: &'a glow::Context,
    state: S,
}

impl<S: Restore> Drop for Guard<'_, S> {
    fn drop(&mut self) {
        self.state.restore(self.gl);
    }
}

impl<S: Restore> std::ops::Deref for Guard<'_, S> {
    type Target = S;
    fn deref(&self) -> &S {
        &self.state
    }
}

impl<S: Restore> std::ops::DerefMut for Guard<'_, S> {
    fn deref_mut(&mut self) -> &mut S {
        &mut self.state
    }
}

impl SavedState {
    /// Capture the state, with the texture bindings of units `0..units`.
    /// The stencil function and reference are not captured (and so not put
    /// back): a pass that sets them calls [`SavedState::keep_stencil_func`].
    pub fn capture(gl: &glow::Context, units: u32) -> Self {
        unsafe {
            let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE);
            let textures = (0..units)
                .map(|k| {
                    gl.active_texture(glow::TEXTURE0 + k);
                    TEXTURE_TARGETS.map(|(_, binding)| gl.get_parameter_i32(binding))
                })
                .collect();
            gl.active_texture(active as u32);
            let mut viewport = [0; 4];
            gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
            let mut scissor_box = [0; 4];
            gl.get_parameter_i32_slice(glow::SCISSOR_BOX, &mut scissor_box);
            let mut polygon_mode = [glow::FILL as i32; 2];
            gl.get_parameter_i32_slice(glow::POLYGON_MODE, &mut polygon_mode);
            let capabilities = PASS_OFF
                .iter()
                .filter(|&&cap| cap != glow::BLEND)
                .chain(&[glow::DEPTH_TEST, glow::FRAMEBUFFER_SRGB])
                .map(|&cap| (cap, gl.is_enabled(cap)))
                .collect();
            let ops = |[fail, zfail, zpass, write]: [u32; 4]| {
                [fail, zfail, zpass, write].map(|p| gl.get_parameter_i32(p))
            };
            SavedState {
                framebuffer: gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING),
                read_framebuffer: gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING),
                capabilities,
                draw_buffers: DrawBufferState::capture(gl),
                scissor_box,
                polygon_mode: polygon_mode[0],
                program: gl.get_parameter_i32(glow::CURRENT_PROGRAM),
                vertex_array: gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING),
                active_texture: active,
                textures,
                viewport,
                viewport_arrays: ViewportArrays::capture(gl),
                depth_func: gl.get_parameter_i32(glow::DEPTH_FUNC),
                depth_mask: gl.get_parameter_i32(glow::DEPTH_WRITEMASK) != 0,
                stencil_clear: gl.get_parameter_i32(glow::STENCIL_CLEAR_VALUE),
                stencil: StencilFaces {
                    func: None,
                    ops: [
                        ops([
                            glow::STENCIL_FAIL,
                            glow::STENCIL_PASS_DEPTH_FAIL,
                            glow::STENCIL_PASS_DEPTH_PASS,
                            glow::STENCIL_WRITEMASK,
                        ]),
                        ops([
                            glow::STENCIL_BACK_FAIL,
                            glow::STENCIL_BACK_PASS_DEPTH_FAIL,
                            glow::STENCIL_BACK_PASS_DEPTH_PASS,
                            glow::STENCIL_BACK_WRITEMASK,
                        ]),
                    ],
                },
            }
        }
    }

    /// Capture the stencil function, reference and value mask of both
    /// faces too, for a pass that sets them. GL clamps a query of the
    /// reference to the stencil bits of the bound draw framebuffer (0 bits
    /// on a default framebuffer without stencil: the reference would read
    /// 0), so it is read with a framebuffer of an 8-bit stencil bound, a
    /// 1x1 `GL_DEPTH24_STENCIL8` renderbuffer made for the read and deleted
    /// (the bindings it changes are put back): exact for every reference in
    /// `0..=255`; one outside that range comes back clamped to it, which no
    /// 8-bit stencil test tells apart.
    ///
    /// Errors: [`Error::Create`] when the probe cannot be made; nothing is
    /// captured then.
    pub fn keep_stencil_func(&mut self, gl: &glow::Context) -> Result<()> {
        unsafe {
            let draw = gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING);
            let renderbuffer = gl.get_parameter_i32(glow::RENDERBUFFER_BINDING);
            let create = |what: &str, reason: String| Error::Create {
                what: format!("{what} (to read the host's stencil reference)"),
                reason,
            };
            let rb = gl
                .create_renderbuffer()
                .map_err(|reason| create("a 1x1 stencil renderbuffer", reason))?;
            let fbo = match gl.create_framebuffer() {
                Ok(fbo) => fbo,
                Err(reason) => {
                    gl.delete_renderbuffer(rb);
                    return Err(create("a 1x1 framebuffer", reason));
                }
            };
            gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
            gl.renderbuffer_storage(glow::RENDERBUFFER, glow::DEPTH24_STENCIL8, 1, 1);
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(fbo));
            gl.framebuffer_renderbuffer(
                glow::DRAW_FRAMEBUFFER,
                glow::DEPTH_STENCIL_ATTACHMENT,
                glow::RENDERBUFFER,
                Some(rb),
            );
            let read = |[func, reference, mask]: [u32; 3]| {
                [func, reference, mask].map(|p| gl.get_parameter_i32(p))
            };
            self.stencil.func = Some([
                read([
                    glow::STENCIL_FUNC,
                    glow::STENCIL_REF,
                    glow::STENCIL_VALUE_MASK,
                ]),
                read([
                    glow::STENCIL_BACK_FUNC,
                    glow::STENCIL_BACK_REF,
                    glow::STENCIL_BACK_VALUE_MASK,
                ]),
            ]);
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, live_framebuffer(gl, draw));
            gl.bind_renderbuffer(
                glow::RENDERBUFFER,
                NonZeroU32::new(renderbuffer as u32)
                    .map(glow::NativeRenderbuffer)
                    .filter(|&r| gl.is_renderbuffer(r)),
            );
            gl.delete_framebuffer(fbo);
            gl.delete_renderbuffer(rb);
        }
        Ok(())
    }

    /// Put it back whenever the guard is dropped ([`Guard`]).
    pub fn guard(self, gl: &glow::Context) -> Guard<'_, Self> {
        Guard { gl, state: self }
    }

    /// Put everything captured back.
    pub fn restore(&self, gl: &glow::Context) {
        <Self as Restore>::restore(self, gl);
    }

    /// Set what a full-screen pass needs whatever the host left on: no
    /// blending, culling, scissor, stencil, sample masking or
    /// alpha-to-coverage, logic op, polygon offset or clip distances,
    /// rasterisation on, filled polygons, every colour channel written.
    /// Depth testing and `GL_FRAMEBUFFER_SRGB` are the pass's own choice.
    pub fn prepare_fullscreen_pass(gl: &glow::Context) {
        unsafe {
            for cap in PASS_OFF {
                gl.disable(cap);
            }
            gl.polygon_mode(glow::FRONT_AND_BACK, glow::FILL);
            gl.color_mask(true, true, true, true);
        }
    }
}

impl Restore for SavedState {
    fn restore(&self, gl: &glow::Context) {
        fn set(gl: &glow::Context, cap: u32, on: bool) {
            unsafe { if on { gl.enable(cap) } else { gl.disable(cap) } }
        }
        unsafe {
            gl.bind_framebuffer(
                glow::DRAW_FRAMEBUFFER,
                live_framebuffer(gl, self.framebuffer),
            );
            gl.bind_framebuffer(
                glow::READ_FRAMEBUFFER,
                live_framebuffer(gl, self.read_framebuffer),
            );
            let [x, y, w, h] = self.scissor_box;
            gl.scissor(x, y, w, h);
            gl.polygon_mode(glow::FRONT_AND_BACK, self.polygon_mode as u32);
            gl.use_program(
                NonZeroU32::new(self.program as u32)
                    .map(glow::NativeProgram)
                    .filter(|&p| gl.is_program(p)),
            );
            gl.bind_vertex_array(
                NonZeroU32::new(self.vertex_array as u32).map(glow::NativeVertexArray),
            );
            for (k, bindings) in self.textures.iter().enumerate() {
                gl.active_texture(glow::TEXTURE0 + k as u32);
                for ((target, _), raw) in TEXTURE_TARGETS.iter().zip(bindings) {
                    gl.bind_texture(*target, live_texture(gl, *raw));
                }
            }
            gl.active_texture(self.active_texture as u32);
            gl.viewport(
                self.viewport[0],
                self.viewport[1],
                self.viewport[2],
                self.viewport[3],
            );
            gl.depth_func(self.depth_func as u32);
            gl.depth_mask(self.depth_mask);
            gl.clear_stencil(self.stencil_clear);
            for (k, face) in [glow::FRONT, glow::BACK].into_iter().enumerate() {
                if let Some(func) = self.stencil.func {
                    let [func, reference, mask] = func[k];
                    gl.stencil_func_separate(face, func as u32, reference, mask as u32);
                }
                let [fail, zfail, zpass, write] = self.stencil.ops[k];
                gl.stencil_op_separate(face, fail as u32, zfail as u32, zpass as u32);
                gl.stencil_mask_separate(face, write as u32);
            }
        }
        self.draw_buffers.restore(gl);
        for &(cap, on) in &self.capabilities {
            set(gl, cap, on);
        }
        // After `glViewport`, `glScissor` and `glEnable(GL_SCISSOR_TEST)`,
        // which set every viewport to the first's.
        if let Some(arrays) = &self.viewport_arrays {
            arrays.restore(gl);
        }
    }
}

/// Everything set-up calls (creating textures, buffers, framebuffers and
/// programs, probing formats, introspecting the host's framebuffer) may
/// touch, for a retrofit made or rebuilt in the middle of the host's frame:
/// [`SavedState`] over every texture unit, and the renderbuffer, buffer and
/// pixel-store state.
pub struct SetupState {
    passes: SavedState,
    renderbuffer: i32,
    buffers: [(u32, i32); 4],
    pixel_store: [(u32, i32); 4],
    /// The active unit's other texture targets.
    other_textures: [(u32, i32); 3],
}

impl SetupState {
    /// Capture it.
    pub fn capture(gl: &glow::Context) -> Self {
        unsafe {
            let units = gl
                .get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS)
                .clamp(1, 32) as u32;
            let get = |pname: u32| gl.get_parameter_i32(pname);
            SetupState {
                passes: SavedState::capture(gl, units),
                renderbuffer: get(glow::RENDERBUFFER_BINDING),
                buffers: [
                    (glow::ARRAY_BUFFER, get(glow::ARRAY_BUFFER_BINDING)),
                    (
                        glow::PIXEL_PACK_BUFFER,
                        get(glow::PIXEL_PACK_BUFFER_BINDING),
                    ),
                    (
                        glow::PIXEL_UNPACK_BUFFER,
                        get(glow::PIXEL_UNPACK_BUFFER_BINDING),
                    ),
                    (glow::UNIFORM_BUFFER, get(glow::UNIFORM_BUFFER_BINDING)),
                ],
                pixel_store: [
                    glow::PACK_ALIGNMENT,
                    glow::UNPACK_ALIGNMENT,
                    glow::PACK_ROW_LENGTH,
                    glow::UNPACK_ROW_LENGTH,
                ]
                .map(|p| (p, get(p))),
                other_textures: [
                    (
                        glow::TEXTURE_RECTANGLE,
                        get(glow::TEXTURE_BINDING_RECTANGLE),
                    ),
                    (glow::TEXTURE_CUBE_MAP, get(glow::TEXTURE_BINDING_CUBE_MAP)),
                    (glow::TEXTURE_3D, get(glow::TEXTURE_BINDING_3D)),
                ],
            }
        }
    }

    /// [`SavedState::keep_stencil_func`], for set-up calls whose passes set
    /// the stencil function.
    pub fn keep_stencil_func(&mut self, gl: &glow::Context) -> Result<()> {
        self.passes.keep_stencil_func(gl)
    }

    /// Put it back whenever the guard is dropped ([`Guard`]).
    pub fn guard(self, gl: &glow::Context) -> Guard<'_, Self> {
        Guard { gl, state: self }
    }

    /// Put it back.
    pub fn restore(&self, gl: &glow::Context) {
        <Self as Restore>::restore(self, gl);
    }
}

impl Restore for SetupState {
    fn restore(&self, gl: &glow::Context) {
        self.passes.restore(gl);
        unsafe {
            gl.bind_renderbuffer(
                glow::RENDERBUFFER,
                NonZeroU32::new(self.renderbuffer as u32)
                    .map(glow::NativeRenderbuffer)
                    .filter(|&r| gl.is_renderbuffer(r)),
            );
            for (target, raw) in self.buffers {
                gl.bind_buffer(
                    target,
                    NonZeroU32::new(raw as u32)
                        .map(glow::NativeBuffer)
                        .filter(|&b| gl.is_buffer(b)),
                );
            }
            for (pname, value) in self.pixel_store {
                gl.pixel_store_i32(pname, value);
            }
            for (target, raw) in self.other_textures {
                gl.bind_texture(target, live_texture(gl, raw));
            }
        }
    }
}

/// The framebuffer `raw` names, if it still exists: a binding captured
/// before a call that deleted that object goes back to 0 (binding a deleted
/// name is `GL_INVALID_OPERATION`).
pub(crate) fn live_framebuffer(gl: &glow::Context, raw: i32) -> Option<glow::Framebuffer> {
    NonZeroU32::new(raw as u32)
        .map(glow::NativeFramebuffer)
        .filter(|&f| unsafe { gl.is_framebuffer(f) })
}

/// The texture `raw` names, if it still exists ([`live_framebuffer`]).
pub(crate) fn live_texture(gl: &glow::Context, raw: i32) -> Option<glow::Texture> {
    NonZeroU32::new(raw as u32)
        .map(glow::NativeTexture)
        .filter(|&t| unsafe { gl.is_texture(t) })
}
