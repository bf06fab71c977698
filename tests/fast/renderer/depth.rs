//! Depth: reversed-Z against standard depth on every built-in scene, a far
//! scene with FreeSpace Open's layout, and the host's depth state left as
//! the renderer found it.

use super::*;

/// Read a texture of the renderer back (row 0 at the top).
fn read_texture(
    gl: &glow::Context,
    texture: deferred_msaa_lab::gl::TextureRef,
) -> deferred_msaa_lab::readback::SampleImage {
    let mut readback = Readback::new(gl).expect("readback");
    let img = readback.read(gl, texture, 1).expect("reading a texture");
    readback.destroy(gl);
    img
}

fn with_depth(mode: DepthMode, aa: AaMode) -> RenderOptions {
    RenderOptions {
        depth_mode: mode,
        ..options(aa)
    }
}

#[test]
fn far_scene_keeps_its_model_with_reversed_z_and_warns_with_the_freespace_layout() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let clip_control = Capabilities::query(gl).clip_control;
    let scene = Scene::load("builtin:far").expect("scene");

    // The recommended layout, Auto: reversed-Z where the context allows it.
    let mut renderer = renderer(&ctx, &scene, &options(median()));
    if clip_control {
        assert_eq!(renderer.depth_mode(), DepthMode::Reversed);
        assert_eq!(renderer.clear_depth(), 0.0);
        assert!(renderer.warnings().is_empty(), "{:#?}", renderer.warnings());
        let frame = renderer.resolve_frame();
        assert_eq!(frame.depth_mode, deferred_msaa::DepthMode::ReversedZ);
        let (projection, _) = frame.depth_terms().expect("a perspective projection");
        assert!(projection.zero_to_one && projection.clear_depth == 0.0);
        assert_eq!(projection.p22, 0.0, "an infinite far plane");
        let img = render_checked(gl, &mut renderer, "far, reversed-Z");
        save(&img, "far-reversed");
        // The model, not background, covers most of the view: its depth is
        // not the clear depth and its positions are finite and 200 km away.
        let depth = read_texture(gl, TextureRef::from(&renderer.gbuffer().depth));
        let k = GBufferLayout::recommended()
            .index_of("position")
            .expect("position");
        let position = read_texture(gl, TextureRef::from(&renderer.gbuffer().colors[k]));
        let model: Vec<usize> = (0..(W * H) as usize)
            .filter(|&i| depth.data[i * 4] != 0.0)
            .collect();
        assert!(
            model.len() > (W * H) as usize / 20,
            "only {} of {} pixels show the model",
            model.len(),
            W * H
        );
        for &i in &model {
            let z = -position.data[i * 4 + 2];
            assert!((1.9e5..2.1e5).contains(&z), "pixel {i}: view depth {z}");
        }
    } else {
        // Without glClipControl the standard float depth loses the model, and says so.
        assert_eq!(renderer.depth_mode(), DepthMode::Standard);
        assert!(!renderer.warnings().is_empty());
        let e = Renderer::new(
            gl,
            |n| ctx.get_proc_address(n),
            &scene,
            &with_depth(DepthMode::Reversed, median()),
        )
        .expect_err("reversed-Z without glClipControl");
        assert!(
            matches!(e, Error::Core(CoreError::Unsupported { .. })),
            "{e}"
        );
    }
    renderer.destroy(gl);

    // FreeSpace Open's layout (FP16 positions, D24) in standard depth warns
    // about both, before anything is allocated.
    let fso = RenderOptions {
        layout: GBufferLayout::freespace_open(),
        ..with_depth(DepthMode::Standard, median())
    };
    let mut renderer =
        Renderer::new(gl, |n| ctx.get_proc_address(n), &scene, &fso).expect("renderer");
    assert_eq!(renderer.depth_mode(), DepthMode::Standard);
    let warnings = renderer.warnings().to_vec();
    assert_eq!(warnings.len(), 2, "{warnings:#?}");
    assert!(
        warnings[0].contains("65504") && warnings[0].contains("position"),
        "{warnings:#?}"
    );
    assert!(warnings[1].contains("DEPTH_COMPONENT24"), "{warnings:#?}");
    renderer.render(gl).expect("a frame, warned or not");
    // Switching back to the recommended layout clears them (when reversed-Z is there).
    renderer
        .set_options(gl, &options(median()))
        .expect("recommended layout");
    assert_eq!(renderer.warnings().is_empty(), clip_control);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn every_builtin_scene_looks_the_same_with_reversed_and_standard_depth() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    if !Capabilities::query(gl).clip_control {
        let scene = Scene::load("builtin:box").expect("scene");
        let e = Renderer::new(
            gl,
            |n| ctx.get_proc_address(n),
            &scene,
            &with_depth(DepthMode::Reversed, median()),
        )
        .expect_err("reversed-Z without glClipControl");
        assert!(e.to_string().contains("glClipControl"), "{e}");
        return;
    }
    for name in Scene::builtin_names() {
        let scene = Scene::load(&format!("builtin:{name}")).expect("builtin scene");
        let mut renderer = renderer(&ctx, &scene, &with_depth(DepthMode::Reversed, median()));
        assert_eq!(renderer.depth_mode(), DepthMode::Reversed);
        assert!(
            renderer.warnings().is_empty(),
            "{name}: {:#?}",
            renderer.warnings()
        );
        let reversed = render_checked(gl, &mut renderer, &format!("{name} reversed"));
        let position = |r: &Renderer| {
            let k = r.options().layout.index_of("position").expect("position");
            read_texture(gl, TextureRef::from(&r.gbuffer().colors[k]))
        };
        let reversed_position = position(&renderer);

        // The same renderer switched to standard depth: nothing is rebuilt.
        renderer
            .set_options(gl, &with_depth(DepthMode::Standard, median()))
            .expect("standard depth");
        assert_eq!(renderer.depth_mode(), DepthMode::Standard);
        assert_eq!(renderer.clear_depth(), 1.0);
        if *name == "far" {
            // 200 km away, standard float depth rounds the model to the
            // clear depth: the precision check says so (and the image may
            // lose the model), but the frame stays finite.
            assert!(
                !renderer.warnings().is_empty(),
                "far: no warning in standard depth"
            );
            renderer.render(gl).expect("far, standard depth");
            let hdr = read_texture(gl, renderer.hdr_texture());
            assert!(
                hdr.data.iter().all(|v| v.is_finite()),
                "far: non-finite HDR values"
            );
            renderer.destroy(gl);
            continue;
        }
        assert!(
            renderer.warnings().is_empty(),
            "{name}: {:#?}",
            renderer.warnings()
        );
        let standard = render_checked(gl, &mut renderer, &format!("{name} standard"));
        save(&reversed, &format!("{name}-reversed"));
        save(&standard, &format!("{name}-standard"));
        // The same surfaces at the same places: resolved positions agree.
        let standard_position = position(&renderer);
        let off = reversed_position
            .data
            .chunks_exact(4)
            .zip(standard_position.data.chunks_exact(4))
            .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3 * (1.0 + a[2].abs())))
            .count();
        let flip = deferred_msaa_lab::compare::flip(&standard, &reversed).expect("same size");
        eprintln!(
            "{name}: FLIP mean {:.5} (max {:.3}); {off} pixels with other positions",
            flip.mean, flip.max
        );
        assert!(
            off <= (W * H) as usize / 200,
            "{name}: {off} pixels resolve to other positions with reversed-Z"
        );
        // `zfight`'s coplanar panels have no right answer: which one wins a
        // pixel is decided by rounding, which the depth convention changes,
        // so only its positions are compared.
        if *name != "zfight" {
            assert!(
                flip.mean < 0.02,
                "{name}: reversed-Z and standard depth differ (FLIP mean {})",
                flip.mean
            );
        }
        renderer.destroy(gl);
    }
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

