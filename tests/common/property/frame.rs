//! One frame through the retrofit: the host's random state around each
//! call, the checks of its state and errors, and the two lightings.

use super::geometry::{Geometry, Plane, compare, read_planes};
use crate::common::gl_state::GlState;
use deferred_msaa::{Frame, MsaaRetrofit};
use deferred_msaa_testkit::Rng;
use deferred_msaa_testkit::random_host::RandomHost;
use glow::HasContext;

/// The host framebuffer's own set-up: what is attached where, its draw
/// buffers and read buffer. Read with the bindings put back.
pub(super) fn fbo_setup(gl: &glow::Context, fbo: glow::Framebuffer) -> Vec<i32> {
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

/// The host's own state, random: what it leaves bound and enabled when it
/// calls the retrofit.
pub(super) fn clutter(gl: &glow::Context, rng: &mut Rng, host: &RandomHost, geometry: &Geometry) {
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

pub(super) fn gl_error(gl: &glow::Context, after: &str, failures: &mut Vec<String>) {
    let e = unsafe { gl.get_error() };
    if e != glow::NO_ERROR {
        failures.push(format!("glGetError is 0x{e:04X} after {after}"));
        while unsafe { gl.get_error() } != glow::NO_ERROR {}
    }
}

/// Call `f` in the host's random state and check what it left: the host's
/// state, its framebuffer's set-up, glGetError.
pub(super) fn around<T>(
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

pub(super) fn frame(host: &RandomHost) -> Frame {
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
pub(super) struct Lit {
    texture: glow::Texture,
    fbo: glow::Framebuffer,
}

/// What the host's first and second lighting write.
pub(super) const LIT: [[u8; 4]; 2] = [[51, 102, 204, 255], [255, 0, 102, 255]];

impl Lit {
    pub(super) fn new(gl: &glow::Context, w: u32, h: u32) -> Lit {
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
    pub(super) fn light(&self, gl: &glow::Context, w: u32, h: u32, colour: [u8; 4]) {
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

    pub(super) fn read(&self, gl: &glow::Context, w: u32, h: u32) -> Vec<u8> {
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

    pub(super) fn destroy(self, gl: &glow::Context) {
        unsafe {
            gl.delete_framebuffer(self.fbo);
            gl.delete_texture(self.texture);
        }
    }
}

/// Draw, resolve and compare; with two layers, the three calls around the
/// host's lighting too.
pub(super) fn frame_checks(
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
    let fbo = match msaa.begin_frame(gl) {
        Ok(fbo) => fbo,
        Err(e) => {
            failures.push(format!("{what}: begin_frame failed: {e}"));
            return;
        }
    };
    geometry.draw(gl, host, fbo);
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
