//! The host whose G-buffer the calls retrofit: its attachments, its own
//! draw and clears, and the GL state it leaves behind between calls.

use deferred_msaa_testkit::Rng;
use glow::HasContext;

use super::sequence::*;

/// The host's G-buffer, its lighting output and the objects its state
/// binds.
pub(super) struct Host {
    pub(super) fbo: glow::Framebuffer,
    pub(super) light_fbo: glow::Framebuffer,
    pub(super) light: glow::Texture,
    /// Colour textures, then depth; `None` once deleted.
    pub(super) images: Vec<Option<glow::Texture>>,
    pub(super) colors: usize,
    pub(super) stencil: bool,
    pub(super) program: glow::Program,
    pub(super) vao: glow::VertexArray,
    pub(super) buffer: glow::Buffer,
    pub(super) spare: glow::Texture,
}

pub(super) const COLOR_FORMATS: [(u32, u32, u32); 3] = [
    (glow::RGBA16F, glow::RGBA, glow::FLOAT),
    (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE),
    (glow::RGBA16F, glow::RGBA, glow::FLOAT),
];

impl Host {
    pub(super) fn new(gl: &glow::Context, colors: usize, stencil: bool) -> Host {
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
    pub(super) fn specify(&mut self, gl: &glow::Context, k: usize, size: (i32, i32)) {
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
    pub(super) fn put_back(&mut self, gl: &glow::Context) {
        for k in 0..self.images.len() {
            self.specify(gl, k, SIZE);
        }
    }

    /// The framebuffer deleted and made again, as an engine does on a
    /// resize, every image attached again with the same draw buffers. GL
    /// need not give the freed name back (Mesa does not): the handles made
    /// for the old one cannot follow, and say so.
    pub(super) fn recreate(&mut self, gl: &glow::Context) {
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

    pub(super) fn delete(&mut self, gl: &glow::Context, k: usize) {
        if let Some(t) = self.images[k].take() {
            unsafe { gl.delete_texture(t) };
        }
    }

    pub(super) fn fbo_arg(&self, fbo: Fbo) -> u32 {
        match fbo {
            Fbo::Host => self.fbo.0.get(),
            Fbo::Light => self.light_fbo.0.get(),
            Fbo::Zero => 0,
            Fbo::NotAFramebuffer => NOT_A_FRAMEBUFFER,
        }
    }

    /// The uniform values a draw leaves: per colour attachment, then
    /// depth and stencil.
    pub(super) fn clear(gl: &glow::Context, colors: usize) {
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
    pub(super) fn read(&self, gl: &glow::Context) -> Vec<Vec<f32>> {
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

    pub(super) fn destroy(self, gl: &glow::Context) {
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

pub(super) fn host_program(gl: &glow::Context) -> glow::Program {
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
pub(super) fn dirty(gl: &glow::Context, host: &Host, seed: u64) {
    let mut rng = Rng::new(seed);
    let draw_buffers = unsafe { gl.get_parameter_i32(glow::MAX_DRAW_BUFFERS) }.max(1) as u32;
    let units =
        unsafe { gl.get_parameter_i32(glow::MAX_COMBINED_TEXTURE_IMAGE_UNITS) }.clamp(1, 32) as u32;
    let flip = |rng: &mut Rng| rng.below(2) == 0;
    unsafe {
        for _ in 0..1 + rng.below(8) {
            match rng.below(20) {
                18 | 19 if crate::common::gl_state::has_viewport_arrays(gl) => {
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
pub(super) fn reset(gl: &glow::Context) {
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