#[test]
fn the_renderer_leaves_the_hosts_depth_state_as_it_found_it() {
    let Some(ctx) = common::egl_context() else {
        return;
    };
    let gl = ctx.gl();
    let extra = ExtraFns::load(gl, |n| ctx.get_proc_address(n));
    if !extra.has_clip_control() {
        return;
    }
    let state = || unsafe {
        (
            gl.get_parameter_i32(glow::CLIP_ORIGIN) as u32,
            gl.get_parameter_i32(glow::CLIP_DEPTH_MODE) as u32,
            gl.get_parameter_i32(glow::DEPTH_FUNC) as u32,
            gl.get_parameter_f32(glow::DEPTH_CLEAR_VALUE),
        )
    };
    let scene = Scene::load("builtin:box").expect("scene");
    let mut renderer = renderer(&ctx, &scene, &with_depth(DepthMode::Standard, median()));
    let standard = render_checked(gl, &mut renderer, "box standard");

    // A host with its own depth state.
    unsafe {
        gl.depth_func(glow::LEQUAL);
        gl.clear_depth_f64(0.75);
    }
    let host = (
        glow::LOWER_LEFT,
        glow::NEGATIVE_ONE_TO_ONE,
        glow::LEQUAL,
        0.75,
    );
    assert_eq!(state(), host);
    renderer
        .set_options(gl, &with_depth(DepthMode::Reversed, median()))
        .expect("reversed-Z");
    let reversed = render_checked(gl, &mut renderer, "box reversed");
    assert_eq!(state(), host, "after a reversed-Z frame");

    // A host that uses GL_ZERO_TO_ONE itself: a standard frame still renders
    // as before, and the host gets its clip control back.
    assert!(extra.set_clip_depth_zero_to_one(true));
    let host = (glow::LOWER_LEFT, glow::ZERO_TO_ONE, glow::LEQUAL, 0.75);
    renderer
        .set_options(gl, &with_depth(DepthMode::Standard, median()))
        .expect("standard");
    let again = render_checked(gl, &mut renderer, "box standard, host in zero-to-one");
    assert_eq!(state(), host, "after a standard frame");
    assert_eq!(again, standard);
    let flip = deferred_msaa_lab::compare::flip(&standard, &reversed).expect("same size");
    assert!(flip.mean < 0.02, "FLIP mean {}", flip.mean);
    extra.set_clip_depth_zero_to_one(false);
    renderer.destroy(gl);
    assert_eq!(live_objects().total(), 0, "{:?}", live_objects());
}

// ---------------------------------------------------------------------------
// Per-sample lighting (`per-sample`) and per-sample lighting of complex
// pixels only (`complex`).
