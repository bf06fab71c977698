//! The host zoo: small deferred renderers written the way the engines and
//! tutorials they stand for write them (their own FBO set-up with raw glow
//! calls, their own model and lighting shaders), each retrofitted with the
//! two integration lines and nothing else changed. For each host
//! (`tests/zoo/*.rs`, module docs say which habit it stands for):
//!
//! - the retrofit accepts the host's G-buffer (or refuses in one line that
//!   names the attachment and the GL enum);
//! - inside every face (pixels whose 3x3 neighbourhood is one face in the
//!   host's own render), every attachment the host writes a constant value
//!   to holds, bit for bit, what the host's own no-MSAA render holds there;
//!   varying attachments stay within the no-MSAA 3x3 range; attachments the
//!   geometry pass does not write are untouched;
//! - the lit image is closer (FLIP mean) to the host's own 16x supersampled
//!   image than the host's image without MSAA, with no halo pixels the
//!   no-MSAA image does not have (a halo: brighter than the 16x image by
//!   more than the pixel's coverage quantisation explains,
//!   `harness/halo.rs`);
//! - the GL state the host left is as it was after `new` and `resolve`,
//!   and the host's lighting, which bound its G-buffer to texture units
//!   once at start-up, still works;
//! - no GL object of the crate's is left after `destroy`.
//!
//! `ZOO_DUMP=1` writes the three images of each host under the target's
//! test temporary folder.

use crate::common;

// The hosts are this module's children; the tests below name them `zoo::…`.
use crate::zoo;

pub mod harness;
pub mod scene;

pub mod fyrox;
pub mod holes;
pub mod layered;
pub mod learnopengl;
pub mod pbr;
pub mod picking;
pub mod stencil;

/// What cannot work is refused with the typed error, in one line naming
/// the attachment and the GL enum: a host whose G-buffer is already
/// multisampled (`GL_TEXTURE_2D_MULTISAMPLE`) has no single-sample texture
/// to resolve into.
#[test]
fn an_already_multisampled_gbuffer_is_refused_in_one_line() {
    use glow::HasContext;
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    unsafe {
        let colour = gl.create_texture().unwrap();
        gl.bind_texture(glow::TEXTURE_2D, Some(colour));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::RGBA8 as i32,
            32,
            16,
            0,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelUnpackData::Slice(None),
        );
        let multisampled = gl.create_texture().unwrap();
        gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(multisampled));
        gl.tex_image_2d_multisample(
            glow::TEXTURE_2D_MULTISAMPLE,
            4,
            glow::RGBA16F as i32,
            32,
            16,
            true,
        );
        let depth = gl.create_texture().unwrap();
        gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, Some(depth));
        gl.tex_image_2d_multisample(
            glow::TEXTURE_2D_MULTISAMPLE,
            4,
            glow::DEPTH_COMPONENT24 as i32,
            32,
            16,
            true,
        );
        gl.bind_texture(glow::TEXTURE_2D_MULTISAMPLE, None);
        gl.bind_texture(glow::TEXTURE_2D, None);
        let fbo = gl.create_framebuffer().unwrap();
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT1,
            glow::TEXTURE_2D_MULTISAMPLE,
            Some(multisampled),
            0,
        );
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::DEPTH_ATTACHMENT,
            glow::TEXTURE_2D_MULTISAMPLE,
            Some(depth),
            0,
        );
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        let error =
            deferred_msaa::MsaaRetrofit::new(gl, fbo, &deferred_msaa::RetrofitOptions::default())
                .expect_err("an already multisampled G-buffer");
        zoo::harness::assert_refusal(&error, "GL_COLOR_ATTACHMENT1", "GL_TEXTURE_2D_MULTISAMPLE");
        gl.delete_framebuffer(fbo);
        for t in [colour, multisampled, depth] {
            gl.delete_texture(t);
        }
    }
    assert_eq!(deferred_msaa::gl::live_objects().total(), 0);
}

/// With the second layer, no host's retrofitted image has a halo pixel
/// (luminance over the brightest its surfaces give at its sample coverage
/// by more than the threshold: `harness/halo.rs`) that its own image
/// without MSAA does not have, and every other check of
/// the harness holds around the three second-layer calls. With one layer
/// it does not hold: on silhouettes against the brighter sky, a pixel whose
/// samples are half background takes the median reference's surface whole,
/// the background, where the host's own pixel centre hits the geometry
/// (`one_layer_gains_halo_pixels` shows it).
#[test]
fn no_host_gains_halo_pixels_with_two_layers() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let outcomes = [
        zoo::learnopengl::outcome_world_key(&ctx, 2),
        zoo::learnopengl::outcome_depth_key(&ctx, 2),
        zoo::stencil::outcome(&ctx, 2),
        zoo::pbr::outcome(&ctx, 2),
        zoo::layered::outcome(&ctx, 2),
        zoo::picking::outcome(&ctx, 2),
        zoo::holes::outcome(&ctx, 2),
        zoo::fyrox::outcome(&ctx, 2),
    ];
    for outcome in &outcomes {
        outcome.assert_ok();
    }
    let failures: Vec<String> = outcomes
        .iter()
        .filter_map(|o| o.halo_failure.clone().map(|f| format!("{}: {f}", o.host)))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The halo check catches a real halo: the tutorial's program with a small
/// bright light in the gap behind the floating triangle, its G-buffer
/// resolved as a blit resolves it (every sample averaged, positions and
/// normals too), lights averaged positions between the triangle's edge and
/// the panel, light no mix of the pixel's own surfaces at its coverage
/// gives; resolved by the median, it has fewer. (Were this to stop
/// holding, the halo check, which forgives coverage quantisation, would
/// test nothing.)
#[test]
fn a_blit_resolved_gbuffer_has_halo_pixels() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let averaged = zoo::learnopengl::outcome_gap_lit(&ctx, true);
    if let Some(why) = &averaged.not_run {
        // The GL 3.2 floor run: the tutorial's shaders are GLSL 3.30.
        eprintln!("{}: {why}", averaged.host);
        return;
    }
    let median = zoo::learnopengl::outcome_gap_lit(&ctx, false);
    for o in [&averaged, &median] {
        eprintln!(
            "{}: {} halo pixels, {} new over its image without MSAA ({} over the 16x image, quantisation included)",
            o.host, o.halos_resolved, o.new_halos, o.over_reference
        );
    }
    assert!(
        averaged.halo_failure.is_some(),
        "{}: a blit-resolved G-buffer shows no new halo pixel",
        averaged.host
    );
    assert!(
        median.new_halos < averaged.new_halos,
        "the median resolve gains as many halo pixels ({}) as the averaged one ({})",
        median.new_halos,
        averaged.new_halos
    );
}

/// What the second layer mends: with one layer, silhouette pixels whose
/// samples are half background take the median reference's surface whole,
/// and some host's image gains halo pixels its own image does not have.
/// (Were this to stop holding, the halo check above would test nothing.)
#[test]
fn one_layer_gains_halo_pixels() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let outcomes = [
        zoo::learnopengl::outcome_world_key(&ctx, 1),
        zoo::stencil::outcome(&ctx, 1),
        zoo::pbr::outcome(&ctx, 1),
        zoo::layered::outcome(&ctx, 1),
        zoo::picking::outcome(&ctx, 1),
        zoo::holes::outcome(&ctx, 1),
        zoo::fyrox::outcome(&ctx, 1),
    ];
    for o in &outcomes {
        eprintln!("{}: {} new halo pixels with one layer", o.host, o.new_halos);
    }
    assert!(outcomes.iter().any(|o| o.new_halos > 0));
}
